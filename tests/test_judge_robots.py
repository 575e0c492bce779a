"""The judge's robots kept per task (judge/robots.py, issue 25): every verdict of a check on a robot taken back from
the task's pool equals, bit for bit, the verdict of the former check on a freshly built robot
(model.cell.solution_robot), over a seeded mix of base poses, assemblies, motions into the obstacles, too fast
motions and a moving obstacle, judged in an order that hands each robot from one base pose and motion to another."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from test_sweep_clearance import _into_obstacle

import make_tasks as mt  # assets/tasks, on the path by conftest
from robodesign import load_module_set
from robodesign.design.solve import solve
from robodesign.formats.solution import Trajectory
from robodesign.formats.task_io import load_task
from robodesign.judge import checker, robots
from robodesign.model import cell


def _rz(angle: float, dx: float, dy: float) -> np.ndarray:
    """A base pose turned by ``angle`` about z and moved by (dx, dy)."""
    T = np.eye(4)
    c, s = math.cos(angle), math.sin(angle)
    T[:2, :2] = [[c, -s], [s, c]]
    T[:2, 3] = dx, dy
    return T


def _faster(sol, factor: float):
    """``sol`` timed ``factor`` times faster (the same path: velocities ×factor, accelerations ×factor²)."""
    tr = sol.trajectory
    return sol.with_(trajectory=Trajectory(tr.t / factor, tr.q, tr.dq * factor, tr.ddq * factor ** 2,
                                           {g: t / factor for g, t in tr.goal2time.items()}))


def _fresh_verdict(task, sol, ms):
    """The former check: a robot built for this check alone (cell.solution_robot), no pool kept."""
    robots._POOLS.clear()
    orig = robots.take
    robots.take = lambda t, s, m=None: cell.solution_robot(t, s, m)
    try:
        return checker.check(task, sol, ms)
    finally:
        robots.take = orig
        robots._POOLS.clear()


def _key(v) -> str:
    """A verdict's every field but its timings, numbers as JSON writes them (repr: bit for bit)."""
    d = v.to_json()
    d.pop("timings")
    return json.dumps(d, sort_keys=True)


def _variants(task, ms, sol):
    """A seeded mix of solutions of ``task``: base poses moved and turned, another assembly, motions moved into the
    obstacles, motions timed faster (torque and speed violations)."""
    rng = np.random.default_rng(25)
    base = np.asarray(sol.base_pose, dtype=float)
    out = [sol]
    for _ in range(4):
        out.append(sol.with_(base_pose=_rz(rng.uniform(-0.05, 0.05), *rng.uniform(-0.03, 0.03, 2)) @ base))
    out.append(sol.with_(module_order=("1", "21", "5", "22", "4", "23", "12")))   # another arm, the same dof
    robot = cell.solution_robot(task, sol, ms)
    Q0 = np.asarray(sol.trajectory.q)
    for k in (60, 175, 290):
        hit = _into_obstacle(robot, Q0, k)
        if hit is not None:
            Q = Q0.copy()
            Q[k] = hit[0]
            tr = sol.trajectory
            out.append(sol.with_(trajectory=Trajectory(tr.t, Q, tr.dq, tr.ddq, tr.goal2time)))
    out += [_faster(sol, f) for f in (1.6, 3.0)]
    return out


def test_pooled_robots_give_the_fresh_robots_verdicts(ptp3_solved):
    task, ms, sol = ptp3_solved
    sols = _variants(task, ms, sol)
    expected = [_key(_fresh_verdict(task, s, ms)) for s in sols]
    invalid = sum('"valid": false' in e for e in expected)
    assert invalid >= 4 and len(set(expected)) == len(expected)
    robots._POOLS.clear()
    order = np.random.default_rng(7).permutation(np.tile(np.arange(len(sols)), 3))
    for i in order:
        assert _key(checker.check(task, sols[i], ms)) == expected[i], i
    assert robots._POOLS.get(task) is not None and robots._POOLS[task]._count >= 1


def test_a_robot_is_lent_once_and_kept_only_after_its_check_returned(ptp3_solved, monkeypatch):
    task, ms, sol = ptp3_solved
    robots._POOLS.clear()
    first = robots.take(task, sol, ms)
    assert robots._POOLS.get(task) is None        # the first robot of a task: built as before, no pool yet
    robots.give_back(task, first)
    again, other = robots.take(task, sol, ms), robots.take(task, sol, ms)
    assert again is first and other is not first   # a kept robot is lent to one check at a time
    robots.give_back(task, again)
    monkeypatch.setattr(checker, "_judge", lambda *a: 1 / 0)
    with pytest.raises(ZeroDivisionError):
        checker.check(task, sol, ms)
    assert robots.take(task, sol, ms) is not first   # the robot of a check that raised is dropped
    robots._POOLS.clear()


def test_a_moving_obstacle_is_judged_as_on_a_fresh_robot():
    ms = load_module_set("robodesign_arm")
    task = load_task("robodesign/wait_for_shuttle")
    res = solve(task, ms, list(mt.DEFAULT_ORDER), base_pose=mt.base_pose("wait_for_shuttle"))
    assert res.feasible, res.message
    sol = res.solution
    tr = sol.trajectory
    early = sol.with_(trajectory=Trajectory(tr.t * 0.5, tr.q, tr.dq * 2, tr.ddq * 4,
                                            {g: t * 0.5 for g, t in tr.goal2time.items()}))
    sols = [sol, early, sol, early]
    expected = [_key(_fresh_verdict(task, s, ms)) for s in sols]
    assert '"valid": true' in expected[0] and '"valid": false' in expected[1]
    robots._POOLS.clear()
    for s, e in zip(sols, expected):
        assert _key(checker.check(task, s, ms)) == e
    robots._POOLS.clear()
