"""A solution's q, dq, ddq and t must describe one motion (issue 13; docs/checker.md, "One motion").

Regression: a valid PTP_3 solution with 0.5 rad added to joint 1's q for samples 100-149 (dq, ddq left as
they are) is INVALID, naming the two steps where q jumps. Honest solutions stay valid: robodesign's own
(every timing method; the built-in tasks are covered by test_builtin_tasks, whose solves end in a check),
the same solution with dq/ddq filled by numpy.gradient as the reference reads files without them, and
reference-style from_mstraj trapezoids.
"""
import json

import numpy as np
import pytest

from robodesign.judge.checker import check
from robodesign.cli.entry import main
from robodesign.formats.module_io import load_module_set
from robodesign.judge.quantities import DQ_RULE_FACTOR, Q_RULE_FACTOR, RULE_ATOL, RULE_RTOL, step_residuals
from robodesign.formats.solution import SolutionTrajectory, load_solution
from robodesign.design.solve import SolveSettings, solve
from robodesign.formats.task_io import load_task

from conftest import IMPROV, TASKS
from reference_trajectories import mstraj_like

ORDER = ["1", "21", "4", "22", "5", "23", "12"]


@pytest.fixture(scope="module")
def ptp3():
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    res = solve(task, ms, ORDER, settings=SolveSettings(seed=0))
    assert res.feasible, res.message
    return task, ms, res.solution


def with_arrays(sol, **kw):
    tr = sol.trajectory
    a = {k: kw.get(k, getattr(tr, k)) for k in ("t", "q", "dq", "ddq")}
    return sol.with_(trajectory=SolutionTrajectory(a["t"], a["q"], a["dq"], a["ddq"], dict(tr.goal2time)))


def test_rules_by_hand():
    # constant acceleration a = 2 from rest, h = 0.1: q = t², dq = 2t, ddq = 2: both rules hold exactly
    t = np.array([0.0, 0.1, 0.2])
    st = step_residuals(t, (t ** 2)[:, None], (2 * t)[:, None], np.full((3, 1), 2.0))
    np.testing.assert_allclose(st.q, 0, atol=1e-15)
    np.testing.assert_allclose(st.dq, 0, atol=1e-15)
    # A = 2 (max |ddq| and |Δdq|/h): q tolerance 0.6·2·0.01 + 1e-9 + 1e-9·|Δq|
    np.testing.assert_allclose(st.q_tol[:, 0], [Q_RULE_FACTOR * 2 * 0.01 + RULE_ATOL + RULE_RTOL * 0.01,
                                                Q_RULE_FACTOR * 2 * 0.01 + RULE_ATOL + RULE_RTOL * 0.03])
    np.testing.assert_allclose(st.dq_tol[:, 0], DQ_RULE_FACTOR * 2 * 0.1 + RULE_ATOL + RULE_RTOL * 0.2)
    np.testing.assert_allclose(st.mean_velocity[:, 0], [0.1, 0.3])
    np.testing.assert_allclose(st.mean_acceleration[:, 0], [2.0, 2.0])
    # a teleport: q jumps by 0.5 with dq = 0 → residual 0.5 ≫ tolerance (A = 0: slack only)
    st = step_residuals([0.0, 0.01], [[0.0], [0.5]], [[0.0], [0.0]], [[0.0], [0.0]])
    assert st.q[0, 0] == 0.5 and st.q_tol[0, 0] == pytest.approx(RULE_ATOL + RULE_RTOL * 0.5)
    # under-reported accelerations: true a = 2 everywhere, the file says 1 → Δdq = 0.2 vs h·1 = 0.1
    t = np.arange(5) * 0.1
    st = step_residuals(t, (t ** 2)[:, None], (2 * t)[:, None], np.full((5, 1), 1.0))
    assert np.all(np.abs(st.dq) > st.dq_tol)  # 0.1 > 0.3·2·0.1 = 0.06 (A = 2 from Δdq/h)


def test_teleport_is_invalid_and_names_the_samples(ptp3, tmp_path, capsys):
    task, ms, sol = ptp3
    v = check(task, sol, ms)
    assert v.valid, [str(x) for x in v.violations]
    assert max(step_residuals(sol.trajectory.t, sol.trajectory.q, sol.trajectory.dq,
                              sol.trajectory.ddq).worst_ratio) < 1e-6  # robodesign writes the rules exactly
    q = sol.trajectory.q.copy()
    assert len(q) > 160
    q[100:150, 0] += 0.5
    bad = with_arrays(sol, q=q)
    v = check(task, bad, ms)
    assert not v.valid
    tele = [x for x in v.violations if x.constraint == "trajectory.q"]
    assert [(x.sample, x.joint) for x in tele] == [(99, 0), (149, 0)]
    assert tele[0].value == pytest.approx(0.5, abs=0.05) and tele[1].value == pytest.approx(-0.5, abs=0.05)
    assert "between samples 99 and 100" in tele[0].message and "between samples 149 and 150" in tele[1].message
    # without the one-motion rules (what the reference does) only qDist notices
    from robodesign.judge.checker import CheckSettings
    assert check(task, bad, ms, CheckSettings(one_motion=False)).valid
    # the CLI says INVALID (exit 1) and names the samples
    f = tmp_path / "teleport.json"
    f.write_text(bad.to_json() if isinstance(bad.to_json(), str) else json.dumps(bad.to_json()))
    code = main(["check", str(TASKS / "simple" / "PTP_3.json"), str(f), "--modules", str(IMPROV)])
    out = capsys.readouterr().out
    assert code == 1 and "INVALID" in out.upper() and "between samples 99 and 100" in out


def test_gradient_filled_solution_is_one_motion(ptp3, tmp_path):
    """The reference fills missing dq/ddq with numpy.gradient: robodesign's q alone, read that way, passes
    the one-motion rules. (The central difference is not 0 where the motion stops for a reach goal without a
    pause, so those goals fail, in the reference too: the test after this one adds the pauses.)"""
    task, ms, sol = ptp3
    d = sol.to_json() if isinstance(sol.to_json(), dict) else json.loads(sol.to_json())
    del d["trajectory"]["dq"], d["trajectory"]["ddq"]
    f = tmp_path / "q_only.json"
    f.write_text(json.dumps(d))
    sol2 = load_solution(f)
    np.testing.assert_allclose(sol2.trajectory.dq, np.gradient(sol.trajectory.q, sol.trajectory.t, axis=0))
    v = check(task, sol2, ms)
    assert not [str(x) for x in v.violations if x.constraint.startswith("trajectory.")]
    assert {x.constraint for x in v.violations} == {"goal"}
    assert all("still moving" in x.message for x in v.violations)
    assert max(step_residuals(sol2.trajectory.t, sol2.trajectory.q, sol2.trajectory.dq,
                              sol2.trajectory.ddq).worst_ratio) <= 1.0


def test_reference_style_trapezoids_are_valid(ptp3):
    """from_mstraj-style rest-to-rest trapezoids between the goal configurations (straight in joint space,
    at 90 % of the velocity limit, blends within the acceleration limit), with two samples at rest around
    each goal (Trajectory.stationary), concatenated, dq/ddq by numpy.gradient over the whole: valid."""
    task, ms, sol = ptp3
    tr = sol.trajectory
    from robodesign.model.cell import solution_robot
    robot = solution_robot(task, sol, ms)
    stops = [tr.q[0]] + [tr.q[int(np.argmin(np.abs(tr.t - tr.goal2time[g])))] for g in task.goal_order]
    dt = task.dt
    qd = 0.9 * float(np.min(robot.dq_max))
    t_all, q_all = [dt * np.arange(3)], [np.repeat(stops[0][None], 3, axis=0)]
    g2t = {task.goal_order[0]: dt}  # goal 1 is where the motion starts
    for gid, a, b in zip(task.goal_order[1:], stops[1:], stops[2:]):
        t_acc = dt * np.ceil(1.2 * qd / float(np.min(robot.ddq_max)) / dt)  # blends below the acceleration limit
        t, q, _, _, amax, _ = mstraj_like(np.vstack([a, b]), qd, t_acc, dt)
        assert np.all(amax <= robot.ddq_max)
        np.testing.assert_allclose(q[-1], b, atol=1e-12)
        t = np.concatenate([t, t[-1] + dt * np.arange(1, 3)])  # at rest for two more samples
        q = np.vstack([q, q[-1:], q[-1:]])
        t_all.append(t[1:] + t_all[-1][-1])
        q_all.append(q[1:])
        g2t[gid] = float(t_all[-1][-2])  # the middle one of the three samples at rest
    t, q = np.concatenate(t_all), np.vstack(q_all)
    dq = np.gradient(q, t, axis=0)
    ddq = np.gradient(dq, t, axis=0)
    ref = sol.with_(trajectory=SolutionTrajectory(t, q, dq, ddq, g2t))
    v = check(task, ref, ms)
    assert v.valid, [str(x) for x in v.violations]
    assert max(step_residuals(t, q, dq, ddq).worst_ratio) <= 1.0


def test_random_reference_style_trajectories_pass_the_rules():
    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(300):
        dt = float(rng.choice([0.001, 0.005, 0.01, 0.02]))
        t_acc = float(rng.uniform(dt, 0.8))
        t, q, dq, ddq, _, _ = mstraj_like(rng.uniform(-2, 2, (int(rng.integers(2, 5)), 3)),
                                          float(rng.uniform(0.3, 3)), t_acc, dt)
        worst = max(worst, *step_residuals(t, q, dq, ddq).worst_ratio)
    assert 0.5 < worst <= 1.0  # they do use the slack (the rules are not trivially loose)


@pytest.mark.slow
@pytest.mark.parametrize("timing, optimize, cost", [("ruckig", False, "cyc"), ("toppra", True, "mechEnergy")])
def test_every_solver_writes_one_motion(timing, optimize, cost):
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    res = solve(task, ms, ORDER, cost=cost, settings=SolveSettings(seed=0, timing=timing,
                                                                   optimize_trajectory=optimize))
    assert res.feasible, res.message
    tr = res.solution.trajectory
    assert max(step_residuals(tr.t, tr.q, tr.dq, tr.ddq).worst_ratio) < 1e-6
