"""``robodesign optimize --workers N``: the same seed and batch size give the same result for any N."""
import json
import subprocess
import sys

import pytest

from conftest import IMPROV, TASKS
from robodesign.checker import check
from robodesign.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
from robodesign.experiment.executors import ProcessPool
from robodesign.optimize import Budget, SerialExecutor, Study, create_optimizer
from robodesign.problem import Problem
from robodesign.solution import load_solution
from robodesign.task_io import load_task

PTP3 = TASKS / "simple" / "PTP_3.json"
RD = [sys.executable, "-m", "robodesign.cli"]


def _history(executor, problem):
    opt = create_optimizer("genetic", problem, seed=3, options={"population_size": 8})
    res = Study(opt, executor, Budget(evaluations=24), batch_size=6).run()
    return [(e.candidate.key(), e.feasible, e.stage, e.cost, e.goals_reached) for e in res.history]


@pytest.mark.slow
def test_process_pool_gives_the_serial_history(tmp_path):
    """Every evaluation (candidate, stage reached, cost) of a genetic run is the same on 2 worker processes
    as in this process."""
    problem = Problem.build(str(PTP3), str(IMPROV), "cyc")
    spec = EvaluatorSpec(problem, evaluation_settings(), seed=3)
    serial = _history(SerialExecutor(Evaluator(spec)), problem)
    with ProcessPool({"s": spec}, 2) as pool:
        parallel = _history(pool.bind("s"), problem)
        assert pool.workers == 2
    assert len(serial) == 24 and parallel == serial
    assert len({k for k, *_ in serial}) > 8  # the genetic search moved beyond its first generation


@pytest.mark.slow
def test_cli_workers_2_equals_workers_1(tmp_path):
    outs = {}
    for w in (1, 2):
        r = subprocess.run(RD + ["optimize", str(PTP3), "--modules", str(IMPROV), "--optimizer", "genetic",
                                 "--budget", "32evals", "--seed", "3", "--batch-size", "8", "--workers", str(w),
                                 "--json", "--out", str(tmp_path / f"best{w}.json")],
                           capture_output=True, text=True, timeout=600)
        assert r.returncode in (0, 1), r.stderr
        outs[w] = json.loads(r.stdout)
    one, two = outs[1], outs[2]
    assert (one["workers"], two["workers"]) == (1, 2) and one["batch_size"] == two["batch_size"] == 8
    assert one["evaluations"] == two["evaluations"] == 32
    assert one["best"] == two["best"] and one["feasible"] == two["feasible"]
    if one["feasible"]:
        files = [json.loads((tmp_path / f"best{w}.json").read_text()) for w in (1, 2)]
        for f in files:
            f.pop("computationTime")  # wall time of the search, the one field that may differ
        assert files[0] == files[1]
        # the reported cost is the checker's on the written file
        verdict = check(load_task(PTP3), load_solution(tmp_path / "best2.json"), IMPROV)
        assert verdict.valid and verdict.cost == pytest.approx(two["best"]["cost"], rel=1e-9)


@pytest.mark.parametrize("args,msg", [(["--workers", "0"], "--workers must be at least 1, got 0"),
                                      (["--batch-size", "0"], "--batch-size must be at least 1, got 0")])
def test_bad_workers_and_batch_size(capsys, args, msg):
    from robodesign.cli import main
    code = main(["optimize", str(PTP3), "--modules", str(IMPROV), "--budget", "2evals", *args])
    err = capsys.readouterr().err
    assert code == 2 and msg in err and "Traceback" not in err


def test_bound_executor_sends_each_candidate_to_the_workers_once():
    """Repeats (within a batch or from an earlier one) come from the driver's cache, as in-process."""
    from robodesign.evaluator import Evaluation
    from robodesign.experiment.executors import EvaluatorPool
    from robodesign.search_space import Candidate

    class Counting(EvaluatorPool):
        sent = []

        def map(self, spec_id, candidates):
            self.sent.append([c.key() for c in candidates])
            return [Evaluation(candidate=c, feasible=False, cost=None, score=float(len(c.order)), stage="ik",
                               stage_index=3, goals_reached=0, seconds=0.0, seed=0) for c in candidates]

    a, b, c = (Candidate(tuple(o), ()) for o in (["1", "21", "12"], ["1", "22", "12"], ["1", "21", "4", "12"]))
    ex = Counting({"s": None}).bind("s")
    first = ex.map([a, b, a, c])
    second = ex.map([c, b])
    assert Counting.sent == [[a.key(), b.key(), c.key()]]
    assert [e.candidate.key() for e in first] == [a.key(), b.key(), a.key(), c.key()] and first[0] is first[2]
    assert second[0] is first[3] and second[1] is first[1] and [e.score for e in first] == [3.0, 3.0, 3.0, 4.0]
    d = Candidate(("1", "23", "12"), ())
    ex.map([a, d])
    assert Counting.sent == [[a.key(), b.key(), c.key()], [d.key()]]
