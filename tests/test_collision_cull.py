"""model/collision_cull.py on the real PTP_3 cell (IMPROV arm, CNC-machine mesh): the culled collision verdicts
equal ``robot.in_collision`` state by state, and the planner's segment checks find the same states."""
import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV, TASKS

from robodesign.design.solve import SolveSettings, solve
from robodesign.formats.assembly import Assembly
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.model.cell import build_robot
from robodesign.model.collision_cull import SLACK, CollisionCuller, culler_of
from robodesign.solvers import planning
from robodesign.solvers.planning import check_path
from robodesign.solvers.schedule import static_cell

GOOD = ("1", "21", "4", "22", "5", "23", "12")


@pytest.fixture(scope="module")
def cell():
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    robot = build_robot(static_cell(task), ms, Assembly.from_order(ms, GOOD), task.nominal_base_pose)
    res = solve(task, ms, GOOD, settings=SolveSettings(seed=0))
    assert res.feasible
    stops = [q for q in res.solution.trajectory.q[::25]]   # states along the solved motion (near the machine)
    return robot, np.array(stops)


def coal_verdict(robot, q) -> bool:
    """Every pair asked of coal (pinocchio's own query, no bounds in front): the reference verdict."""
    return bool(pin.computeCollisions(robot.model, robot.data, robot.geom_model, robot.geom_data, q, True))




def test_verdicts_equal_in_collision(cell, geometry_paths):
    robot, stops = cell
    rng = np.random.default_rng(5)
    Q = np.vstack([stops, [robot.random_configuration(rng) for _ in range(600)],
                   stops + rng.normal(0.0, 0.05, stops.shape)])
    c = CollisionCuller(robot)
    S = c.survivors(Q)
    fresh = np.array([coal_verdict(robot, q) for q in Q])
    culled = np.array([bool(np.any(S[i])) and c.collides(q, np.flatnonzero(S[i])) for i, q in enumerate(Q)])
    assert fresh.any() and not fresh.all()
    assert np.array_equal(culled, fresh)
    assert S.sum() < 0.3 * S.size            # the bounds do clear most pairs
    # a pair the bounds clear is one coal does not report: every colliding pair survived
    for i in np.flatnonzero(fresh)[:40]:
        hits = {tuple(p) for p in robot.colliding_pairs(Q[i])}
        objs = robot.geom_model.geometryObjects
        kept = {(objs[cp.first].name, objs[cp.second].name)
                for k, cp in enumerate(robot.geom_model.collisionPairs) if S[i, k]}
        assert hits <= kept


def test_distance_field_bounds_the_distance(cell):
    robot, _ = cell
    c = CollisionCuller(robot)
    field = c.obstacles[0][0]
    rng = np.random.default_rng(2)
    P = robot.base_pose[:3, 3] + rng.uniform(-1.2, 1.2, (300, 3))
    lb = field.lower_bounds(P)
    exact = np.array([field._exact(p) for p in P])
    assert np.all(lb <= exact + 1e-12)
    assert np.array_equal(field.lower_bounds(P), lb)    # the cells are remembered, the bounds stay


def test_segment_finds_the_same_first_colliding_state(cell, geometry_paths):
    """A straight move from a solved stop to a colliding configuration: the culled check of its dense states (in
    order and in the planner's coarse-to-fine order) stops at the same state as ``in_collision`` one by one."""
    robot, stops = cell
    rng = np.random.default_rng(11)
    bad = next(q for q in (robot.random_configuration(rng) for _ in range(1000)) if coal_verdict(robot, q))
    a = stops[len(stops) // 2]
    n = 200
    Q = np.array([a + (bad - a) * (k / n) for k in range(1, n + 1)])
    first = next(i for i, q in enumerate(Q) if coal_verdict(robot, q))
    assert CollisionCuller(robot).first_collision(Q) == first
    order = planning._bisection_order(n)
    Qo = np.array([a + (bad - a) * (k / n) for k in order])
    first_o = next(i for i, q in enumerate(Qo) if coal_verdict(robot, q))
    assert CollisionCuller(robot).first_collision(Qo) == first_o
    # check_path: the same first bad segment with and without the culled queries
    P = np.vstack([stops[:4], bad, stops[4:6]])
    with_cull = check_path(robot, P, 0.01, static_torque=True)
    counted = []
    robot.in_collision = lambda q: counted.append(1) or coal_verdict(robot, q)
    try:
        memo = planning._Memoized(planning._config_validator(robot, True))   # no robot: every state one query
        without = check_path(robot, P, 0.01, static_torque=True, _valid=memo)
    finally:
        del robot.in_collision
    assert with_cull == without and not with_cull[0] and counted


def test_the_culler_is_kept_while_the_geometry_is(cell):
    robot, stops = cell
    c = culler_of(robot)
    assert culler_of(robot) is c
    T = robot.base_pose.copy()
    try:
        robot.set_base_pose(T @ np.diag([1.0, 1.0, 1.0, 1.0]) + np.array([[0, 0, 0, SLACK * 50]] * 3 + [[0, 0, 0, 0]]))
        c2 = culler_of(robot)
        assert c2 is not c
        q = stops[1]
        S = c2.survivors(q[None])
        assert (bool(S.any()) and c2.collides(q, np.flatnonzero(S[0]))) == coal_verdict(robot, q)
    finally:
        robot.set_base_pose(T)


def test_verdicts_equal_in_collision_with_a_safety_margin(cell, geometry_paths):
    """With a 3 cm safety margin on the robot–obstacle pairs (coal's security margin), the bounds keep the pairs
    that come within it: the same verdicts as ``in_collision`` on states near the machine."""
    robot, stops = cell
    obstacles, margin = list(robot.obstacles), robot.safety_margin
    rng = np.random.default_rng(8)
    Q = np.vstack([stops, stops + rng.normal(0.0, 0.1, stops.shape),
                   [robot.random_configuration(rng) for _ in range(300)]])
    try:
        robot.set_obstacles(obstacles, safety_margin=0.03)
        c = culler_of(robot)
        fresh = np.array([coal_verdict(robot, q) for q in Q])
        S = c.survivors(Q)
        culled = np.array([bool(np.any(S[i])) and c.collides(q, np.flatnonzero(S[i])) for i, q in enumerate(Q)])
        assert np.array_equal(culled, fresh)
        robot.set_obstacles(obstacles, safety_margin=0.0)
        plain = np.array([coal_verdict(robot, q) for q in Q])
        assert (fresh & ~plain).any()     # the margin does make some states collide
    finally:
        robot.set_obstacles(obstacles, safety_margin=margin)


def test_field_cells_are_coals_distances_at_their_centres(cell):
    """fill's cells (centres made in one numpy pass, coal asked with one kept pose) hold, bit for bit, the distance
    coal gives at each cell's centre made one by one as before ((grid_lo + index + 0.5) · cell, a new transform per
    point), on a fresh field of the PTP_3 machine: random batches with repeats and known cells (seeded)."""
    import coal
    from robodesign.model.collision_cull import DistanceField
    robot, _ = cell
    o = robot.geom_model.geometryObjects[robot.n_collision_geometries]
    field = DistanceField(o.geometry, o.placement.homogeneous)
    assert len(field.values) > 1000
    dz, dy = int(field.grid_dim[2]), int(field.grid_dim[1])
    req, res, dot = coal.DistanceRequest(), coal.DistanceResult(), coal.Sphere(0.0)

    def one_by_one(f):
        c = (field.grid_lo + np.array([f // (dy * dz), f // dz % dy, f % dz]) + 0.5) * field.cell
        res.clear()
        return float(coal.distance(dot, coal.Transform3s(np.eye(3), c), field.shape, field.tf, req, res))

    rng = np.random.default_rng(8)
    for _ in range(6):
        flat = rng.integers(len(field.values), size=int(rng.integers(1, 80)))
        flat = np.concatenate([flat, flat[:5]])
        got = field.fill(flat)
        want = np.array([one_by_one(f) for f in flat.tolist()])
        assert got.tobytes() == want.tobytes()
    assert np.isnan(field.values).sum() < len(field.values)
