"""The compiled single-configuration broad phase (robodesign.model.geometry_kernel) behind ``Robot.in_collision``:
on the real PTP_3 cell (IMPROV arm, the CNC-machine mesh) and in a cell of boxes around it, the culled verdicts
equal coal's over every pair, every pair coal finds colliding survives the bounds, the robot forgets its culler
when its geometry changes, and the grid and box bounds are what they claim (checked against coal's distances)."""
import coal
import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV, TASKS, boxes_around

from robodesign.formats.assembly import Assembly
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.model import collision_cull, geometry_kernel
from robodesign.model.cell import build_robot
from robodesign.model.collision_cull import CELL, DistanceField, distance_field
from robodesign.model.robot import Obstacle
from robodesign.solvers.schedule import static_cell

pytestmark = pytest.mark.skipif(not geometry_kernel.available(), reason="numba unavailable or ROBODESIGN_JIT=0")

GOOD = ("1", "21", "4", "22", "5", "23", "12")


@pytest.fixture(scope="module")
def robot():
    assert geometry_kernel.warm_up() and geometry_kernel.ready()
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    return build_robot(static_cell(task), ms, Assembly.from_order(ms, GOOD), task.nominal_base_pose)


def coal_verdict(robot, q) -> bool:
    """Every pair asked of coal (pinocchio's query, no bounds in front): the reference verdict."""
    return bool(pin.computeCollisions(robot.model, robot.data, robot.geom_model, robot.geom_data, q, True))


def states(robot, n, seed):
    rng = np.random.default_rng(seed)
    Q = np.array([robot.random_configuration(rng) for _ in range(n)])
    return np.vstack([Q, Q[: n // 2] + rng.normal(0.0, 0.05, (n // 2, robot.dof))])


def check_cell(robot, Q):
    """The robot's verdicts (the culled path after the first queries) against coal's; every colliding pair kept."""
    verdicts = [robot.in_collision(q) for q in Q]
    c = robot._culler
    assert c is not None, "the culled path took over"
    assert verdicts == [coal_verdict(robot, q) for q in Q]
    args, *_ = c._one
    gm = robot.geom_model
    objs = gm.geometryObjects
    for q in Q[np.flatnonzero(verdicts)[:60]]:
        n, _, _ = geometry_kernel.survivors(q, *args)
        kept = {int(k) for k in args[-2][:n]}
        names = {(objs[gm.collisionPairs[k].first].name, objs[gm.collisionPairs[k].second].name) for k in kept}
        assert set(robot.colliding_pairs(q)) <= names
    return np.array(verdicts)


def test_culled_verdicts_equal_coal_on_the_ptp3_cell(robot):
    Q = states(robot, 600, 1)
    v = check_cell(robot, Q)
    assert 0.1 < v.mean() < 0.9
    c = robot._culler
    asked = c.narrow
    for q in Q[:200]:
        robot.in_collision(q)
    assert c.narrow - asked < 200 * 0.25 * len(robot.geom_model.collisionPairs)   # the bounds clear most pairs


def test_culled_verdicts_equal_coal_among_boxes_and_with_a_margin(robot):
    obstacles, margin = list(robot.obstacles), robot.safety_margin
    try:
        for seed, m in ((3, 0.0), (4, 0.05)):
            robot.set_obstacles(boxes_around(robot, seed), safety_margin=m)
            assert robot._culler is None
            v = check_cell(robot, states(robot, 400, seed))
            assert v.any() and not v.all()
            fields = [f for f, *_ in robot._culler.obstacles]
            assert fields and all(f.is_box and len(f.values) == 0 for f in fields)   # boxes: the exact box bound
    finally:
        robot.set_obstacles(obstacles, safety_margin=margin)


def test_several_gridded_obstacles_share_one_grid_array(robot, monkeypatch):
    """The machine's mesh, a sphere and a cylinder: three grids, copied into one array for the kernel; the cells
    the kernel fills reach both the copy and the fields (a later culler finds them known)."""
    monkeypatch.setattr(collision_cull, "_FIELDS", {})   # (no field of an earlier test dropped beyond the budget)
    obstacles, margin = list(robot.obstacles), robot.safety_margin
    rng = np.random.default_rng(21)
    extra = []
    for i, shape in enumerate((coal.Sphere(0.15), coal.Cylinder(0.1, 0.5))):
        T = np.eye(4)
        T[:3, :3] = pin.exp3(rng.normal(0.0, 1.0, 3))
        T[:3, 3] = robot.base_pose[:3, 3] + rng.uniform(-0.5, 0.5, 3)
        extra.append(Obstacle(f"round{i}", shape, T))
    try:
        robot.set_obstacles([*obstacles, *extra], safety_margin=0.01)
        Q = states(robot, 300, 22)
        v = check_cell(robot, Q)
        assert v.any() and not v.all()
        (args, (fields, offsets, direct, grid), _) = robot._culler._one
        assert direct is None and len(fields) == 3 and all(len(f.values) for f in fields)
        assert len(grid) == sum(len(f.values) for f in fields)
        for f, o in zip(fields, offsets):
            assert np.array_equal(grid[o:o + len(f.values)], f.values, equal_nan=True)   # filled in both
        assert np.isfinite(grid).sum() > 0
        robot.set_base_pose(robot.base_pose)
        for q in Q[:1]:
            robot.in_collision(q)
        args2, *_ = robot._culler._one
        assert all(geometry_kernel.survivors(q, *args2)[1] == 0 for q in Q[1:])   # (the culled ones)
    finally:
        robot.set_obstacles(obstacles, safety_margin=margin)


def test_the_robot_forgets_its_culler_when_its_geometry_changes(robot):
    Q = states(robot, 40, 6)
    for q in Q[:1]:
        robot.in_collision(q)
    assert robot._culler is not None
    free = next(q for q in Q if not coal_verdict(robot, q))
    assert not robot.in_collision(free)
    obstacles, T = list(robot.obstacles), robot.base_pose.copy()
    try:
        # a box moved onto the TCP: the same state now collides
        away = np.eye(4)
        away[:3, 3] = 50.0
        box = Obstacle("box", coal.Box(0.2, 0.2, 0.2), away)
        robot.set_obstacles([*obstacles, box], robot.safety_margin)
        for q in Q[:1]:
            robot.in_collision(q)
        assert robot._culler is not None
        assert not robot.in_collision(free) and not coal_verdict(robot, free)
        robot.move_obstacle(len(obstacles), robot.fk(free))
        assert robot._culler is None
        assert robot.in_collision(free) and coal_verdict(robot, free)
        # the base moved 10 m away from the machine: no obstacle contact is left for the same states
        robot.set_obstacles(obstacles, robot.safety_margin)
        for q in Q[:1]:
            robot.in_collision(q)
        far = T.copy()
        far[:3, 3] += (10.0, 0.0, 0.0)
        robot.set_base_pose(far)
        assert robot._culler is None
        check_cell(robot, Q)
    finally:
        robot.set_obstacles(obstacles, robot.safety_margin)
        robot.set_base_pose(T)


def test_grid_and_dictionary_hold_the_exact_distance_of_the_cell_centre(robot):
    ob = robot.obstacles[0]
    field = DistanceField(ob.shape, ob.pose)
    assert not field.is_box and len(field.values) == int(np.prod(field.grid_dim)) > 0
    rng = np.random.default_rng(9)
    inside = (field.grid_lo + rng.uniform(0, 1, (200, 3)) * field.grid_dim) * CELL
    outside = (field.grid_lo - 3 - rng.uniform(0, 20, (50, 3))) * CELL
    P = np.vstack([inside, outside])
    lb = field.lower_bounds(P)
    centres = (np.floor(P / CELL) + 0.5) * CELL
    want = np.array([field._exact(c) for c in centres]) - np.linalg.norm(P - centres, axis=1)
    assert np.array_equal(lb, want)                              # the same numbers as the dictionary's formula
    assert len(field.known) == len(np.unique(np.floor(outside / CELL), axis=0))   # outside: the dictionary
    assert np.isfinite(field.values).sum() == len(np.unique(np.floor(inside / CELL), axis=0))
    exact = np.array([field._exact(p) for p in P])
    assert np.all(lb <= exact + 1e-12) and np.all(field.box_bounds(P) <= exact + 1e-9)


def test_box_bound_is_coal_distance_for_a_box():
    rng = np.random.default_rng(2)
    T = np.eye(4)
    T[:3, :3] = pin.exp3(np.array([0.3, -0.7, 1.1]))
    T[:3, 3] = (0.4, -0.2, 0.9)
    field = DistanceField(coal.Box(0.3, 0.5, 0.2), T)
    P = T[:3, 3] + rng.uniform(-0.8, 0.8, (300, 3))
    exact = np.array([field._exact(p) for p in P])
    b = field.box_bounds(P)
    out = exact > 1e-9
    assert out.sum() > 250 and np.allclose(b[out], exact[out], atol=1e-9)
    assert np.all(b[~out] == 0.0)


def test_unknown_cells_are_filled_for_the_next_queries(robot):
    robot.set_base_pose(robot.base_pose)        # a fresh culler
    Q = states(robot, 60, 12)
    for q in Q[:1]:
        robot.in_collision(q)
    args, *_ = robot._culler._one
    for q in Q:
        robot.in_collision(q)
        n, nu, _ = geometry_kernel.survivors(q, *args)
        assert nu == 0                            # the cells this state asked about are known now
        pin.updateGeometryPlacements(robot.model, robot.data, robot.geom_model, robot.geom_data, q)
        assert set(args[-2][:n].tolist()) >= {k for k in range(len(robot.geom_model.collisionPairs))
                                            if pin.computeCollision(robot.geom_model, robot.geom_data, k)}


def test_grids_are_dropped_beyond_the_budget(monkeypatch):
    monkeypatch.setattr(collision_cull, "_FIELDS", {})
    shape = coal.Sphere(0.3)
    first = distance_field(shape, np.eye(4))
    size = len(first.values)
    assert size > 0
    monkeypatch.setattr(collision_cull, "GRID_CELLS_KEPT", int(2.5 * size))
    poses = [np.eye(4) for _ in range(3)]
    for k, T in enumerate(poses):
        T[0, 3] = k + 1.0
        distance_field(shape, T)
    assert len(collision_cull._FIELDS) == 2     # two grids fit the budget: the oldest were dropped
    assert distance_field(shape, poses[-1]) is distance_field(shape, poses[-1])
    assert first is not distance_field(shape, np.eye(4))


def test_a_cold_cache_starts_one_compiler_and_looks_for_the_stamp_once_a_second(monkeypatch):
    """core.jit_cache.KernelModule as the geometry kernels use it (every=1.0): one background compiler, the stamp
    looked for at most once a second, the compiled kernels from the first look that finds it."""
    from robodesign.core import jit_cache
    assert geometry_kernel.KERNELS.every == 1.0
    clock, looks, started, warmed = [100.0], [], [], []
    km = jit_cache.KernelModule("robodesign.model.geometry_kernel", geometry_kernel.__file__,
                                geometry_kernel.survivors, ("survivors",), lambda: warmed.append(clock[0]), every=1.0)
    monkeypatch.setattr(jit_cache.time, "monotonic", lambda: clock[0])
    monkeypatch.setattr(km, "compiled", lambda: looks.append(clock[0]) or clock[0] >= 103.0)
    monkeypatch.setattr(km.cache, "start_compiler", lambda: started.append(1) or object())
    assert not km.ready() and started == [1] and looks == [100.0]   # the compiler starts, the numpy path runs
    for t in (100.3, 100.9):
        clock[0] = t
        assert not km.ready()
    assert looks == [100.0] and started == [1] and not warmed     # not looked for again within the second
    clock[0] = 101.2
    assert not km.ready() and looks == [100.0, 101.2] and started == [1]
    clock[0] = 103.5
    assert km.ready() and km.state == "ready" and warmed == [103.5]   # the stamp is there: compiled from now on
    clock[0] = 103.6
    assert km.ready() and looks == [100.0, 101.2, 103.5] and warmed == [103.5]


def test_no_compiler_when_the_kernels_are_off(monkeypatch):
    from robodesign.core import jit_cache
    monkeypatch.setenv("ROBODESIGN_JIT", "0")
    km = jit_cache.KernelModule("robodesign.model.geometry_kernel", geometry_kernel.__file__,
                                geometry_kernel.survivors, ("survivors",), lambda: pytest.fail("no warm-up"), every=1.0)
    monkeypatch.setattr(km.cache, "start_compiler", lambda: pytest.fail("no compiler with ROBODESIGN_JIT=0"))
    assert not km.available() and not km.ready() and km.state is None and not km.warm_up()
