"""model/pair_clearance.py (issue 25): self pairs proven never to collide. Against pinocchio and coal on random
IMPROV and primitive-module arms: the chain poses are pinocchio's relative joint poses; the arms bound how fast
coal's distance changes; a proven pair is farther apart than its limit at thousands of random configurations, inside
the joint limits and far outside; and the culler, with every provable pair switched off, gives coal's verdicts."""
import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV, PRIMITIVES

from robodesign.formats.assembly import random_serial_order
from robodesign.formats.module_io import load_module_set
from robodesign.model import pair_clearance
from robodesign.model.collision_cull import SLACK, CollisionCuller
from robodesign.model.robot import Robot


def random_arms(n, seed):
    """``n`` random serial arms of each of the IMPROV and the primitive module sets (seeded)."""
    rng = np.random.default_rng(seed)
    out = []
    for path, dofs in ((IMPROV, (6, 7)), (PRIMITIVES, (3, 8))):
        ms = load_module_set(path)
        for _ in range(n):
            order = random_serial_order(ms, rng, dof=int(rng.integers(*dofs)))
            out.append(Robot.from_order(ms, order))
    return out


def self_pairs(robot):
    """(pair index, first object, second object, chain or None) of every self pair of ``robot``."""
    gm, objs = robot.geom_model, robot.geom_model.geometryObjects
    out = []
    for k, cp in enumerate(gm.collisionPairs):
        a, b = objs[cp.first], objs[cp.second]
        if cp.second < robot.n_collision_geometries:
            links = pair_clearance.chain(robot.model, a.parentJoint, b.parentJoint)
            if links is None:
                a, b = b, a
                links = pair_clearance.chain(robot.model, a.parentJoint, b.parentJoint)
            out.append((k, a, b, links))
    return out


def ends(obj):
    """(shape, 4×4 placement, parent joint) of a geometry object: one end of a pair for ``never_collides``."""
    return obj.geometry, np.array(obj.placement.homogeneous), int(obj.parentJoint)


def chain_joints(model, i, j):
    """The joints from i (exclusive) to j (inclusive), root side first."""
    path = []
    while j != i:
        path.append(j)
        j = int(model.parents[j])
    return path[::-1]


def wide_configuration(robot, rng):
    """A configuration with every angle uniform in [−2π, 2π] (outside the joint limits too)."""
    return rng.uniform(-2 * np.pi, 2 * np.pi, robot.dof)


def test_chain_poses_are_pinocchios_relative_joint_poses():
    """``chain_poses`` of the chain's angles equals oMi[i]⁻¹·oMi[j] from pinocchio's forward kinematics."""
    checked = 0
    rng = np.random.default_rng(1)
    for robot in random_arms(3, 21):
        m, d = robot.model, robot.data
        for _ in range(20):
            q = wide_configuration(robot, rng)
            pin.forwardKinematics(m, d, q)
            for j in range(1, m.njoints):
                for i in range(j):
                    links = pair_clearance.chain(m, i, j)
                    if links is None:
                        continue
                    angles = np.array([q[m.idx_qs[n]] for n in chain_joints(m, i, j)])
                    T = pair_clearance.chain_poses(links, angles[None])[0]
                    ref = (d.oMi[i].inverse() * d.oMi[j]).homogeneous
                    assert np.allclose(T, ref, rtol=0, atol=1e-12)
                    checked += 1
    assert checked > 1000


def test_arms_bound_how_fast_the_distance_changes():
    """Turning one chain joint by δ changes coal's distance of the pair by at most arm·|δ| (+ coal's tolerance, far below SLACK)."""
    rng = np.random.default_rng(2)
    checked = tight = 0
    for robot in random_arms(3, 22):
        gm, gd, m = robot.geom_model, robot.geom_data, robot.model
        for k, a, b, links in self_pairs(robot):
            if links is None:
                continue
            arms = pair_clearance.chain_arms(links, (a.geometry, np.array(a.placement.homogeneous)),
                                             (b.geometry, np.array(b.placement.homogeneous)))
            joints = chain_joints(m, a.parentJoint, b.parentJoint)
            for _ in range(6):
                q = wide_configuration(robot, rng)
                n = int(rng.integers(len(joints)))
                delta = float(rng.uniform(-0.6, 0.6))
                q2 = q.copy()
                q2[m.idx_qs[joints[n]]] += delta
                ds = []
                for x in (q, q2):
                    pin.updateGeometryPlacements(m, robot.data, gm, gd, x)
                    ds.append(pin.computeDistance(gm, gd, k).min_distance)
                if min(ds) > 0:
                    assert abs(ds[1] - ds[0]) <= arms[n] * abs(delta) + 1e-5   # (coal: ~1e-6)
                    checked += 1
                    tight += abs(ds[1] - ds[0]) > 0.5 * arms[n] * abs(delta)
    assert checked > 500 and tight > 0


@pytest.mark.parametrize("margin", [0.0, 0.01])
def test_proven_pairs_are_apart_at_every_configuration(margin):
    """Every self pair proven at ``margin`` is farther apart than margin + SLACK by coal's distance, and coal's
    collision test at that margin finds it free, at random configurations inside and far outside the limits."""
    rng = np.random.default_rng(3)
    proven = tried = 0
    for robot in random_arms(4, 23):
        gm, gd, m = robot.geom_model, robot.geom_data, robot.model
        mine = [k for k, a, b, links in self_pairs(robot)
                if pair_clearance.never_collides(m, ends(a), ends(b), margin + SLACK)]
        tried += len(gm.collisionPairs)
        proven += len(mine)
        for k in mine:
            gd.collisionRequests[k].security_margin = margin
        Q = [wide_configuration(robot, rng) for _ in range(150)] + [robot.random_configuration(rng) for _ in range(150)]
        for q in Q:
            pin.updateGeometryPlacements(m, robot.data, gm, gd, q)
            for k in mine:
                assert pin.computeDistance(gm, gd, k).min_distance > margin + SLACK
                assert not pin.computeCollision(gm, gd, k)
    assert proven > 50 and proven < tried


def test_the_verdict_is_kept_by_what_it_depends_on():
    """A second robot of the same modules gets the kept verdicts (no new entry); another limit is a new entry with
    a verdict of its own."""
    ms = load_module_set(IMPROV)
    order = ["1", "21", "4", "22", "5", "23", "12"]
    robots = [Robot.from_order(ms, order) for _ in range(2)]
    def verdicts(robot, limit):
        return [pair_clearance.never_collides(robot.model, ends(a), ends(b), limit) for _, a, b, _ in self_pairs(robot)]
    first = verdicts(robots[0], SLACK)
    size = len(pair_clearance._KNOWN)
    again = verdicts(robots[1], SLACK)
    assert again == first and len(pair_clearance._KNOWN) == size and sum(first) > 20
    wide = verdicts(robots[1], 0.05)
    assert len(pair_clearance._KNOWN) > size and sum(wide) < sum(first)
    assert not any(w and not f for w, f in zip(wide, first))


def test_culler_with_proven_pairs_gives_coals_verdicts(geometry_paths):
    """The culler with every provable self pair switched off (each pair asked :data:`PROVE_AFTER` times) gives the
    verdict of pinocchio's computeCollisions over every pair, at random configurations of random arms."""
    rng = np.random.default_rng(4)
    hits = total = proven = 0
    for robot in random_arms(4, 24):
        c = CollisionCuller(robot)
        for k, *_ in self_pairs(robot):
            c._prove(k)
        proven += c.proven
        assert c.proven == int((~c.active).sum())
        Q = np.array([robot.random_configuration(rng) for _ in range(60)] + [wide_configuration(robot, rng)
                                                                            for _ in range(30)])
        S = c.survivors(Q)
        for i, q in enumerate(Q):
            ref = bool(pin.computeCollisions(robot.model, robot.data, robot.geom_model, robot.geom_data, q, True))
            assert c.in_collision(q) == ref
            assert (bool(S[i].any()) and c.collides(q, np.flatnonzero(S[i]))) == ref
            hits += ref
            total += 1
    assert proven > 30 and 0.05 * total < hits < 0.95 * total


def test_proofs_are_tried_on_robots_with_a_convex_mesh_only():
    """IMPROV arms (convex meshes) get proofs; the built-in arms (primitives) and the primitive modules do not, and
    their culler switches nothing off however often a pair is asked."""
    good = Robot.from_order(load_module_set(IMPROV), ["1", "21", "4", "22", "5", "23", "12"])
    assert CollisionCuller(good).provable
    c = CollisionCuller(random_arms(1, 25)[1])
    assert not c.provable and not any(type(o.geometry).__name__.startswith("Convex")
                                      for o in c.robot.geom_model.geometryObjects)
    ks = [k for k, *_ in self_pairs(c.robot)]
    q = np.zeros(c.robot.dof)
    for _ in range(40):
        c.collides(q, ks)
    assert c.proven == 0 and c.active.all() and len(c.until_proof) == 0 and c.narrow == 40 * len(ks)


def test_a_pair_on_the_base_is_seen_alike_from_every_base_pose():
    """``in_a_frame`` of a pair on the base (a on the universe joint) at random base poses: within 10⁻⁹ per entry of
    the pose computed with the base left out (what the allowance covers); the kept verdicts serve every pose."""
    ms = load_module_set(IMPROV)
    robot = Robot.from_order(ms, ["1", "21", "4", "22", "5", "23", "12"])
    base = [(k, a, b, links) for k, a, b, links in self_pairs(robot) if a.parentJoint == 0 and links is not None]
    rest = {}
    for k, a, b, links in base:
        rest[k] = pair_clearance.in_a_frame(np.array(a.placement.homogeneous), links, np.array(b.placement.homogeneous))
    verdicts = {k: pair_clearance.never_collides(robot.model, ends(a), ends(b), SLACK) for k, a, b, _ in base}
    rng = np.random.default_rng(6)
    for _ in range(5):
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = pin.exp3(rng.normal(0.0, 2.0, 3)), rng.uniform(-2.0, 2.0, 3)
        robot.set_base_pose(T)
        objs = robot.geom_model.geometryObjects
        for k, a, b, _ in base:
            a, b = objs[robot.geom_model.getGeometryId(a.name)], objs[robot.geom_model.getGeometryId(b.name)]
            links = pair_clearance.chain(robot.model, a.parentJoint, b.parentJoint)
            seen, Pb = pair_clearance.in_a_frame(np.array(a.placement.homogeneous), links,
                                                 np.array(b.placement.homogeneous))
            assert np.allclose(Pb, rest[k][1], rtol=0, atol=1e-9)
            for (M, axis), (M0, axis0) in zip(seen, rest[k][0]):
                assert np.allclose(M, M0, rtol=0, atol=1e-9) and np.array_equal(axis, axis0)
            assert pair_clearance.never_collides(robot.model, ends(a), ends(b), SLACK) == verdicts[k]
    assert len(base) >= 5 and any(verdicts.values())


def test_a_builds_next_robots_start_with_its_proven_pairs_off(geometry_paths):
    """The pairs a culler of a robot with a convex mesh proved, both bodies beyond the first joint, are off in the next
    culler of the same build (module set, assembly, shapes) before its first query, at another base pose; each is
    what ``never_collides`` answers for the new robot itself, pairs on the base are left to be proven again, and the
    new culler's verdicts are pinocchio's computeCollisions over every pair at random configurations."""
    rng = np.random.default_rng(8)
    ms = load_module_set(IMPROV)
    carried = 0
    for _ in range(4):
        order = random_serial_order(ms, rng, dof=6)
        first = CollisionCuller(Robot.from_order(ms, order))
        for k, *_ in self_pairs(first.robot):
            first._prove(k)
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = pin.exp3(rng.normal(0.0, 1.0, 3)), rng.uniform(-1.0, 1.0, 3)
        robot = Robot.from_order(ms, order, base_pose=T)
        c = CollisionCuller(robot)
        objs = robot.geom_model.geometryObjects
        expected = {k for k, a, b, _ in self_pairs(robot) if not first.active[k] and a.parentJoint > 0
                    and b.parentJoint > 0} if first.provable else set()   # (primitives only: no proofs in use)
        assert set(np.flatnonzero(~c.active).tolist()) == expected and c.proven == len(expected)
        for k in expected:
            cp = robot.geom_model.collisionPairs[k]
            assert pair_clearance.never_collides(robot.model, ends(objs[cp.first]), ends(objs[cp.second]),
                                                 float(c.margin[k]) + SLACK)
        carried += len(expected)
        for q in [robot.random_configuration(rng) for _ in range(40)] + [wide_configuration(robot, rng)
                                                                      for _ in range(20)]:
            ref = bool(pin.computeCollisions(robot.model, robot.data, robot.geom_model, robot.geom_data, q, True))
            assert c.in_collision(q) == ref
    assert carried > 10


def test_the_framed_key_is_in_a_frames_bytes():
    """framed (kept per the raw placements' bytes) gives the bytes of in_a_frame's rounded Pb and links, on the self
    pairs of random IMPROV and primitive arms, asked once (new entries) and again (kept ones); and
    never_collides(prove=False) answers the kept verdicts as they were proven."""
    for robot in random_arms(6, 17):
        for _, a, b, links in self_pairs(robot):
            if links is None:
                continue
            Pa, Pb = np.array(a.placement.homogeneous), np.array(b.placement.homogeneous)
            f_links, f_Pb = pair_clearance.in_a_frame(Pa, links, Pb)
            want = (f_Pb.tobytes(), tuple((M.tobytes(), axis.tobytes()) for M, axis in f_links))
            assert pair_clearance.framed(Pa, links, Pb) == want
            assert pair_clearance.framed(Pa.copy(), [(M.copy(), x.copy()) for M, x in links], Pb.copy()) == want
    ms = load_module_set(IMPROV)
    robot = Robot.from_order(ms, ["1", "21", "4", "22", "5", "23", "12"])
    proven = [pair_clearance.never_collides(robot.model, ends(a), ends(b), SLACK) for _, a, b, _ in self_pairs(robot)]
    kept = [pair_clearance.never_collides(robot.model, ends(a), ends(b), SLACK, prove=False)
            for _, a, b, _ in self_pairs(robot)]
    assert kept == proven and sum(proven) > 20
