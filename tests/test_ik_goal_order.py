"""The ik stage asks every goal for one IK solution before it collects any goal's others, and stops collecting at
the first goal the arm cannot hold against gravity (GoalPlanner.solve_ik / collect_ik). Each goal draws from a
random stream of its own (GoalPlanner.goal_rng), so the order of the work does not change what a goal finds.

Checked against an independent computation: for every IK search the stage makes, a second, complete search of the
same goal from the same stream (48 solutions, all restarts), made beside it. On a generated Whitman2020 task (five
goals, five obstacles, free base; the published variant) with random candidates of the built-in set, and on
PTP_3 with the known-good IMPROV arm."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import IMPROV, TASKS

from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.solvers import ik
from robodesign.solvers.lazy_rng import LazyGenerator

GOOD = ("1", "21", "4", "22", "5", "23", "12")   # experiments/profile_evaluator.GOOD


@pytest.fixture
def searches(monkeypatch):
    """Every IK search the ik stage makes: [search, its goal, the complete search beside it, the n of each run]."""
    made: list = []
    plain = ik.IKSearch

    class Watched(plain):
        def __init__(self, robot, goal, rng, **kw):
            super().__init__(robot, goal, rng, **kw)
            self.seed = rng._seed
            full = plain(robot, goal, LazyGenerator(rng._seed), **kw).run(48)
            self.record = [self, goal, full, []]
            made.append(self.record)

        def run(self, n):
            self.record[3].append(n)
            return super().run(n)
    monkeypatch.setattr(ik, "IKSearch", Watched)
    return made


def _same(a, b) -> bool:
    return len(a) == len(b) and all(x.tobytes() == y.tobytes() for x, y in zip(a, b))


def _held(robot, sols):
    """(the solutions held within the torque limits at rest, the smallest excess over the limit) — by hand."""
    taus = [np.abs(robot.gravity_torque(q)) for q in sols]
    ok = [q for q, t in zip(sols, taus) if np.all(t <= robot.tau_max)]
    return ok, min(float(np.max(t - robot.tau_max)) for t in taus)


def test_failures_at_later_goals_are_those_of_complete_searches(searches, tmp_path, monkeypatch):
    from robodesign.design import goal_planner
    from robodesign.generate.registry import generate
    robots = []
    real = goal_planner.GoalPlanner.solve_ik

    def keep_robot(self):
        robots.append(self.robot)
        return real(self)
    monkeypatch.setattr(goal_planner.GoalPlanner, "solve_ik", keep_robot)
    f = generate("whitman2020", tmp_path, 1, 7, {"goals": 5, "obstacles": 5, "base": "xyz_any_rot",
                                                 "variant": "published"})[0]
    problem = Problem.build(f, "robodesign_arm", "cyc")
    ev = Evaluator(EvaluatorSpec(problem, seed=0))
    rng = np.random.default_rng(0)
    late_ik = torque = 0
    for _ in range(600):
        searches.clear()
        robots.clear()
        e = ev.evaluate(problem.space.random_candidate(rng))
        if not searches:
            continue
        if e.stage == "ik":
            # the failing goal's search found nothing in all its restarts; every goal before it has solutions, and
            # the stage took only the first one of each (no goal was collected)
            *before, last = searches
            assert last[2].solutions == [] and last[0].finished and last[3] == [1]
            assert all(r[2].solutions and r[3] == [1] for r in before)
            assert all(_same(r[0].solutions, r[2].solutions[:1]) for r in before)
            assert e.goals_reached == len(before)
            assert f"({last[2].stats['reason']})" in e.message
            late_ik += len(before) > 0
        elif e.stage == "static_torque":
            # collected goal by goal: the first goal none of whose solutions the arm holds is the last one collected
            collected = [r for r in searches if 48 in r[3]]
            held = [_held(robots[0], r[2].solutions) for r in collected]
            assert [bool(ok) for ok, _ in held] == [True] * (len(held) - 1) + [False]
            assert all(_same(r[0].solutions, r[2].solutions) for r in collected)
            assert e.shortfall == held[-1][1]
            torque += len(collected) < len(searches)   # goals after it were never collected
        if late_ik >= 3 and torque >= 2:
            break
    assert late_ik >= 3 and torque >= 2, (late_ik, torque)


def test_a_feasible_design_gets_every_goals_complete_search(searches):
    problem = Problem.build(TASKS / "simple" / "PTP_3.json", IMPROV, "cyc")
    for seed in (1, 2):
        searches.clear()
        e = Evaluator(EvaluatorSpec(problem, seed=seed)).evaluate(Candidate(GOOD))
        assert e.feasible and len(searches) == 3
        for search, goal, full, runs in searches:
            assert runs == [1, 48]                        # first one solution, later the rest
            assert _same(search.solutions, full.solutions)
            assert search.stats["attempts"] == full.stats["attempts"] == 150
        # each goal has its own stream
        assert len({tuple(s[0].seed) for s in searches}) == 3
