"""solvers.ik.IKSearch: a search that stops at its first solution and goes on later finds, bit for bit, what one
solve_ik call finds, also when other goals' searches run in between (each draws from its own generator). On the
IMPROV arm of the PTP_3 benchmark solutions and PTP_3's goals."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import IMPROV, TASKS

from robodesign.core.errors import InputError
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.formats.tolerance import ToleratedPose
from robodesign.model.robot import Robot
from robodesign.solvers.ik import IKSearch, solve_ik

GOOD = ["1", "21", "4", "22", "5", "23", "12"]   # experiments/profile_evaluator.GOOD


@pytest.fixture(scope="module")
def arm_and_goals():
    robot = Robot.from_order(load_module_set(IMPROV), GOOD)
    task = load_task(TASKS / "simple" / "PTP_3.json")
    return robot, [g.pose for g in task.goals]


def _same(a, b) -> bool:
    return len(a) == len(b) and all(x.tobytes() == y.tobytes() for x, y in zip(a, b))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_first_solution_then_the_rest_is_one_call_bit_for_bit(arm_and_goals, seed):
    robot, goals = arm_and_goals
    whole = [solve_ik(robot, g, rng=seed * 10 + i, max_restarts=150, n_solutions=48) for i, g in enumerate(goals)]
    # every goal's first solution, then every goal's others: the searches interleave
    searches = [IKSearch(robot, g, rng=seed * 10 + i, max_restarts=150) for i, g in enumerate(goals)]
    firsts = [s.run(1) for s in searches]
    rest = [s.run(48) for s in searches]
    assert sum(len(w.solutions) for w in whole) > len(goals)   # there are solutions left to collect
    for w, f, r in zip(whole, firsts, rest):
        assert _same(f.solutions, w.solutions[:1])
        assert f.stats["reason"] == "found"
        assert _same(r.solutions, w.solutions)
        for key in ("attempts", "iterations", "converged", "rejected_collision", "rejected_duplicate", "repairs",
                    "reason"):
            assert r.stats[key] == w.stats[key], key
    # a result is a copy: going on does not change what an earlier run returned
    assert all(len(f.solutions) == 1 for f in firsts)


def test_a_finished_search_stays_finished(arm_and_goals):
    robot, goals = arm_and_goals
    s = IKSearch(robot, goals[0], rng=5, max_restarts=20)
    r = s.run(1000)
    assert s.finished and r.stats["reason"] == "max_restarts" and r.stats["attempts"] == 20
    again = s.run(1000)
    assert _same(again.solutions, r.solutions) and again.stats["attempts"] == 20
    assert r.solutions == [] or np.all(np.isfinite(r.solutions[0]))


def test_an_unreachable_goal_ends_at_once(arm_and_goals):
    robot, goals = arm_and_goals
    g = goals[0]
    nominal = g.nominal.copy()
    nominal[:3, 3] += np.array([30.0, 0.0, 0.0])             # 30 m away: the reach bounds prove it
    far = ToleratedPose(nominal, g.projections, g.intervals, g.frames)
    s = IKSearch(robot, far, rng=0, max_restarts=150)
    r = s.run(1)
    assert s.finished and r.solutions == [] and r.stats["attempts"] == 0
    assert r.stats["reason"] == solve_ik(robot, far, rng=0, max_restarts=150).stats["reason"] == "out_of_reach"


def test_bad_arguments_are_refused_when_the_search_is_made(arm_and_goals):
    robot, goals = arm_and_goals
    with pytest.raises(InputError, match="q_seed must have 6 values"):
        IKSearch(robot, goals[0], q_seed=np.zeros(3))
    with pytest.raises(InputError, match="saturate"):
        IKSearch(robot, goals[0], saturate=-1)
    with pytest.raises(InputError, match="n_solutions"):
        solve_ik(robot, goals[0], n_solutions=0)
