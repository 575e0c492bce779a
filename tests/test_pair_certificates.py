"""solvers/pair_certificates.py: a pair's distance at one configuration proves it free at others, and the planner's
segment checks with these certificates give every state coal's own verdict (random IMPROV arms in the PTP_3 cell,
with its mesh, and among random boxes; seeded)."""
from types import SimpleNamespace

import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV, TASKS, boxes_around

from robodesign.design.problem import Problem
from robodesign.formats.assembly import Assembly
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.model.cell import build_robot
from robodesign.model.robot import Robot
from robodesign.model.sweep import pair_arms
from robodesign.solvers import planning
from robodesign.solvers.pair_certificates import ANCHORS, SLACK, PairCertificates
from robodesign.solvers.schedule import static_cell


@pytest.fixture(scope="module")
def robots():
    """Eight random IMPROV arms (the PTP_3 search space's orders, seed 11) at the task's nominal base, and the known
    good arm."""
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    space = Problem.build(TASKS / "simple" / "PTP_3.json", IMPROV, "cyc").space
    rng = np.random.default_rng(11)
    orders = [space.random_order(rng) for _ in range(8)] + [("1", "21", "4", "22", "5", "23", "12")]
    cell = [build_robot(static_cell(task), ms, Assembly.from_order(ms, o), task.nominal_base_pose) for o in orders]
    boxed = []
    for i, o in enumerate(orders[:5]):
        r = Robot.from_order(ms, list(o))
        r.set_obstacles(boxes_around(r, 20 + i, n=8))
        boxed.append(r)
    return cell + boxed


def coal_verdict(robot, q) -> bool:
    """Every pair asked of coal (pinocchio's own query, no bounds in front): the reference verdict."""
    return bool(pin.computeCollisions(robot.model, robot.data, robot.geom_model, robot.geom_data, q, True))


def distances(robot, q) -> np.ndarray:
    """coal's distance of every collision pair at ``q``."""
    gm, gd = robot.geom_model, robot.geom_data
    pin.updateGeometryPlacements(robot.model, robot.data, gm, gd, q)
    return np.array([pin.computeDistance(gm, gd, k).min_distance for k in range(len(gm.collisionPairs))])


def test_a_distance_bounds_the_distance_elsewhere(robots):
    """d(q) ≥ d(a) − |q − a|·W for every pair (self and with a box), at random pairs of configurations near and far apart, up to
    coal's own distance error (GJK's tolerance, ~1e-6 m; a cylinder turning about its axis: W 0, distances that
    differ by some 1e-7 m), far below the certificates' SLACK."""
    rng = np.random.default_rng(3)
    checked, worst = 0, 0.0
    for robot in robots:
        W = pair_arms(robot)
        for _ in range(12):
            a = robot.random_configuration(rng)
            q = a + rng.normal(0.0, rng.choice([0.01, 0.1, 1.0]), robot.dof)
            da, dq = distances(robot, a), distances(robot, q)
            bound = da - np.abs(q - a) @ W
            ok = np.isfinite(da) & (da > 0)
            worst = max(worst, float(np.max(bound[ok] - dq[ok], initial=0.0)))
            checked += int(ok.sum())
    assert checked > 5000
    assert worst < SLACK / 10


def test_segment_verdicts_are_coals(robots):
    """first_invalid with the certificates: the first invalid state and every state's verdict those of coal asked
    about every pair, on random segments (many passing through self-collisions), with far fewer collision tests."""
    rng = np.random.default_rng(7)
    used = asked = boxes = 0
    for robot in robots:
        valid = planning._Memoized(planning._config_validator(robot), robot)
        for _ in range(12):
            a = robot.random_configuration(rng)
            b = a + rng.normal(0.0, 0.6, robot.dof)
            n = int(np.ceil(np.max(np.abs(b - a)) / 0.01))
            Q = a + (b - a) * (np.arange(1, n + 1) / n)[:, None]
            Q = Q[rng.permutation(n)]   # (any order: the bisection order is one)
            ref = [bool(np.all(q >= robot.q_lower - 1e-9) and np.all(q <= robot.q_upper + 1e-9))
                   and not coal_verdict(robot, q) for q in Q]
            first = valid.first_invalid(Q)
            assert first == (ref.index(False) if False in ref else -1)
            for q, v in zip(Q[:first if first >= 0 else n], ref):
                assert valid.memo[q.tobytes()] == v
            asked += n
        certs = valid.certificates
        assert certs is not None
        used += certs.count
        boxes += int(np.isfinite(certs.free[:, robot.n_self_collision_pairs:]).sum())
    assert 0 < used < asked / 4
    assert boxes > 0   # pairs with a box certified too


def test_certified_states_leave_the_slack(robots):
    """A state the certificates clear for a pair has that pair farther apart than its margin + SLACK."""
    rng = np.random.default_rng(9)
    robot = robots[8]
    valid = planning._Memoized(planning._config_validator(robot), robot)
    valid.culler()
    certs = valid.certificates
    a = robot.random_configuration(rng)
    Q = a + rng.normal(0.0, 0.02, (200, robot.dof))
    S = np.zeros((len(Q), len(robot.geom_model.collisionPairs)), dtype=bool)
    S[:, certs.certified] = True
    P = certs.pending(Q, S)
    for j in range(len(Q)):
        left = set(certs.ask(P, Q, j))
        d = distances(robot, Q[j])
        cleared = [k for k in np.flatnonzero(certs.certified) if k not in left]
        assert np.all(d[cleared] - certs.margin[cleared] > SLACK)
    assert certs.count < len(Q) / 4


def test_which_pairs_get_certificates(robots):
    """An IMPROV arm (convex meshes): every pair but those with the CNC machine's triangle mesh; a built-in arm
    (cylinders and spheres only): none."""
    from robodesign.solvers.pair_certificates import certified_pairs
    for robot in (robots[8], robots[9]):
        gm = robot.geom_model
        kinds = [type(o.geometry).__name__ for o in gm.geometryObjects]
        mesh = np.array(["BVHModelOBBRSS" in (kinds[cp.first], kinds[cp.second]) for cp in gm.collisionPairs])
        assert np.array_equal(certified_pairs(gm, robot.n_collision_geometries), ~mesh)
    cell, boxed = robots[8], robots[9]
    assert certified_pairs(cell.geom_model, cell.n_collision_geometries)[:cell.n_self_collision_pairs].all()
    assert certified_pairs(boxed.geom_model, boxed.n_collision_geometries)[boxed.n_self_collision_pairs:].all()
    space = Problem.build(TASKS / "simple" / "PTP_3.json", "robodesign_arm", "cyc").space
    rng = np.random.default_rng(4)
    for _ in range(3):
        builtin = Robot.from_order(load_module_set("robodesign_arm"), list(space.random_order(rng)))
        assert not certified_pairs(builtin.geom_model, builtin.n_collision_geometries).any()


def test_the_certified_pairs_kept_per_geometry_model_follow_its_changes():
    """The set-up's certified pairs, remembered per geometry model, are certified_pairs of the model as it is: an
    IMPROV arm without obstacles, then with boxes (added to the same model), then with the PTP_3 cell's triangle
    mesh among them (a new model), then boxes again, each asked twice; against the pairs' kinds read afresh."""
    from robodesign.solvers.pair_certificates import _certified_of
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    robot = Robot.from_order(ms, ["1", "21", "4", "22", "5", "23", "12"])
    mesh_cell = build_robot(static_cell(task), ms, Assembly.from_order(ms, ["1", "21", "4", "22", "5", "23", "12"]),
                            task.nominal_base_pose).obstacles
    models, seen = set(), 0
    for obstacles in ([], boxes_around(robot, 3, n=4), list(mesh_cell) + boxes_around(robot, 4, n=2),
                      boxes_around(robot, 5, n=3)):
        if obstacles:
            robot.set_obstacles(obstacles)
        gm = robot.geom_model
        models.add(id(gm))
        kinds = [type(o.geometry).__name__ for o in gm.geometryObjects]
        want = np.array([not ("BVH" in kinds[cp.first][:3] or "BVH" in kinds[cp.second][:3])
                         for cp in gm.collisionPairs])
        for _ in range(2):
            got = _certified_of(gm, robot.n_collision_geometries)
            assert np.array_equal(got, want)
        seen += int((~want).sum())
    assert len(models) >= 2 and seen > 0   # a model changed in place and models made anew; mesh pairs left out


def test_pending_bounds_only_the_rows_it_changes():
    """``PairCertificates.pending`` (only the rows with a certified pair in ``S`` bounded) equals the formula over
    every row: random certificates (1–32 kept, of 40 made at most; clearances with NaN where not computed, some just
    above and below the slack) of 1–9 joints and 1–60 pairs, random blocks of 0–150 rows and survivor masks of
    several densities; the bounds of a row subset are the full bounds' rows bit for bit; seeded."""
    rng = np.random.default_rng(2025)
    cleared = kept = 0
    for _ in range(400):
        dof, k, n = int(rng.integers(1, 10)), int(rng.integers(1, 61)), int(rng.integers(0, 151))
        certs = PairCertificates(SimpleNamespace(dof=dof), rng.random(k) < 0.7, rng.random((dof, k)) * 0.5,
                                 rng.random(k) * 0.01)
        certs.count = int(rng.integers(0, 41))
        certs.anchors[:] = rng.uniform(-3, 3, certs.anchors.shape)
        certs.free[:] = np.where(rng.random(certs.free.shape) < 0.3, np.nan,
                                 rng.choice([0.05, 1.0, SLACK], size=certs.free.shape) * rng.random(certs.free.shape))
        R = certs.anchors[rng.integers(0, len(certs.anchors), n)] + rng.normal(size=(n, dof)) * rng.choice([1e-3, 0.1, 1])
        S = rng.random((n, k)) < rng.choice([0.01, 0.1, 0.5])
        S0 = S.copy()
        m = min(certs.count, ANCHORS)
        want = S.copy()
        cols = np.flatnonzero(S.any(axis=0) & certs.certified)
        if m and len(cols):
            bound = np.abs(R[:, None, :] - certs.anchors[None, :m]) @ certs.W[:, cols]
            want[:, cols] &= ~(certs.free[:m, cols] - bound > SLACK).any(axis=1)
            rows = np.flatnonzero(S[:, cols].any(axis=1))
            sub = np.abs(R[rows, None, :] - certs.anchors[None, :m]) @ certs.W[:, cols]
            assert sub.tobytes() == bound[rows].tobytes()
        got = certs.pending(R, S)
        assert got.dtype == bool and np.array_equal(got, want)
        assert np.array_equal(S, S0)   # (S itself not changed)
        cleared, kept = cleared + int((S & ~got).sum()), kept + int(got.sum())
    assert cleared > 1000 and kept > 1000   # (certificates clearing some pairs and leaving others)
