"""The certified sweep (robodesign.model.sweep): its motion bounds hold on real module sets, bodies of revolution
drop exactly the joints that cannot change a distance, and the tighter bounds keep the verdicts while
cutting the distance queries of a real near-contact motion."""
import numpy as np
import pinocchio as pin
import pytest

from robodesign.design.problem import Problem
from robodesign.model.robot import Robot
from robodesign.model.sweep import SweepChecker, own_axis_symmetric

from conftest import COBRA as SHARED, ROOT

IMPROV = SHARED / "modules" / "IMPROV"
PRIMITIVES = SHARED / "modules" / "geometric_primitive_modules"
BUILTIN = ROOT / "assets" / "modules" / "robodesign_arm"
PTP3 = SHARED / "tasks" / "simple" / "PTP_3.json"
ORDER = ("1", "22", "5", "23", "5", "29", "14", "16")  # IMPROV: three 2-DoF modules (housing, sphere, housing)


def pair_distances(robot: Robot, pairs, q) -> np.ndarray:
    """Distances of collision pairs ``pairs`` (indices into the geometry model) at q, from a fresh GeometryData."""
    gd = pin.GeometryData(robot.geom_model)
    pin.updateGeometryPlacements(robot.model, robot.model.createData(), robot.geom_model, gd, q)
    return np.array([pin.computeDistance(robot.geom_model, gd, k).min_distance for k in pairs])


def random_q(robot, rng, n=1):
    lo = np.maximum(robot.model.lowerPositionLimit, -np.pi)
    hi = np.minimum(robot.model.upperPositionLimit, np.pi)
    return lo + (hi - lo) * rng.random((n, robot.dof))


def in_cell(p, order) -> Robot:
    from robodesign.model.cell import build_robot
    from robodesign.formats.assembly import Assembly
    return build_robot(p.task, p.module_set, Assembly.from_order(p.module_set, order), np.eye(4))


def improv_robot():
    p = Problem.build(str(PTP3), str(IMPROV), "cyc")
    return in_cell(p, ORDER), p


def test_bodies_of_revolution_found_on_improv():
    """By hand from IMPROV's geometry: each 2-DoF module is a housing cylinder (body_1) coaxial with joint 1, a
    sphere (body_2) centred on joint 2's axis and an output cylinder (body_3) coaxial with joint 2."""
    r, _ = improv_robot()
    names = [o.name for o in r.geom_model.geometryObjects]
    own = {n for n, s in zip(names, own_axis_symmetric(r)) if s}
    assert own == {"22.22_body_3.c0", "23.23_body_3.c0", "29.29_body_3.c0"}
    chk, plain = SweepChecker(r), SweepChecker(r, symmetry=False)
    assert np.all(chk.W <= plain.W + 1e-15)
    dropped = {(a, b): set(np.nonzero(w1 != w0)[0]) for (a, b), w1, w0 in zip(chk.pair_names, chk.W.T, plain.W.T)
               if np.any(w1 != w0)}
    # joint indices: 22_1 = 0, 22_2 = 1, 23_1 = 2, 23_2 = 3, 29_1 = 4, 29_2 = 5
    assert dropped[("23.23_body_1.c0", "5-1.5.c0")] == {2}  # housing coaxial with 23_1 (rule 2 of the docstring)
    assert dropped[("22.22_body_2.c0", "23.23_body_2.c0")] == {1}  # sphere on 22_2's axis
    assert dropped[("23.23_body_1.c0", "23.23_body_3.c0")] == {2, 3}  # both rules
    assert dropped[("22.22_body_3.c0", "29.29_body_3.c0")] == {5}  # output cylinder turning on its own axis
    assert ("5.5.c0", "5-1.5.c0") not in dropped  # convex links: nothing to drop


def test_dropped_joints_do_not_change_distances():
    """Independent of the bounds: turning only a dropped joint leaves the pair's distance unchanged (up to coal's
    GJK tolerance of 1e-6 m on curved shapes), while the other joints of the pair do change it."""
    r, _ = improv_robot()
    chk, plain = SweepChecker(r), SweepChecker(r, symmetry=False)
    rng = np.random.default_rng(0)
    gm = r.geom_model
    checked = 0
    for c, k in enumerate(chk.pairs):
        for j in np.nonzero((chk.W[:, c] == 0) & (plain.W[:, c] > 0))[0]:
            for q in random_q(r, rng, 3):
                Q = np.tile(q, (9, 1))
                Q[:, j] = np.linspace(-np.pi, np.pi, 9)
                d = np.array([pair_distances(r, [k], qq)[0] for qq in Q])
                assert np.ptp(d) < 2e-6, (chk.pair_names[c], j, d)
                checked += 1
    assert checked > 100
    # a joint that is not dropped moves the pair (the test can fail)
    c = chk.pair_names.index(("23.23_body_1.c0", "5-1.5.c0"))
    q = np.zeros(r.dof)
    Q = np.tile(q, (9, 1))
    Q[:, 3] = np.linspace(-1.5, 1.5, 9)
    assert np.ptp([pair_distances(r, [chk.pairs[c]], qq)[0] for qq in Q]) > 1e-3


@pytest.mark.parametrize("module_set,seed", [(IMPROV, 1), (PRIMITIVES, 2), (BUILTIN, 3)])
def test_motion_bound_holds_densely(module_set, seed):
    """The property certification rests on, for every pair (self and obstacle) of random real robots: along a
    linear joint motion qa→qb, |d(s) − d(s')| ≤ (W·|qb − qa|)·|s − s'| (dense samples, exact distances; the
    slack 1e-3 m per unit s is 2e-6 m of GJK tolerance between two samples 1/200 apart, less than one bound of
    a typical pair)."""
    p = Problem.build(str(PTP3), str(module_set), "cyc")
    space = p.space
    rng = np.random.default_rng(seed)
    s = np.linspace(0.0, 1.0, 201)
    checked = 0
    for _ in range(4):
        order = space.random_order(rng)
        r = in_cell(p, order)
        chk = SweepChecker(r)
        for qa, qb in zip(random_q(r, rng, 3), random_q(r, rng, 3)):
            qb = qa + 0.5 * (qb - qa)
            bound = np.abs(qb - qa) @ chk.W
            D = np.array([pair_distances(r, chk.pairs, qa + t * (qb - qa)) for t in s])  # (201, P)
            # between separated samples only: in contact coal gives penetration depths, which jump inside meshes
            apart = (D[:-1] > 0) & (D[1:] > 0)
            slope = np.max(np.where(apart, np.abs(np.diff(D, axis=0)), 0.0), axis=0) / (s[1] - s[0])
            assert np.all(slope <= bound + 1e-3), [(chk.pair_names[c], slope[c], bound[c])
                                                   for c in np.nonzero(slope > bound + 1e-3)[0]]
            checked += int(np.sum(apart.all(axis=0)))
    assert checked > 300


def test_near_contact_motion_same_verdict_far_fewer_queries():
    """A real PTP_3 motion of an IMPROV arm whose link slides past a joint housing at a few µm (found by random
    search): the tight bounds and the plain ones agree that it is collision-free, with ≥ 20× fewer queries. (The
    plain bounds may need more than the default 2,000 sub-steps in one step to certify a µm gap; at the limit a
    checker reports the pair as in contact, so the plain one gets enough to be exact to its tolerance.)"""
    from dataclasses import replace
    from robodesign.design.evaluator import candidate_seed, evaluation_settings
    from robodesign.design.search_space import Candidate
    from robodesign.design.solve import solve
    robot, p = improv_robot()
    # as `robodesign optimize --optimizer random --seed 3` evaluates it (its 6th candidate)
    settings = replace(evaluation_settings(), seed=candidate_seed(3, Candidate(ORDER, ()).key()))
    res = solve(p.task, p.module_set, list(ORDER), np.eye(4), cost="cyc", settings=settings)
    assert res.feasible
    sol = res.solution
    Q = np.asarray(sol.trajectory.q)
    tight, plain = SweepChecker(robot), SweepChecker(robot, symmetry=False, max_substeps=10 ** 6)
    assert tight.check(Q, first_only=False) == [] == plain.check(Q, first_only=False)
    c = tight.pair_names.index(("23.23_body_1.c0", "5-1.5.c0"))
    d = np.array([tight.distances(q, [c])[0] for q in Q])
    assert d.min() < 2e-5  # the near contact is real
    assert plain.queries > 20 * tight.queries


def test_robot_pair_motion_bound_holds_densely():
    """The same property for two robots moving at once (robodesign.model.pair_sweep, collaborative cells): the lever
    arms with bodies of revolution bound every cross pair's distance change along a stacked linear motion."""
    from robodesign.model.pair_sweep import RobotPairSweep
    p = Problem.build(str(PTP3), str(IMPROV), "cyc")
    from robodesign.model.sweep import lever_arms
    a, _ = improv_robot()
    shift = np.eye(4)
    shift[:3, 3] = [0.45, 0.1, 0.0]
    b = Robot.from_order(p.module_set, ("1", "23", "5", "29", "14", "16"), base_pose=shift)
    sweep = RobotPairSweep(a, b)
    assert np.sum(lever_arms(a) < lever_arms(a, symmetry=False)) == 3  # the three output cylinders
    rng = np.random.default_rng(4)
    s = np.linspace(0.0, 1.0, 201)
    checked = 0
    for _ in range(3):
        qa = np.concatenate([random_q(a, rng)[0], random_q(b, rng)[0]])
        qb = np.concatenate([random_q(a, rng)[0], random_q(b, rng)[0]])
        qb = qa + 0.5 * (qb - qa)
        bound = np.abs(qb - qa) @ sweep.W
        D = np.array([sweep.distances(qa + t * (qb - qa), range(len(sweep.pairs))) for t in s])
        apart = (D[:-1] > 0) & (D[1:] > 0)
        slope = np.max(np.where(apart, np.abs(np.diff(D, axis=0)), 0.0), axis=0) / (s[1] - s[0])
        assert np.all(slope <= bound + 1e-3)
        checked += int(np.sum(apart.all(axis=0)))
    assert checked > 300


def test_symmetry_needs_the_centre_on_the_axis_and_the_axis_aligned():
    """symmetric_about by hand: a sphere anywhere on the line, a cylinder/capsule/cone only when coaxial; a box
    or a convex mesh never; 1e-9 m or rad of misalignment is the limit."""
    import coal
    from robodesign.model.revolution import symmetric_about

    def obj(shape, xyz=(0, 0, 0), rot=np.eye(3)):
        return pin.GeometryObject("g", 0, pin.SE3(rot, np.array(xyz, float)), shape)
    z, p0 = np.array([0.0, 0.0, 1.0]), np.zeros(3)
    tilt = pin.exp3(np.array([1e-6, 0.0, 0.0]))
    assert symmetric_about(obj(coal.Sphere(0.1), (0, 0, 0.3)), p0, z)
    assert not symmetric_about(obj(coal.Sphere(0.1), (0.001, 0, 0.3)), p0, z)
    for shape in (coal.Cylinder(0.05, 0.2), coal.Capsule(0.05, 0.2), coal.Cone(0.05, 0.2)):
        assert symmetric_about(obj(shape, (0, 0, -0.1)), p0, z)
        assert symmetric_about(obj(shape, (0, 0, -0.1), pin.exp3(np.array([np.pi, 0, 0]))), p0, z)  # flipped
        assert not symmetric_about(obj(shape, (0, 0, -0.1), tilt), p0, z)
        assert not symmetric_about(obj(shape, (0, 2e-9, -0.1)), p0, z)
        assert symmetric_about(obj(shape, (0, 5e-10, -0.1)), p0, z)
        x = np.array([1.0, 0, 0])
        assert not symmetric_about(obj(shape), p0, x)  # its axis is z
    assert not symmetric_about(obj(coal.Box(0.1, 0.1, 0.1)), p0, z)
    assert symmetric_about(obj(coal.Sphere(0.1), (0.2, 0.5, 0.0)), np.array([0.2, 0.5, 7.0]), z)  # line off origin


def _pair_arms_per_pair(robot: Robot, pairs, symmetry: bool):
    """W and owner of SweepChecker, pair by pair from the kinematic tree (the definition the vectorised
    model.sweep._pair_arms computes)."""
    from robodesign.model.sweep import _Tree
    tree = _Tree(robot)
    R, anc = tree.lever_arms(symmetry, robot.dof), tree.ancestors()
    cox = tree.coaxial_child_joints() if symmetry else [set()] * robot.n_collision_geometries
    cps = [(cp.first, cp.second) for cp in robot.geom_model.collisionPairs]
    W, owner = np.zeros((robot.dof, len(pairs))), np.full((robot.dof, len(pairs)), -1)
    for c, k in enumerate(pairs):
        a, b = cps[k]
        if b >= robot.n_collision_geometries:
            W[:, c], owner[:, c] = R[:, a], a
            continue
        for j in anc[a] - anc[b]:
            W[tree.idx_v[j], c], owner[tree.idx_v[j], c] = R[tree.idx_v[j], a], a
        for j in anc[b] - anc[a]:
            W[tree.idx_v[j], c], owner[tree.idx_v[j], c] = R[tree.idx_v[j], b], b
        for j in (cox[a] & (anc[b] - anc[a])) | (cox[b] & (anc[a] - anc[b])):
            W[tree.idx_v[j], c] = 0.0
    return W, owner


@pytest.mark.parametrize("module_set", [IMPROV, BUILTIN, PRIMITIVES])
def test_pair_arms_are_the_per_pair_definition(module_set):
    """The pairs' lever arms and owners (self pairs: the joints only one side hangs from, bodies of revolution
    dropped; robot–obstacle pairs: the robot geometry's) on random robots of real module sets, with and without
    symmetry and for a subset of the obstacles."""
    p = Problem.build(str(PTP3), str(module_set), "cyc")
    rng = np.random.default_rng(4)
    dropped = 0
    for _ in range(3):
        r = in_cell(p, p.space.random_order(rng))
        for sym in (True, False):
            for obstacles in (None, [0]):
                chk = SweepChecker(r, symmetry=sym, obstacles=obstacles, posed_arms=True)
                W, owner = _pair_arms_per_pair(r, chk.pairs, sym)
                assert np.array_equal(chk.W, W) and np.array_equal(chk._owner, owner)
                assert chk.is_env.sum() == len(chk.pairs) - r.n_self_collision_pairs > 0
                assert np.all(chk.margins[chk.is_env] == r.safety_margin) and np.all(chk.margins[~chk.is_env] == 0)
                dropped += int(np.sum((W == 0) & (owner >= 0)))
    assert dropped > 0  # bodies of revolution did drop joints


def test_setup_shared_by_robots_built_alike():
    """A second robot built alike (same assembly, base pose and cell) takes the first one's checker set-up: the
    same bounds and names, its own robot and scratch space, the same events and queries; a robot at another base
    pose gets its own set-up (its bounds from the first's, its posed arms at its base pose: tests/test_sweep_rebase.py)."""
    from robodesign.model import sweep
    from robodesign.model.cell import build_robot
    from robodesign.formats.assembly import Assembly
    p = Problem.build(str(PTP3), str(IMPROV), "cyc")
    build = lambda T: build_robot(p.task, p.module_set, Assembly.from_order(p.module_set, ORDER), T)  # noqa: E731
    sweep._SETUPS.clear()
    a, b = build(np.eye(4)), build(np.eye(4))
    ca, cb = SweepChecker(a, posed_arms=True), SweepChecker(b, posed_arms=True)
    assert len(sweep._SETUPS) == 1 and cb.W is ca.W and cb.pair_names == ca.pair_names
    assert cb.robot is b and cb._posed.robot is b and ca._posed.robot is a and cb._req is not ca._req
    sweep._SETUPS.clear()
    fresh = SweepChecker(b, posed_arms=True)
    for attr in ("W", "_owner", "margins", "is_env"):
        assert np.array_equal(getattr(fresh, attr), getattr(cb, attr))
    assert (fresh.pairs, fresh._mov, fresh._ref) == (cb.pairs, cb._mov, cb._ref)
    rng = np.random.default_rng(12)
    Q = random_q(b, rng, 1)[0] + np.outer(np.linspace(0, 1, 40), 2.0 * rng.normal(size=b.dof))
    e1, e2 = cb.check(Q, first_only=False), fresh.check(Q, first_only=False)
    assert e1 == e2 and e1 and cb.queries == fresh.queries
    T = np.eye(4)
    T[:3, 3] = (0.1, -0.2, 0.0)
    moved = SweepChecker(build(T), posed_arms=True)   # its own set-up, the bounds taken from b's (sweep_rebase)
    assert len(sweep._SETUPS) == 2 and moved.W is fresh.W and moved._posed.t_g is not fresh._posed.t_g
