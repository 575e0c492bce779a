"""GoalPlanner remembers the moves it timed for its own robot (goal retries and a motion delayed as a whole time
every move again): the same trajectories as timing them afresh, bit for bit, and only the slowed moves timed again."""
import numpy as np
import pytest
from conftest import COBRA

ARM = ["1", "21", "4", "22", "5", "23", "12"]


@pytest.fixture(scope="module")
def planner():
    from robodesign.design.evaluator import evaluation_settings
    from robodesign.design.solve import GoalPlanner, SolveResult
    from robodesign.formats.assembly import Assembly
    from robodesign.formats.module_io import load_module_set
    from robodesign.formats.task_io import load_task
    from robodesign.model.cell import build_robot
    task = load_task(str(COBRA / "tasks" / "simple" / "PTP_3.json"))
    ms = load_module_set(str(COBRA / "modules" / "IMPROV"))
    robot = build_robot(task, ms, Assembly.from_order(ms, ARM), task.nominal_base_pose)
    gp = GoalPlanner(task, robot, evaluation_settings(seed=0), np.random.default_rng(0), SolveResult())
    gp.solve_ik()
    gp.filter_static_torque()
    gp.choose_and_plan()
    return gp


def _bytes(traj):
    return [x.tobytes() for x in (traj.t, traj.q, traj.dq, traj.ddq)]


def test_moves_are_timed_once_and_slowed_ones_again(planner, monkeypatch):
    from robodesign.design import goal_planner
    calls = []
    real = goal_planner.time_parameterize
    monkeypatch.setattr(goal_planner, "time_parameterize", lambda r, p, **kw: calls.append(r) or real(r, p, **kw))
    planner._timed_memo.clear()
    first, g2t = planner.timed_motion()
    moves = len(calls)
    assert moves >= 2 and all(r is planner.robot for r in calls)
    first.q[:] = 0.0   # the caller's copy: the remembered moves stay as they were timed
    again, g2t_again = planner.timed_motion()
    assert len(calls) == moves and g2t_again == g2t
    planner._timed_memo.clear()
    fresh, _ = planner.timed_motion()
    assert len(calls) == 2 * moves and _bytes(again) == _bytes(fresh)
    # a goal retry: only the slowed goal's move is timed again (with the slowed robot), the rest is remembered
    slow_goal = planner.actions[-1][2].id
    slowed, _ = planner.timed_motion(slow={slow_goal: 0.5})
    assert len(calls) == 2 * moves + 1 and calls[-1] is not planner.robot
    planner._timed_memo.clear()
    slowed_fresh, _ = planner.timed_motion(slow={slow_goal: 0.5})
    assert _bytes(slowed) == _bytes(slowed_fresh)


def test_the_remembered_moves_are_not_shared_with_the_motion(planner):
    """The moves are returned from the memo itself (no copy): the whole motion is made of new arrays, so writing
    into every array of it (and of the motion delayed as a whole) leaves every remembered move's bytes as they were,
    and timing the motion again gives the first motion's bytes."""
    planner._timed_memo.clear()
    first, g2t = planner.timed_motion()
    want = _bytes(first)
    kept = {k: _bytes(v) for k, v in planner._timed_memo.items()}
    assert kept
    for x in (first.t, first.q, first.dq, first.ddq):
        x[:] = -1.0
    whole, _ = planner.time_parameterize()
    for x in (whole.t, whole.q, whole.dq, whole.ddq):
        x[:] = -2.0
    assert {k: _bytes(v) for k, v in planner._timed_memo.items()} == kept
    again, g2t_again = planner.timed_motion()
    assert _bytes(again) == want and g2t_again == g2t
