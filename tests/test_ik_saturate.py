"""solve_ik's ``saturate``: a goal's collecting stops at the saturate-th duplicate since its last new solution, and
what it returns is what the full search found up to that attempt. Checked against a full search's recorded
verdicts (the same seed draws the same starts), on the IMPROV arm the PTP_3 benchmark solutions use."""
from __future__ import annotations

import numpy as np
import pytest

from robodesign.design.evaluator import evaluation_settings
from robodesign.design.stages import SolveSettings
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.model.robot import Robot
from robodesign.solvers import ik
from robodesign.solvers.ik import solve_ik

from conftest import IMPROV, TASKS

GOOD = ["1", "21", "4", "22", "5", "23", "12"]   # experiments/profile_evaluator.GOOD


@pytest.fixture
def verdicts(monkeypatch):
    """Every verdict of the Acceptance objects solve_ik makes, in order."""
    log: list = []

    class Recorded(ik.Acceptance):
        def __call__(self, q):
            v = super().__call__(q)
            log.append(v)
            return v
    monkeypatch.setattr(ik, "Acceptance", Recorded)
    return log


def expected_stop(log: list, k: int):
    """The number of verdicts a search stopping at the k-th duplicate since the last new solution sees, or None
    when the full search never gets there."""
    repeats = 0
    for i, v in enumerate(log):
        if v == "added":
            repeats = 0
        elif v == "duplicate":
            repeats += 1
            if repeats == k:
                return i + 1
    return None


@pytest.mark.parametrize("k", [3, 8])
def test_saturated_search_is_the_full_search_cut_at_the_kth_repeat(verdicts, k):
    robot = Robot.from_order(load_module_set(IMPROV), GOOD)
    task = load_task(TASKS / "simple" / "PTP_3.json")
    stopped = saved = 0
    for goal in (g.pose for g in task.goals):
        for seed in range(3):
            verdicts.clear()
            full = solve_ik(robot, goal, rng=seed, max_restarts=150, n_solutions=48)
            log = list(verdicts)
            assert log.count("added") == len(full.solutions)
            verdicts.clear()
            cut = solve_ik(robot, goal, rng=seed, max_restarts=150, n_solutions=48, saturate=k)
            stop = expected_stop(log, k)
            if stop is None:
                assert cut.stats["reason"] == full.stats["reason"]
                assert verdicts == log
                assert cut.stats["attempts"] == full.stats["attempts"]
            else:
                stopped += 1
                assert cut.stats["reason"] == "saturated"
                assert verdicts == log[:stop]
                assert cut.stats["rejected_duplicate"] >= k
                saved += full.stats["attempts"] - cut.stats["attempts"]
            assert len(cut.solutions) == log[:len(verdicts)].count("added")
            for a, b in zip(cut.solutions, full.solutions):
                assert np.array_equal(a, b)
            for q in cut.solutions:   # each a solution of the goal (an independent forward kinematics)
                assert goal.valid(robot.fk(q))
    assert stopped >= 3 and saved > 50 * stopped   # it stops, and early: the later restarts only repeat


def test_saturate_off_is_the_plain_search(verdicts):
    robot = Robot.from_order(load_module_set(IMPROV), GOOD)
    goal = load_task(TASKS / "simple" / "PTP_3.json").goals[0].pose
    a = solve_ik(robot, goal, rng=4, max_restarts=60, n_solutions=48)
    b = solve_ik(robot, goal, rng=4, max_restarts=60, n_solutions=48, saturate=0)
    assert a.stats["attempts"] == b.stats["attempts"] == 60 and a.stats["reason"] == "max_restarts"
    assert all(np.array_equal(x, y) for x, y in zip(a.solutions, b.solutions)) and len(a.solutions) == len(b.solutions)


def test_off_by_default_and_on_from_a_config(tmp_path):
    """Off for searches and single solves (it costs the best designs a little: docs/benchmarks.md); an experiment
    config's ``solve`` section turns it on."""
    from robodesign.experiment.config import load_experiment
    assert evaluation_settings().ik_saturate == 0 and SolveSettings().ik_saturate == 0
    cfg = tmp_path / "exp.yaml"
    cfg.write_text(f"tasks: [{{task: {TASKS / 'simple' / 'PTP_3.json'}}}]\nmodules: {IMPROV}\n"
                   "optimizers: [random]\nbudget: 10evals\nsolve: {ik_saturate: 8}\n")
    exp = load_experiment(cfg)[0]
    assert exp.solve.ik_saturate == 8 and exp.solve.ik_restarts == 150


def test_the_evaluator_passes_it_on(monkeypatch):
    """An evaluation with ``ik_saturate`` = 8 stops its goals' collecting there (the IK searches it makes and
    their last runs, recorded)."""
    from robodesign.design.evaluator import Candidate, Evaluator, EvaluatorSpec
    from robodesign.design.problem import Problem
    runs: dict = {}

    class Recorded(ik.IKSearch):
        def run(self, n):
            r = super().run(n)
            runs[id(self)] = (self._saturate, n, r.stats["reason"], r.stats["attempts"])
            return r

        def __init__(self, *a, saturate=0, **kw):
            super().__init__(*a, saturate=saturate, **kw)
            self._saturate = saturate
    monkeypatch.setattr(ik, "IKSearch", Recorded)
    problem = Problem.build(TASKS / "simple" / "PTP_3.json", IMPROV, "cyc")
    for k in (0, 8):
        runs.clear()
        e = Evaluator(EvaluatorSpec(problem, settings=evaluation_settings(ik_saturate=k), seed=1)).evaluate(
            Candidate(tuple(GOOD)))
        calls = list(runs.values())
        assert e.feasible and len(calls) == 3 and all(c[0] == k and c[1] == 48 for c in calls)
        reasons = {c[2] for c in calls}
        assert reasons == ({"max_restarts"} if k == 0 else {"saturated"})
        assert all(c[3] == 150 for c in calls) == (k == 0)


def test_a_negative_setting_is_an_error_naming_the_field(tmp_path):
    from robodesign.core.errors import InputError
    from robodesign.design.stages import check_settings
    from robodesign.experiment.config import load_experiment
    with pytest.raises(InputError, match="saturate must be 0"):
        solve_ik(Robot.from_order(load_module_set(IMPROV), GOOD),
                 load_task(TASKS / "simple" / "PTP_3.json").goals[0].pose, rng=0, saturate=-1)
    with pytest.raises(InputError, match="--ik-saturate: must be a whole number"):
        check_settings(SolveSettings(ik_saturate=-2))
    cfg = tmp_path / "exp.yaml"
    cfg.write_text(f"tasks: [{{task: {TASKS / 'simple' / 'PTP_3.json'}}}]\nmodules: {IMPROV}\n"
                   "optimizers: [random]\nsolve: {ik_saturate: -1}\n")
    with pytest.raises(InputError) as e:
        load_experiment(cfg)
    assert "exp.yaml" in str(e.value) and "solve.ik_saturate" in str(e.value)
