"""solve_ik: solutions lie inside the tolerated pose (checked by goal.valid and independently), within the
joint limits and collision-free; free directions of the tolerance are exploited; failures are clean."""
import json
import math

import numpy as np
import pinocchio as pin
import pytest

from robodesign.formats.geometry import coal_shapes, parse_geometries
from robodesign.formats.module_io import load_module_set
from robodesign.model.robot import Obstacle, Robot
from robodesign.solvers.ik import IKResult, goal_model, solve_ik
from robodesign.formats.tolerance import ToleratedPose

from conftest import IMPROV, TASKS

ORDER = ["1", "21", "4", "22", "5", "23", "12"]
# an IMPROV arm that reaches goal "1" of simple/PTP_3 (found by a 3000-restart search)
PTP3_ARM = ["1", "22", "7", "29", "4", "21", "16"]


@pytest.fixture(scope="module")
def ms():
    return load_module_set(IMPROV)


@pytest.fixture(scope="module")
def robot(ms):
    return Robot.from_order(ms, ORDER)


def free_config(robot, seed):
    rng = np.random.default_rng(seed)
    while True:
        q = robot.random_configuration(rng)
        if not robot.in_collision(q):
            return q


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def angle(R):
    return math.acos(max(-1.0, min(1.0, (np.trace(R) - 1) / 2)))


def check_common(robot, goal, res):
    assert isinstance(res, IKResult)
    assert res.success and res.stats["reason"] == "found"
    for q in res.solutions:
        assert goal.valid(robot.fk(q))
        assert np.all(q >= robot.q_lower) and np.all(q <= robot.q_upper)
        assert not robot.in_collision(q)


def test_sphere_and_angle_tolerance(robot):
    T_ref = robot.fk(free_config(robot, 1)).copy()
    goal = ToleratedPose(T_ref, ("r_sph", "Theta_R"), ((0.0, 0.01), (0.0, 0.01)))
    for seed in range(5):
        res = solve_ik(robot, goal, seed)
        check_common(robot, goal, res)
        T = robot.fk(res.q)
        # independent computation: position error norm and rotation angle
        assert np.linalg.norm(T[:3, 3] - T_ref[:3, 3]) <= 0.01 + 1e-12
        assert angle(T_ref[:3, :3].T @ T[:3, :3]) <= 0.01 + 1e-9


def test_box_with_free_yaw(robot):
    """x, y, z ±5 mm and N_x, N_y ±0.01 in the nominal frame; N_z is free: the tool z axis must match,
    the yaw may differ from the nominal."""
    T_ref = robot.fk(free_config(robot, 2)).copy()
    nominal = T_ref @ rot_z(1.0)          # the yaw of the nominal is not that of the reference config
    goal = ToleratedPose(nominal, ("x", "y", "z", "N_x", "N_y"),
                         ((-0.005, 0.005), (-0.005, 0.005), (-0.005, 0.005), (-0.01, 0.01), (-0.01, 0.01)))
    gm = goal_model(goal)
    assert "N_z" not in gm.names and len(gm.names) == 5     # no row for the free rotation
    yaws = []
    for seed in range(6):
        res = solve_ik(robot, goal, seed)
        check_common(robot, goal, res)
        T = robot.fk(res.q)
        p = nominal[:3, :3].T @ (T[:3, 3] - nominal[:3, 3])
        assert np.all(np.abs(p) <= 0.005 + 1e-12)
        z_err = math.acos(min(1.0, float(nominal[:3, 2] @ T[:3, 2])))
        assert z_err <= 0.01 * math.sqrt(2) + 1e-9                 # tilt ≤ ‖(N_x, N_y)‖
        D = nominal[:3, :3].T @ T[:3, :3]
        yaws.append(math.atan2(D[1, 0], D[0, 0]))
    assert max(abs(y) for y in yaws) > 0.1                         # the free yaw is used


def test_cylindrical_tolerance_with_nominal_outside(robot):
    """Annulus sector r_cyl ∈ [1, 3] cm, phi_cyl ∈ [0, π/2], |z| ≤ 5 mm, Theta_R ≤ 0.05: the nominal
    itself is not valid, the solver must still land inside."""
    T_ref = robot.fk(free_config(robot, 3)).copy()
    goal = ToleratedPose(T_ref, ("r_cyl", "phi_cyl", "z", "Theta_R"),
                         ((0.01, 0.03), (0.0, math.pi / 2), (-0.005, 0.005), (0.0, 0.05)))
    assert not goal.valid(T_ref)
    for seed in range(4):
        res = solve_ik(robot, goal, seed)
        check_common(robot, goal, res)
        T = robot.fk(res.q)
        x, y, z = T_ref[:3, :3].T @ (T[:3, 3] - T_ref[:3, 3])
        assert 0.01 - 1e-12 <= math.hypot(x, y) <= 0.03 + 1e-12
        assert -1e-12 <= math.atan2(y, x) <= math.pi / 2 + 1e-12
        assert abs(z) <= 0.005 + 1e-12
        assert angle(T_ref[:3, :3].T @ T[:3, :3]) <= 0.05 + 1e-9


def test_world_frame_entries(robot):
    """Tolerances given in the world frame are honoured (z only in world, rotation angle)."""
    T_ref = robot.fk(free_config(robot, 4)).copy()
    goal = ToleratedPose(T_ref, ("x", "y", "z", "Theta_R"), ((-0.003, 0.003), (-0.003, 0.003), (-0.003, 0.003),
                                                             (0.0, 0.02)), ("world", "world", "world", "nominal"))
    res = solve_ik(robot, goal, 0)
    check_common(robot, goal, res)
    assert np.all(np.abs(robot.fk(res.q)[:3, 3] - T_ref[:3, 3]) <= 0.003 + 1e-12)


def test_model_check_agrees_with_valid(robot):
    """The solver's own exact check (used to decide when to call goal.valid) agrees with goal.valid."""
    rng = np.random.default_rng(0)
    T_ref = robot.fk(free_config(robot, 5)).copy()
    goals = [
        ToleratedPose(T_ref, ("r_sph", "Theta_R"), ((0.0, 0.02), (0.0, 0.05))),
        ToleratedPose(T_ref, ("x", "y", "z", "N_x", "N_y", "N_z"), ((-0.01, 0.02), (-0.02, 0.01), (-0.01, 0.01),
                                                                   (-0.03, 0.03), (-0.03, 0.03), (0.0, 0.05))),
        ToleratedPose(T_ref, ("r_cyl", "phi_cyl", "z", "Theta_R"), ((0.0, 0.03), (-1.0, 1.0), (-0.01, 0.01),
                                                                   (0.0, 0.05))),
        ToleratedPose(T_ref, ("r_sph", "theta", "phi_sph"), ((0.0, 0.03), (0.0, 1.0), (-2.0, 2.0))),
        ToleratedPose(T_ref, ("z", "N_z"), ((-0.01, 0.01), (-0.05, 0.05)), ("world", "world")),
    ]
    J = np.zeros((6, robot.dof))
    for goal in goals:
        f, E, JJ = goal_model(goal).evaluator(robot.dof)
        agree = 0
        for _ in range(300):
            w = rng.normal(size=6) * np.array([0.02, 0.02, 0.02, 0.04, 0.04, 0.04])
            T = T_ref @ pin.exp6(pin.Motion(w)).homogeneous
            ok = f(T, J)
            assert ok == goal.valid(T)
            agree += ok
        assert 0 < agree < 300        # both valid and invalid poses were tried


def test_ptp3_goal_with_cnc_obstacle(ms):
    data = json.loads((TASKS / "simple" / "PTP_3.json").read_text())
    goal = ToleratedPose.from_json(data["goals"][0]["goalPose"])
    o = data["obstacles"][0]
    specs = parse_geometries(o["collision"], TASKS, "PTP_3.json", ["obstacles", 0, "collision"])
    arm = Robot.from_order(ms, PTP3_ARM)
    arm.set_obstacles([Obstacle(o["ID"], s, spec.pose) for spec in specs for s in coal_shapes(spec)])
    res = solve_ik(arm, goal, 0, n_solutions=3)
    check_common(arm, goal, res)
    assert len(res.solutions) == 3
    for i in range(3):
        for j in range(i):
            assert np.linalg.norm(res.solutions[i] - res.solutions[j]) > 0.1   # distinct


def test_out_of_workspace_fails_cleanly(robot):
    far = np.eye(4)
    far[:3, 3] = [5.0, 0.0, 0.5]
    goal = ToleratedPose(far, ("r_sph", "Theta_R"), ((0.0, 0.01), (0.0, 0.01)))
    o, R = robot.reach_bound()
    assert np.linalg.norm(far[:3, 3] - o) > R
    res = solve_ik(robot, goal, 0)
    assert not res.success and res.q is None and res.solutions == []
    assert res.stats["reason"] == "out_of_reach" and res.stats["iterations"] == 0
    # the same pose constrained only in z (no reach pruning possible): the search runs and fails
    below = np.eye(4)
    below[2, 3] = -5.0
    goal_z = ToleratedPose(below, ("z",), ((-0.01, 0.01),), ("world",))
    res = solve_ik(robot, goal_z, 0, max_restarts=20)
    assert not res.success and res.stats["reason"] == "max_restarts" and res.stats["attempts"] == 20


def test_deterministic_for_a_seed(robot):
    T_ref = robot.fk(free_config(robot, 6)).copy()
    goal = ToleratedPose(T_ref, ("r_sph", "Theta_R"), ((0.0, 0.01), (0.0, 0.01)))
    a = solve_ik(robot, goal, 42, n_solutions=2)
    b = solve_ik(robot, goal, np.random.default_rng(42), n_solutions=2)
    assert len(a.solutions) == len(b.solutions) == 2
    assert all(np.array_equal(x, y) for x, y in zip(a.solutions, b.solutions))


def test_seed_and_limits(robot):
    q_ref = free_config(robot, 7)
    goal = ToleratedPose(robot.fk(q_ref).copy(), ("r_sph", "Theta_R"), ((0.0, 0.001), (0.0, 0.001)))
    res = solve_ik(robot, goal, 0, q_seed=q_ref)           # the seed itself is a solution
    assert res.success and res.stats["attempts"] == 1 and res.stats["iterations"] == 1
    assert np.array_equal(res.q, q_ref)
    # an unconstrained goal: any collision-free configuration
    anything = ToleratedPose(np.eye(4))
    res = solve_ik(robot, anything, 0)
    assert res.success and not robot.in_collision(res.q)
    # bad arguments
    with pytest.raises(ValueError):
        solve_ik(robot, goal, 0, q_seed=np.zeros(3))
    with pytest.raises(ValueError):
        solve_ik(robot, robot.fk(q_ref), 0)


def test_time_limit(robot):
    goal_z = ToleratedPose(np.eye(4), ("z",), ((-5.01, -4.99),), ("world",))
    res = solve_ik(robot, goal_z, 0, max_restarts=100000, time_limit=0.05)
    # it stopped because of the limit, after it (a lower bound: the machine's load can only lengthen the time)
    assert not res.success and res.stats["reason"] == "time_limit" and res.stats["time"] >= 0.05


def test_projection_without_analytic_rows(robot):
    """Roll/pitch bounds (no analytic row): handled by the fallback rotation rows, yaw stays free."""
    T_ref = robot.fk(free_config(robot, 8)).copy()
    goal = ToleratedPose(T_ref, ("x", "y", "z", "R", "P"),
                         ((-0.005, 0.005),) * 3 + ((-0.02, 0.02), (-0.02, 0.02)))
    assert goal_model(goal).fallback
    res = solve_ik(robot, goal, 0)
    check_common(robot, goal, res)
