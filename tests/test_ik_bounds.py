"""Provable IK early failure (solvers.ik.ChainBounds): a goal the bounds reject has no solution, and a
reachable goal is never rejected — checked against poses the arm does reach (forward kinematics of random
configurations, nominal moved inside the tolerance) and against the full restart loop on random goals."""
from __future__ import annotations

import math

import numpy as np
import pytest

from robodesign.core.spatial import homogeneous, rpy_to_matrix
from robodesign.formats.module_io import load_module_set
from robodesign.formats.tolerance import ToleratedPose
from robodesign.model.robot import Robot
from robodesign.solvers.ik import chain_bounds, provably_unreachable, solve_ik

from conftest import IMPROV, PRIMITIVES

BASE = homogeneous(rpy_to_matrix(0.3, -0.2, 1.0), [1.0, 2.0, 0.5])


@pytest.fixture(scope="module")
def robots(tmp_path_factory):
    from test_urdf import reversed_robot
    imp = load_module_set(IMPROV)
    prim = load_module_set(PRIMITIVES)
    return [Robot.from_order(imp, ["1", "21", "4", "22", "5", "23", "12"]),
            Robot.from_order(imp, ["1", "22", "5", "23", "15", "29", "101"], base_pose=BASE),
            Robot.from_order(imp, ["1", "21", "23", "22", "12"]),
            Robot.from_order(prim, ["base", "J2", "i_30", "J1", "l_15", "J2", "eef"]),
            reversed_robot(tmp_path_factory.mktemp("rev"))]


def random_rotation(rng):
    return rpy_to_matrix(*rng.uniform(-math.pi, math.pi, 3))


def moved_inside(T, rng, r, th):
    """A nominal pose from which T lies within position r and angle th (so the goal is reachable)."""
    u = rng.normal(size=3)
    w = rng.normal(size=3)
    N = np.array(T)
    N[:3, 3] = T[:3, 3] + u / np.linalg.norm(u) * r * rng.uniform(0.0, 0.999)
    a = th * rng.uniform(0.0, 0.999)
    k = w / np.linalg.norm(w)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    N[:3, :3] = T[:3, :3] @ (np.eye(3) + math.sin(a) * K + (1 - math.cos(a)) * K @ K)
    return N


def test_reachable_goals_are_never_rejected(robots):
    rng = np.random.default_rng(0)
    for robot in robots:
        for _ in range(300):
            T = robot.fk(robot.random_configuration(rng))
            r, th = rng.choice([0.0005, 0.01, 0.1]), rng.choice([0.001, 0.05, 0.5, 3.0])
            goal = ToleratedPose(moved_inside(T, rng, r, th), ("r_sph", "Theta_R"), ((0.0, r), (0.0, th)))
            assert goal.valid(T)
            assert provably_unreachable(robot, goal) == ""
            box = ToleratedPose(moved_inside(T, rng, r, 0.0), ("x", "y", "z", "N_x", "N_y", "N_z"),
                                ((-r / 2, r / 2),) * 3 + ((-th / 2, th / 2),) * 3)
            if box.valid(T):
                assert provably_unreachable(robot, box) == ""
            # the tool axis within th of the nominal's, any turn about it (as the Liu goals)
            yaw = rng.uniform(-math.pi, math.pi)
            Nt = moved_inside(T, rng, r, 0.0) @ homogeneous(rpy_to_matrix(rng.uniform(-th, th) / 2, 0.0, yaw), np.zeros(3))
            axis = ToleratedPose(Nt, ("x", "y", "z", "N_x", "N_y"), ((-r, r),) * 3 + ((-th, th),) * 2)
            if axis.valid(T):
                assert provably_unreachable(robot, axis) == ""


def test_rejected_goals_fail_the_full_restart_loop(robots):
    """Random goals around each arm: every goal the bounds reject also fails 300 restarts (without
    collisions, so only kinematics decides), and the tighter bounds reject goals the sphere does not."""
    rng = np.random.default_rng(1)
    counts = {"out_of_reach": 0, "out_of_orientation_reach": 0, "sphere": 0, "tighter": 0}
    for robot in robots[:3]:
        cb = chain_bounds(robot)
        assert cb.circle is not None
        for _ in range(60):
            N = np.eye(4)
            N[:3, :3] = random_rotation(rng)
            N[:3, 3] = cb.o + rng.uniform(-1.0, 1.0, 3) * cb.R
            goal = ToleratedPose(N, ("r_sph", "Theta_R"), ((0.0, 0.01), (0.0, 0.05))) if _ % 2 else \
                ToleratedPose(N, ("r_sph", "N_x", "N_y"), ((0.0, 0.01), (-0.1, 0.1), (-0.1, 0.1)))
            why = provably_unreachable(robot, goal)
            sphere = np.linalg.norm(N[:3, 3] - cb.o) - 0.01 > cb.R + 1e-9
            counts["sphere"] += sphere
            if not why:
                assert not sphere
                continue
            counts[why] += 1
            counts["tighter"] += not sphere
            if not sphere:   # the full loop, without the early exit, also finds nothing
                full = solve_ik(robot, goal, 0, max_restarts=300, check_collision=False, reach_bounds=False)
                assert not full.success and full.stats["attempts"] == 300
    assert counts["tighter"] >= 5 and counts["out_of_orientation_reach"] >= 3, counts


def test_early_exit_costs_no_restarts(robots):
    robot = robots[0]
    cb = chain_bounds(robot)
    N = np.eye(4)
    c, a, rho = cb.circle
    N[:3, 3] = c - a * (cb.R1 + 0.05)     # below the base along its axis: inside the sphere, beyond R' of C1
    assert np.linalg.norm(N[:3, 3] - cb.o) < cb.R
    goal = ToleratedPose(N, ("r_sph",), ((0.0, 0.01),))
    res = solve_ik(robot, goal, 0)
    assert not res.success and res.stats["reason"] == "out_of_reach" and res.stats["attempts"] == 0


def test_bounds_change_nothing_when_they_pass():
    """On the PTP_3 goals (r_sph 1 cm, Theta_R 0.01 rad) with the CNC mesh: for arms whose goals the bounds
    let through, the same seed gives bit-identical solutions and counters with and without the bounds; arms
    they stop fail with the full loop as well."""
    from robodesign.formats.task_io import load_task
    from robodesign.formats.assembly import Assembly
    from robodesign.model.cell import build_robot
    from robodesign.solvers.schedule import static_cell
    from conftest import TASKS
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    passed = stopped = 0
    for order in (["1", "21", "4", "22", "5", "23", "12"], ["1", "22", "7", "29", "4", "21", "16"],
                  ["1", "21", "23", "22", "12"], ["1", "23", "5", "21", "14", "22", "101"]):
        robot = build_robot(static_cell(task), ms, Assembly.from_order(ms, order), task.nominal_base_pose)
        for g in task.goals[:2]:
            a = solve_ik(robot, g.pose, 3, max_restarts=60, n_solutions=4)
            b = solve_ik(robot, g.pose, 3, max_restarts=60, n_solutions=4, reach_bounds=False)
            if a.stats["reason"] in ("out_of_reach", "out_of_orientation_reach"):
                stopped += 1
                assert not b.success and a.stats["attempts"] == 0
                continue
            passed += 1
            assert len(a.solutions) == len(b.solutions)
            assert all(np.array_equal(x, y) for x, y in zip(a.solutions, b.solutions))
            assert {k: v for k, v in a.stats.items() if k != "time"} == {k: v for k, v in b.stats.items() if k != "time"}
    assert passed >= 3


def test_the_verdict_is_remembered_per_goal_model(robots):
    """ChainBounds.unreachable remembers its answer per goal model (the IK stage asks per goal, solve_ik again):
    the remembered answer is the computed one, for reachable and unreachable goals alike."""
    from robodesign.solvers.ik import goal_model
    robot = robots[0]
    cb = chain_bounds(robot)
    rng = np.random.default_rng(5)
    answers = []
    for k in range(40):
        N = homogeneous(random_rotation(rng), rng.uniform(-1.5, 1.5, 3))
        goal = ToleratedPose(N, ("r_sph", "Theta_R"), ((0.0, 0.01), (0.0, [0.01, 3.0][k % 2])))
        gm = goal_model(goal)
        first = cb.unreachable(gm)
        assert first == cb._unreachable(gm) == cb.unreachable(gm) == provably_unreachable(robot, goal)
        assert cb._verdicts[id(gm)] == (gm, first)
        answers.append(first)
    assert {"", "out_of_reach", "out_of_orientation_reach"} <= set(answers)
