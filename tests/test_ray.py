"""Ray executor against a real local Ray cluster (started with ``ray start --head`` on 127.0.0.1); a worker
is killed mid-run and nothing is lost: the results equal a serial run's. Then the Ray pool in this process
(a private local instance): candidates travel in chunks (as with the process pool), batches and streams give
the serial evaluations, the messages are the chunks, and a dead actor costs only its own chunks."""
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import IMPROV, TASKS
from test_experiment import SMALL, rows, stored_count, write

# README's test command runs this file after the parallel part (`-m serial`), alone: its `ray stop --force` stops
# every Ray process of the machine (no other test uses Ray), and Ray's start-up limits (30 s for a node, the actors'
# start) were missed at a load of 10 beside another pytest worker
pytestmark = [pytest.mark.slow, pytest.mark.serial]
BIN = Path(sys.executable).parent
RAY = shutil.which("ray", path=str(BIN)) or shutil.which("ray")
ENV = dict(os.environ, RAY_USAGE_STATS_ENABLED="0", RAY_AUTH_MODE="disabled", PYTHONUNBUFFERED="1")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def actor_pids():
    out = subprocess.run(["ps", "-ww", "-eo", "pid,args"], capture_output=True, text=True).stdout
    return [int(line.split()[0]) for line in out.splitlines() if "ray::EvaluatorActor" in line]


@pytest.mark.skipif(RAY is None, reason="the ray command line is not installed")
def test_ray_cluster_run_survives_a_killed_worker(tmp_path):
    cfg = write(tmp_path, SMALL.format(budget=10, executor="serial").replace("batch_size: 2", "batch_size: 6"))
    ref = tmp_path / "serial"
    subprocess.run([sys.executable, "-m", "robodesign.cli", "run", str(cfg), "--out", str(ref), "--progress", "none"],
                   check=True, env=ENV, capture_output=True, timeout=600)
    port = free_port()
    subprocess.run([RAY, "start", "--head", f"--port={port}", "--node-ip-address=127.0.0.1", "--num-cpus=2",
                    "--include-dashboard=false", "--disable-usage-stats"], check=True, env=ENV, capture_output=True,
                   timeout=180)
    try:
        out = tmp_path / "ray"
        p = subprocess.Popen([sys.executable, "-m", "robodesign.cli", "run", str(cfg), "--out", str(out),
                              "--executor", "ray", "--address", f"127.0.0.1:{port}", "--workers", "2",
                              "--chunk-size", "2", "--progress", "lines"], env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             text=True)
        killed = None
        deadline = time.time() + 300
        while time.time() < deadline and p.poll() is None:
            n = stored_count(out)
            pids = actor_pids()
            if n >= 3 and pids:
                killed = pids[0]
                os.kill(killed, signal.SIGKILL)  # a worker dies in the middle of the run
                break
            time.sleep(0.05)
        log, _ = p.communicate(timeout=600)
        assert p.returncode == 0, log
        assert killed is not None, "no Ray worker was found to kill"
        assert rows(out / "evaluations.sqlite") == rows(ref / "evaluations.sqlite")  # nothing lost, nothing doubled
        assert len(rows(ref / "evaluations.sqlite")) == 20
        import json
        assert json.loads((out / "meta.json").read_text())["sessions"][-1]["executor"]["chunk_size"] == 2
    finally:
        subprocess.run([RAY, "stop", "--force"], env=ENV, capture_output=True, timeout=120)


def _history(executor, problem, budget, on_evaluation=None):
    from robodesign.design.optimize import Budget, Study, create_optimizer
    res = Study(create_optimizer("random", problem, seed=3), executor, Budget(evaluations=budget), batch_size=16,
                on_evaluation=on_evaluation).run()
    return [(e.candidate.key(), e.feasible, e.stage, e.cost, e.goals_reached) for e in res.history]


def _spy(pool):
    """Every chunk the Ray pool sends, as (chunk, actor index, actor handle), counted where the remote call is
    made."""
    sent = []
    send = pool._send

    def counting(spec_id, chunk):
        send(spec_id, chunk)
        sent.append((chunk, chunk.worker[0], chunk.worker[1]))
    pool._send = counting
    return sent


def test_ray_pool_sends_chunks_and_loses_only_a_dead_actors_chunks():
    """PTP_3 with IMPROV on 2 Ray actors, chunks as the process pool cuts them: a batch (``map``) and the
    ask-ahead stream (``imap``, random search) give the serial evaluations, candidate by candidate, in as
    many messages as ``chunk_sizes`` / ``auto_chunk_size`` give chunks. Then an actor is killed for good
    (``max_restarts=0``: Ray does not restart it): only the chunks it had are sent again (to a new actor),
    and the stream still gives the serial evaluations."""
    import ray
    from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
    from robodesign.experiment.executors import RayPool, auto_chunk_size, chunk_sizes, chunked
    from robodesign.design.optimize import SerialExecutor, create_optimizer
    from robodesign.design.problem import Problem
    from robodesign.solvers import ik_kernel

    n = 32  # candidates of the stream (two batches of 16)
    problem = Problem.build(str(TASKS / "simple" / "PTP_3.json"), str(IMPROV), "cyc")
    spec = EvaluatorSpec(problem, evaluation_settings(), seed=3)
    evaluator = Evaluator(spec)
    serial = _history(SerialExecutor(evaluator), problem, n)
    opt = create_optimizer("genetic", problem, seed=5, options={"population_size": 8})
    batch = [opt.ask() for _ in range(13)]
    serial_batch = [(c.key(), e.feasible, e.stage, e.cost) for c, e in zip(batch, map(evaluator, batch))]
    assert len({k for k, *_ in serial}) == n and len({k for k, *_ in serial_batch}) == 13
    assert chunk_sizes(13, 2) == [4, 3, 2, 1, 1, 1, 1] and auto_chunk_size(16, 2) == 4
    try:
        # one pool (two would wait for each other's CPUs): first with its chunk size fixed, then automatic
        with RayPool({"s": spec}, 2, max_restarts=0, chunk_size=5) as pool:
            assert pool.info()["chunk_size"] == 5
            loop = "compiled" if ik_kernel.ready() else "python"  # the actors run the driver's IK loop
            assert pool.jit == (loop == "compiled") and ray.get([a.ik_loop.remote() for a in pool.actors]) == [loop] * 2
            messages = []
            for size in (5, None):
                pool.chunk_size = size
                before = pool.messages
                sent = _spy(pool)
                got = pool.map("s", batch)  # a batch, by guided self-scheduling (or in fives)
                assert [(e.candidate.key(), e.feasible, e.stage, e.cost) for e in got] == serial_batch
                assert [len(c.candidates) for c, *_ in sent] == chunk_sizes(13, 2, size)
                sent.clear()
                # the stream (random search asks ahead), through a new executor: nothing cached
                assert _history(pool.bind("s"), problem, n) == serial
                assert [len(c.candidates) for c, *_ in sent] == \
                    [len(p) for p in chunked(range(n), size or auto_chunk_size(16, 2))]
                messages.append(pool.messages - before)
                assert messages[-1] == len(chunk_sizes(13, 2, size)) + len(sent) and pool.failures == 0
            assert messages == [3 + 7, 7 + 8]
            assert pool.info()["chunk_size"] == "auto"

            # an actor dies for good while the stream runs: killed right after the second chunk is sent to it
            # (a kill at some evaluation may find every chunk done: PTP_3 candidates are often quick)
            dead, victim = pool.actors[0], pool.actor_pids()[0]
            sent = _spy(pool)
            send, before = pool._send, pool.messages

            def send_and_kill(spec_id, chunk):
                send(spec_id, chunk)
                if [actor is dead for _, _, actor in sent].count(True) == 2 and chunk.worker[1] is dead:
                    os.kill(victim, signal.SIGKILL)
            pool._send = send_and_kill
            assert _history(pool.bind("s"), problem, n) == serial  # nothing lost or doubled, in ask order
            lost = [c for c, _, actor in sent if actor is dead][1]
            first_actor = {}
            for c, a, actor in sent:
                first_actor.setdefault(id(c), actor)
            again = {id(c): c for c, *_ in sent if sum(s is c for s, *_ in sent) > 1}
            # re-sent: only chunks whose first message went to the killed actor, each once more, to a new actor
            assert id(lost) in again and all(first_actor[k] is dead for k in again)
            assert all(c.attempts == 2 and c.worker[1] is not dead for c in again.values())
            assert len(first_actor) == n // 4 and pool.messages - before == len(sent) == n // 4 + len(again)
            assert pool.failures == 1 and pool.actors[0] is not dead and victim not in pool.actor_pids()
            assert ray.get(pool.actors[0].ik_loop.remote()) == loop  # the new actor too
    finally:
        if ray.is_initialized():
            ray.shutdown()
