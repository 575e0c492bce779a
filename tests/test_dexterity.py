"""Dexterity: an arm whose tool cannot move in all six pose directions does not search for a full-pose goal.

``Robot.generic_rank`` is checked against a finite-difference Jacobian of the forward kinematics alone
(independent of pinocchio's Jacobian); ``fixes_full_pose`` against the published tolerances; the IK stage and
the informed search against seeded runs.
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from test_reach_bound import reach_task_json

from robodesign import Robot, load_module_set
from robodesign.design.problem import Problem
from robodesign.design.search_space import SearchSpace
from robodesign.design.solve import SolveSettings, solve
from robodesign.formats.task_io import load_task
from robodesign.formats.tolerance import ToleratedPose

HEAVY = "robodesign_heavy"
# module orders of robodesign_heavy (assets/modules/robodesign_heavy/README.md) and the rank a hand count gives:
ORDERS = {
    "1,21,22,8,24,12,25,26,25,16": 6,  # example B: roll–pitch shoulder, pitch elbow, roll–pitch–roll wrist
    "1,21,22,8,24,12,25,25,26,16": 5,  # two coaxial wrist rolls: one direction lost
    "1,21,22,8,24,12,26,26,26,16": 4,  # four parallel pitch axes (elbow + 3 wrist pitches): a planar chain of 4
    "1,21,21,3,23,4,25,26,25,16": 3,   # only one axis that is not along the arm at q = 0 ... and coaxial rolls
}


def first_verdict_forged(real, calls: list, violations: list):
    """A stand-in for the solve pipeline's ``check``: the first verdict has the real costs but the given
    ``violations`` (INVALID); every later one is the real judge's. Each judged solution is appended to ``calls``."""
    from robodesign.judge.checker import Verdict

    def fake_check(t, sol, m, **kw):
        calls.append(sol)
        v = real(t, sol, m, **kw)
        if len(calls) == 1:
            return Verdict(False, list(violations), v.costs, v.cost, v.cost_function, v.goals)
        return v
    return fake_check


def numeric_rank(robot: Robot, q: np.ndarray, h: float = 1e-6) -> int:
    """Rank of the pose Jacobian by central differences of Robot.fk (position; rotation through the log map),
    angular part scaled by the reach radius like generic_rank."""
    R = max(robot.reach_bound()[1], 1e-3)
    cols = []
    for j in range(robot.dof):
        e = np.zeros(robot.dof)
        e[j] = h
        Tp, Tm = robot.fk(q + e), robot.fk(q - e)
        dp = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        dR = Tp[:3, :3] @ Tm[:3, :3].T  # ≈ exp(2h·[ω]×)
        w = np.array([dR[2, 1] - dR[1, 2], dR[0, 2] - dR[2, 0], dR[1, 0] - dR[0, 1]]) / 2 / (2 * h)
        cols.append(np.concatenate([dp, R * w]))
    s = np.linalg.svd(np.array(cols).T, compute_uv=False)
    return int(np.sum(s > 1e-5 * s[0]))


@pytest.mark.parametrize("order,hand", list(ORDERS.items()))
def test_generic_rank_against_finite_differences(order, hand):
    ms = load_module_set(HEAVY)
    r = Robot.from_order(ms, order.split(","))
    rng = np.random.default_rng(3)
    lo, hi = np.maximum(r.q_lower, -math.pi), np.minimum(r.q_upper, math.pi)
    numeric = max(numeric_rank(r, rng.uniform(lo, hi)) for _ in range(3))
    assert r.generic_rank() == numeric == hand


def _pose(projections, tolerance):
    T = np.eye(4)
    T[:3, 3] = (0.8, 0.2, -0.3)
    return ToleratedPose.from_json({"nominal": T.tolist(), "toleranceProjection": projections,
                                    "tolerance": tolerance})


def test_full_pose_goals_are_those_of_the_published_families():
    from robodesign.solvers.ik import fixes_full_pose
    mm = [[-1e-3, 1e-3]] * 3
    assert fixes_full_pose(_pose(["x", "y", "z", "Theta_R"], mm + [[0, math.radians(0.5)]]))  # Whitman, BPO24
    assert fixes_full_pose(_pose(["x", "y", "z", "N_x", "N_y", "N_z"], mm + [[-0.01, 0.01]] * 3))
    assert not fixes_full_pose(_pose(["x", "y", "z"], [[-5e-3, 5e-3]] * 3))  # position only (the easy variants)
    assert not fixes_full_pose(_pose(["x", "y", "z", "N_x", "N_y"], mm + [[-0.1, 0.1]] * 2))  # tool axis only
    assert not fixes_full_pose(_pose(["x", "y", "z", "Theta_R"], mm + [[0, math.radians(30)]]))  # loose angle
    assert not fixes_full_pose(_pose(["x", "y", "Theta_R"], [[-1e-3, 1e-3]] * 2 + [[0, 0.01]]))  # z free


def _full_pose_task(tmp_path, full: bool = True):
    data = reach_task_json([(0.7, 0.2, -0.1)], name="dex")
    T = np.array([[0.0, 1.0, 0.0, 0.7], [1.0, 0.0, 0.0, 0.2], [0.0, 0.0, -1.0, -0.1], [0, 0, 0, 1]])
    pose = data["goals"][0]["goalPose"]
    pose["nominal"] = T.tolist()
    if full:
        pose["toleranceProjection"] = ["x", "y", "z", "Theta_R"]
        pose["tolerance"] = [[-1e-3, 1e-3]] * 3 + [[0, math.radians(0.5)]]
    f = tmp_path / "dex.json"
    f.write_text(json.dumps(data))
    return load_task(f)


def test_the_ik_stage_stops_a_rank_deficient_arm_at_a_full_pose_goal(tmp_path):
    ms = load_module_set(HEAVY)
    settings = SolveSettings(seed=0, stop_after="ik", ik_restarts=20, ik_solutions=1)
    for order, rank in ORDERS.items():
        res = solve(_full_pose_task(tmp_path), ms, order.split(","), settings=settings)
        if rank < 6:
            assert res.stage == "ik" and res.goals_reached == 0
            assert f"moves in only {rank} independent directions" in res.message
        else:
            assert "independent directions" not in (res.message or "")
    # a position-only goal is searched as before, whatever the rank (a rank-4 arm reaches a point)
    res = solve(_full_pose_task(tmp_path, full=False), ms, "1,21,22,8,24,12,26,26,26,16".split(","),
                settings=settings)
    assert "independent directions" not in (res.message or "")


def test_informed_designs_can_move_their_tool_in_every_direction(tmp_path):
    task = _full_pose_task(tmp_path)
    problem = Problem.build(task, load_module_set(HEAVY), "cyc")
    space: SearchSpace = problem.space
    assert space.goal_rank == 6
    rng = np.random.default_rng(0)
    uniform = [space.rank_deficit(space.random_order(rng)) == 0 for _ in range(60)]
    informed = [space.rank_deficit(space.informed_candidate(rng, orders=8).order) == 0 for _ in range(30)]
    # about a quarter of the uniform orders have rank 6; the best of 8 has one unless all 8 miss (0.75^8 = 10 %)
    assert 0.1 < np.mean(uniform) < 0.45
    assert np.mean(informed) >= 0.75
    # a position-only task needs no rank: no deficit for any order
    plain = Problem.build(_full_pose_task(tmp_path, full=False), load_module_set(HEAVY), "cyc").space
    assert plain.goal_rank == 0 and plain.rank_deficit("1,21,21,3,23,4,25,26,25,16".split(",")) == 0


# -- the check stage repairs a collision between samples ---------------------------------------------------
def test_a_collision_between_samples_is_repaired_by_timing_along_the_checked_segments(monkeypatch):
    """When the judge finds only collisions (its sweep of the continuous motion; the planner checks states
    0.01 rad apart and the time scaling's blends cut corners), the check stage times the moves again with every
    waypoint a stop (blend radius 0), and keeps the first motion the judge accepts. The first verdict is forged
    here (a collision the real judge would not find); the second is the real judge's."""
    from robodesign.core.defaults import DEFAULT_ORDER
    from robodesign.core.paths import builtin_tasks_dir
    from robodesign.design import solve as solve_module
    from robodesign.judge.checker import Violation

    task = load_task(builtin_tasks_dir() / "robodesign" / "pick_and_place.json")
    ms = load_module_set("robodesign_arm")
    honest = solve(task, ms, list(DEFAULT_ORDER), settings=SolveSettings(seed=0))
    assert honest.feasible, honest.message
    real = solve_module.check
    calls = []

    def forged(kind):
        return first_verdict_forged(real, calls, [Violation(kind, "forged contact between samples 3 and 4")])

    monkeypatch.setattr(solve_module, "check", forged("collisionFree"))
    res = solve(task, ms, list(DEFAULT_ORDER), settings=SolveSettings(seed=0))
    assert res.feasible and res.verdict.valid and len(calls) == 2
    first, second = calls
    # the repaired motion passes the same waypoints but stops at each: never faster than the blended one
    assert second.trajectory.t[-1] >= first.trajectory.t[-1] - 1e-12
    np.testing.assert_array_equal(second.trajectory.q[-1], first.trajectory.q[-1])
    # any other violation is the verdict at once: no retry
    calls.clear()
    monkeypatch.setattr(solve_module, "check", forged("joint.tau"))
    res = solve(task, ms, list(DEFAULT_ORDER), settings=SolveSettings(seed=0))
    assert not res.feasible and res.stage == "check" and len(calls) == 1


def test_a_goal_whose_chosen_configuration_cannot_be_reached_gets_another(monkeypatch):
    """The planner cannot reach the IK solution the sequencing chose for 'place' (forged: as when free space
    falls apart into pieces); the plan stage plans once more to any of the goal's IK solutions (the nearest
    others as further goal states), and the motion goes to the one the path reaches. The judge accepts the result; the solution reaches 'place' in a
    configuration other than the blocked one."""
    from robodesign.core.defaults import DEFAULT_ORDER
    from robodesign.core.paths import builtin_tasks_dir
    from robodesign.solvers import planning

    task = load_task(builtin_tasks_dir() / "robodesign" / "pick_and_place.json")
    ms = load_module_set("robodesign_arm")
    honest = solve(task, ms, list(DEFAULT_ORDER), settings=SolveSettings(seed=0))
    assert honest.feasible, honest.message
    tr = honest.solution.trajectory
    blocked = tr.q[int(np.argmin(np.abs(tr.t - tr.goal2time["place"])))].copy()
    real = planning.plan_path
    tried = []

    def plan_path(robot, q_start, q_goal, other_goals=(), **kw):
        """The real planner, with the blocked configuration taken out of the goals."""
        tried.append(np.array(q_goal))
        if not np.allclose(q_goal, blocked, atol=1e-12):
            return real(robot, q_start, q_goal, other_goals=other_goals, **kw)
        if not len(other_goals):
            return planning.PlanResult(np.zeros((0, robot.dof)), False, {"reason": "no_solution"})
        r = real(robot, q_start, other_goals[0], other_goals=other_goals[1:], **kw)
        r.stats["goal"] = r.stats.get("goal", 0) + 1  # index among (blocked, *other_goals)
        return r

    monkeypatch.setattr(planning, "plan_path", plan_path)
    res = solve(task, ms, list(DEFAULT_ORDER), settings=SolveSettings(seed=0))
    assert res.feasible and res.verdict.valid, res.message
    tr2 = res.solution.trajectory
    q_place = tr2.q[int(np.argmin(np.abs(tr2.t - tr2.goal2time["place"])))]
    assert not np.allclose(q_place, blocked, atol=1e-6)
    assert task.goal("place").pose.valid(res.quantities.tcp_poses[int(np.argmin(np.abs(tr2.t - tr2.goal2time["place"])))])
    assert any(np.allclose(q, blocked, atol=1e-12) for q in tried)  # the chosen one was tried first
    # without alternatives the stage fails
    res = solve(task, ms, list(DEFAULT_ORDER), settings=SolveSettings(seed=0, plan_alternatives=0))
    assert not res.feasible and res.stage == "plan"


def test_a_base_inside_an_obstacle_stops_at_the_base_stage():
    """Placed on the table (its base bodies inside the 0.2 m table box), the arm collides at every configuration:
    the base stage says so at once instead of the IK stage's 300 restarts ending in collisions. Independent: the
    robot collides with an obstacle at every one of 50 random configurations. Beside the table: no base
    collision, and the pipeline goes on."""
    from dataclasses import replace

    from robodesign.core.defaults import DEFAULT_ORDER
    from robodesign.core.paths import builtin_tasks_dir
    from robodesign.formats.assembly import Assembly
    from robodesign.model.cell import build_robot

    task = load_task(builtin_tasks_dir() / "robodesign" / "pick_and_place.json")
    task = replace(task, constraints=tuple(c for c in task.constraints if c.type != "basePlacement"))  # base free
    ms = load_module_set("robodesign_arm")
    on_table = np.eye(4)
    on_table[:3, 3] = (0.55, 0.0, 0.05)  # the table box spans z 0 … 0.2 around x = 0.55
    res = solve(task, ms, list(DEFAULT_ORDER), base_pose=on_table, settings=SolveSettings(seed=0))
    assert res.stage == "base" and "collides with table" in res.message, res.message
    robot = build_robot(task, ms, Assembly.from_order(ms, list(DEFAULT_ORDER)), on_table)
    assert robot.base_collisions() and robot.base_collisions()[0][1] == "obstacle:table.0.0"
    rng = np.random.default_rng(0)
    assert all(robot.collides_with_obstacles(robot.random_configuration(rng)) for _ in range(50))
    beside = build_robot(task, ms, Assembly.from_order(ms, list(DEFAULT_ORDER)), task.nominal_base_pose)
    assert beside.base_collisions() == []
    assert solve(task, ms, list(DEFAULT_ORDER), settings=SolveSettings(seed=0)).stage != "base"


def test_a_slight_torque_excess_of_the_judge_is_repaired_by_timing_slower(monkeypatch):
    """The time scaling checks torques at the samples; the judge certifies the motion between them and may find a
    little more (a Whitman2020 5/5 run: 150.117 Nm against 150). When torque excesses of at most 5 % are all the
    judge finds, the check stage times every goal's motion again at 0.97 of the joint speeds, and keeps the first
    motion the judge accepts. The first verdict is forged (the real judge accepts the motion); the second is the
    real judge's. An excess of 20 % is the verdict at once."""
    from robodesign.core.defaults import DEFAULT_ORDER
    from robodesign.core.paths import builtin_tasks_dir
    from robodesign.design import solve as solve_module
    from robodesign.judge.checker import Violation

    task = load_task(builtin_tasks_dir() / "robodesign" / "pick_and_place.json")
    ms = load_module_set("robodesign_arm")
    real = solve_module.check
    calls = []

    def forged(value):
        return first_verdict_forged(real, calls, [
            Violation("joint.tau", "forged", sample=10, value=value, bound=87.0, joint=1),
            Violation("joint.tau", "... and 3 more steps over the limit")])

    monkeypatch.setattr(solve_module, "check", forged(87.1))
    res = solve(task, ms, list(DEFAULT_ORDER), settings=SolveSettings(seed=0))
    assert res.feasible and res.verdict.valid and len(calls) == 2
    first, second = calls
    assert second.trajectory.t[-1] > first.trajectory.t[-1]  # slower
    for gid in ("pick", "place"):  # the same goal configurations, reached later
        k1 = int(np.argmin(np.abs(first.trajectory.t - first.trajectory.goal2time[gid])))
        k2 = int(np.argmin(np.abs(second.trajectory.t - second.trajectory.goal2time[gid])))
        np.testing.assert_allclose(second.trajectory.q[k2], first.trajectory.q[k1], atol=1e-9)
    calls.clear()
    monkeypatch.setattr(solve_module, "check", forged(87.0 * 1.2))
    res = solve(task, ms, list(DEFAULT_ORDER), settings=SolveSettings(seed=0))
    assert not res.feasible and res.stage == "check" and len(calls) == 1
