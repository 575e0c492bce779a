"""``robodesign optimize --workers N``: the same seed and batch size give the same result for any N, with the
candidates sent to the workers in chunks (fewer messages) and, for random search, asked ahead of the tells."""
import json
import subprocess
import sys

import pytest

from conftest import IMPROV, TASKS
from robodesign.judge.checker import check
from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
from robodesign.experiment.executors import ProcessPool, auto_chunk_size, chunk_sizes
from robodesign.design.optimize import Budget, SerialExecutor, Study, create_optimizer
from robodesign.design.problem import Problem
from robodesign.formats.solution import load_solution
from robodesign.formats.task_io import load_task

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


def _spy(pool):
    """The sizes of the chunks ``pool`` sends to its workers, counted where they are handed to the
    ProcessPoolExecutor (one message per call)."""
    sent = []
    submit = pool._pool.submit

    def counting(fn, *args):
        sent.append(len(args[1]))
        return submit(fn, *args)
    pool._pool.submit = counting
    return sent


@pytest.mark.slow
def test_chunked_pool_gives_the_serial_history_in_fewer_messages():
    """Batches (genetic) and the ask-ahead stream (random) give the serial evaluations, candidate by
    candidate, whether each candidate travels alone or in chunks; chunks are fewer messages."""
    problem = Problem.build(str(PTP3), str(IMPROV), "cyc")
    spec = EvaluatorSpec(problem, evaluation_settings(), seed=3)

    def random_history(executor):
        res = Study(create_optimizer("random", problem, seed=3), executor, Budget(evaluations=32),
                    batch_size=16).run()
        return [(e.candidate.key(), e.feasible, e.stage, e.cost, e.goals_reached) for e in res.history]

    serial = {"genetic": _history(SerialExecutor(Evaluator(spec)), problem),
              "random": random_history(SerialExecutor(Evaluator(spec)))}
    assert len(serial["random"]) == 32 and len({k for k, *_ in serial["random"]}) == 32
    with ProcessPool({"s": spec}, 2) as auto, ProcessPool({"s": spec}, 2, chunk_size=1) as single:
        for pool in (auto, single):
            sent = _spy(pool)
            assert _history(pool.bind("s"), problem) == serial["genetic"]
            genetic_sent = list(sent)
            assert random_history(pool.bind("s")) == serial["random"]
            pool.random_sent = sent[len(genetic_sent):]
            pool.genetic_sent = genetic_sent
        # genetic: 4 batches of 6 candidates; automatic chunks 2, 1, 1, 1, 1 per batch
        assert auto.genetic_sent == [2, 1, 1, 1, 1] * 4 and single.genetic_sent == [1] * 24
        # random: one stream of 32 candidates in chunks of 16 // (2 workers * 2) = 4
        assert auto.random_sent == [4] * 8 and single.random_sent == [1] * 32
        assert auto.messages == 20 + 8 and single.messages == 24 + 32
        # random search is asked ahead of its tells: before the first evaluation of the first batch of 16
        # is told, the stream has asked into the second batch
        opt = create_optimizer("random", problem, seed=3)
        asks, ask = [], opt.ask
        opt.ask = lambda: (asks.append(1), ask())[1]
        told = []
        res = Study(opt, auto.bind("s"), Budget(evaluations=32), batch_size=16,
                    on_evaluation=lambda i, e, best: told.append(len(asks))).run()
        assert [e.candidate.key() for e in res.history] == [k for k, *_ in serial["random"]]
        assert told[0] >= 20 and len(asks) == 32


@pytest.mark.slow
def test_stream_survives_a_killed_worker():
    """A worker killed while chunks are in flight: the pool is restarted, the chunks without a result are
    sent again, and the stream still delivers the serial evaluations in ask order."""
    import os
    import signal
    problem = Problem.build(str(PTP3), str(IMPROV), "cyc")
    spec = EvaluatorSpec(problem, evaluation_settings(), seed=7)

    def keys(executor, on_evaluation=None):
        res = Study(create_optimizer("random", problem, seed=7), executor, Budget(evaluations=64), batch_size=16,
                    on_evaluation=on_evaluation).run()
        return [(e.candidate.key(), e.stage, e.cost) for e in res.history]

    serial = keys(SerialExecutor(Evaluator(spec)))
    with ProcessPool({"s": spec}, 2) as pool:
        first = list(pool.pids)

        def kill_once(i, e, best):
            if i == 0:
                os.kill(first[0], signal.SIGKILL)
        assert keys(pool.bind("s"), kill_once) == serial
        assert pool.failures >= 1 and not set(pool.pids) & set(first)  # new workers took over


def test_pool_workers_follow_the_drivers_ik_loop(monkeypatch):
    """With a cold kernel cache the driver decides the Python loop before it starts the workers, so every
    worker runs it too (the cache these tests use is compiled: a worker deciding alone would compile)."""
    from robodesign.solvers import ik_kernel
    monkeypatch.setenv("ROBODESIGN_JIT", "1")  # restored afterwards; ready() sets 0 for the workers
    monkeypatch.setattr(ik_kernel, "_STATE", None)
    monkeypatch.setattr(ik_kernel, "compiled", lambda: False)  # a cold cache, as the driver sees it
    monkeypatch.setattr(ik_kernel, "_start_compiler", lambda: object())  # the background compiler
    problem = Problem.build(str(PTP3), str(IMPROV), "cyc")
    with ProcessPool({"s": EvaluatorSpec(problem, evaluation_settings())}, 2) as pool:
        assert [pool._pool.submit(ik_kernel.ready).result() for _ in range(4)] == [False] * 4
    assert ik_kernel.ready() is False
    monkeypatch.undo()
    assert ik_kernel.compiled()  # the real cache is compiled: what a worker deciding alone would have used
    with ProcessPool({"s": EvaluatorSpec(problem, evaluation_settings())}, 1) as pool:
        assert pool._pool.submit(ik_kernel.ready).result() is True


def test_chunk_sizes():
    assert chunk_sizes(16, 2) == [4, 3, 3, 2, 1, 1, 1, 1]  # 8 messages instead of 16
    assert chunk_sizes(6, 2) == [2, 1, 1, 1, 1]
    assert chunk_sizes(16, 1) == [8, 4, 2, 1, 1]
    assert chunk_sizes(10, 2, chunk_size=4) == [4, 4, 2] and chunk_sizes(3, 2, chunk_size=8) == [3]
    assert chunk_sizes(0, 2) == []
    assert (auto_chunk_size(16, 2), auto_chunk_size(8, 4), auto_chunk_size(64, 2), auto_chunk_size(1, 2)) == (4, 1, 16, 1)


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
    # 4 batches of 8 in chunks of 2, 2, 1, 1, 1, 1; in this process no message at all
    assert (one["messages"], two["messages"]) == (0, 24)
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
                                      (["--batch-size", "0"], "--batch-size must be at least 1, got 0"),
                                      (["--chunk-size", "0"], "--chunk-size must be at least 1, got 0")])
def test_bad_workers_and_batch_size(capsys, args, msg):
    from robodesign.cli.entry import main
    code = main(["optimize", str(PTP3), "--modules", str(IMPROV), "--budget", "2evals", *args])
    err = capsys.readouterr().err
    assert code == 2 and msg in err and "Traceback" not in err


def test_run_checks_its_chunk_size(capsys):
    """``robodesign run --chunk-size`` (process and Ray executors) is checked before anything starts."""
    from robodesign.cli.entry import main
    code = main(["run", "--executor", "ray", "--chunk-size", "0"])
    err = capsys.readouterr().err
    assert code == 2 and "--chunk-size must be at least 1, got 0" in err and "Traceback" not in err


def test_bound_executor_sends_each_candidate_to_the_workers_once():
    """Repeats (within a batch or from an earlier one) come from the driver's cache, as in-process."""
    from robodesign.design.evaluator import Evaluation
    from robodesign.experiment.executors import EvaluatorPool
    from robodesign.design.search_space import Candidate

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
    # a stream answers repeats (earlier or in the stream itself) from the cache as well, in order
    e, f = Candidate(("1", "24", "12"), ()), Candidate(("1", "21", "21", "12"), ())
    out = list(ex.imap(iter([e, a, e, f, d]), batch_size=2))
    assert Counting.sent[2:] == [[e.key(), f.key()]]  # the two new candidates, in one window of 2
    assert [x.candidate.key() for x in out] == [e.key(), a.key(), e.key(), f.key(), d.key()]
    assert out[0] is out[2] and out[1] is first[0] and [x.score for x in out] == [3.0, 3.0, 3.0, 4.0, 3.0]


def test_ask_ahead_study_resumes_stored_evaluations_exactly():
    """Random search (``independent_asks``) on a streaming executor: every evaluation is stored in ask order
    as it is told; a study resumed from the first 7 stored evaluations replays them (none evaluated again)
    and ends with the uninterrupted run's 12 evaluations; a stored candidate the optimizer does not ask
    again is refused."""
    from robodesign.core.errors import InputError
    from robodesign.experiment.executors import SerialPool

    class Memory:
        def __init__(self, evaluations=()):
            self.rows = list(evaluations)

        def load(self):
            return list(self.rows)

        def append(self, index, ev):
            assert index == len(self.rows)
            self.rows.append(ev)

    problem = Problem.build(str(PTP3), str(IMPROV), "cyc")
    spec = EvaluatorSpec(problem, evaluation_settings(), seed=5)

    def run(storage, budget=12):
        pool = SerialPool({"s": spec})
        ex = pool.bind("s")
        res = Study(create_optimizer("random", problem, seed=5), ex, Budget(evaluations=budget), batch_size=4,
                    storage=storage).run()
        return res, len(ex.cache)

    full = Memory()
    ref, evaluated = run(full)
    assert evaluated == 12 and [e.candidate.key() for e in full.rows] == [e.candidate.key() for e in ref.history]
    # the same candidates as random search asks in batches on the in-process executor
    batched = Study(create_optimizer("random", problem, seed=5), SerialExecutor(Evaluator(spec)),
                    Budget(evaluations=12), batch_size=4).run()
    assert [(e.candidate.key(), e.stage, e.cost) for e in batched.history] == \
        [(e.candidate.key(), e.stage, e.cost) for e in ref.history]
    part = Memory(full.rows[:7])
    resumed, evaluated = run(part)
    assert evaluated == 5 and resumed.history[:7] == full.rows[:7]
    assert [(e.candidate.key(), e.stage, e.cost) for e in resumed.history] == \
        [(e.candidate.key(), e.stage, e.cost) for e in ref.history]
    assert [e.candidate.key() for e in part.rows] == [e.candidate.key() for e in full.rows]
    alien = Memory([full.rows[1]])
    with pytest.raises(InputError, match="cannot resume: evaluation 0"):
        run(alien)


def test_default_workers_follow_the_budget(monkeypatch):
    """Without --workers: all cores, except an evaluations-only budget below 200, where a pool's start-up
    costs more than it saves (docs/benchmarks.md); an explicit --workers is always kept."""
    import os
    from robodesign.cli.commands import POOL_MIN_EVALUATIONS, optimize_workers
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1, 2}, raising=False)
    assert POOL_MIN_EVALUATIONS == 200
    assert optimize_workers(None, 16, None, Budget(evaluations=50)) == 1
    assert optimize_workers(None, 16, None, Budget(evaluations=199)) == 1
    assert optimize_workers(None, 16, None, Budget(evaluations=200)) == 3
    assert optimize_workers(None, 16, None, Budget(seconds=5.0)) == 3
    assert optimize_workers(None, 16, None, Budget(evaluations=50, seconds=60.0)) == 3  # a time limit: the pool
    assert optimize_workers(None, 2, None, Budget(evaluations=500)) == 2  # at most one per candidate of a batch
    assert optimize_workers(2, 16, None, Budget(evaluations=50)) == 2
    assert optimize_workers(None, 16, None) == 3


def test_cli_short_default_budget_runs_in_the_process(capsys, tmp_path):
    """The default budget (50evals) of `robodesign optimize` starts no pool and says so."""
    from robodesign.cli.entry import main
    code = main(["optimize", str(PTP3), "--modules", str(IMPROV), "--budget", "6evals", "--batch-size", "3",
                 "--out", str(tmp_path / "b.json")])
    out = capsys.readouterr().out
    assert code in (0, 1)
    assert "evaluating in this process: 6 evaluations are fewer than a worker pool's start-up pays for (200)" in out
    assert "6 evaluations in" in out and "1 worker(s), batches of 3" in out and "messages" not in out
    code = main(["optimize", str(PTP3), "--modules", str(IMPROV), "--budget", "6evals", "--batch-size", "3",
                 "--json", "--out", str(tmp_path / "b.json")])
    summary = json.loads(capsys.readouterr().out)
    assert (summary["workers"], summary["messages"], summary["evaluations"]) == (1, 0, 6)
