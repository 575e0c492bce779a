"""Executors: evaluate batches of candidates serially, in local processes or on a Ray cluster.

An *evaluator pool* is created once per experiment with the :class:`~robodesign.design.evaluator.EvaluatorSpec`
of every (task, evaluation seed) the runs need, keyed by a spec id. Each worker (the main process, a
spawned process, a Ray actor) builds its :class:`~robodesign.design.evaluator.Evaluator` objects **once**, when it
starts; the specs' problems travel as file references, so tasks and module sets (the heavy models) are
loaded once per worker and shared between specs.
``pool.bind(spec_id)`` gives the object a :class:`~robodesign.design.optimize.Study` uses as its executor
(``map(candidates) -> list[Evaluation]`` in the order given; ``imap(candidates, batch_size)``, the same as a
stream that pulls candidates only as workers need them; ``close()``).

Messages: the process pool and the Ray pool (both :class:`ChunkedPool`) send candidates to their workers in
*chunks*, several candidates per message, and get the evaluations back per chunk (a PTP_3 candidate is
often screened out in 1–2 ms, so one message per candidate would cost a noticeable share of the work). A
batch is split by guided self-scheduling: each chunk takes ``ceil(remaining / (2·workers))`` candidates, so
the big chunks go first and the last ones are single candidates that even out the workers at the end of
the batch (16 candidates on 2 workers: 8 messages instead of 16). A stream (``imap``) is cut into chunks of
:func:`auto_chunk_size` (16 on 2 workers: 4), at most two chunks per worker in flight. ``chunk_size``
(``robodesign optimize --chunk-size``, ``robodesign run --chunk-size``, the experiment config's
``executor.chunk_size``) fixes it. ``messages`` counts the chunks sent.

Interrupts (Ctrl-C, SIGTERM): only the driver handles them. Worker processes are started with SIGINT
ignored (:func:`sigint_ignored` around their start, and again in their initializer; Ray actors in their
``__init__``), so a Ctrl-C in a terminal, which reaches the whole process group, leaves them running until
the driver shuts them down: no worker prints a ``KeyboardInterrupt`` traceback.

Results do not depend on the executor: evaluations are pure functions of the candidate (per-candidate
seeds) and the study tells them in ask order.

Faults: a process-pool worker that dies (``BrokenProcessPool``) makes the pool restart and re-run the
chunks that had no result. A Ray actor that dies is restarted by Ray (``max_restarts``) and its in-flight
chunks retried by Ray (``max_task_retries``); should the actor be gone for good, a new actor is created
and only the chunks that actor had are re-submitted (the other actors' chunks keep their results). A chunk
is sent at most :data:`MAX_ATTEMPTS` times. Either way no candidate is lost, and none is stored twice
(only the main process stores results).

The parts every pool shares (chunking, the bound executor, the serial pool, :class:`ChunkedPool`) are
:mod:`.pools`, the Ray pool :mod:`.ray_pool`; both are importable from here too.
"""
from __future__ import annotations

import multiprocessing
import os
import time
from concurrent.futures import Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Dict, List, Optional

from robodesign.core.errors import InputError
from robodesign.core.gc_heap import freeze_worker_heap
from robodesign.design.evaluator import Evaluation, Evaluator, EvaluatorSpec
from robodesign.design.search_space import Candidate
from robodesign.design.solve import warm_up
from robodesign.experiment.pools import MAX_AHEAD as MAX_AHEAD
from robodesign.experiment.pools import MAX_ATTEMPTS as MAX_ATTEMPTS
from robodesign.experiment.pools import BoundExecutor as BoundExecutor
from robodesign.experiment.pools import ChunkedPool, EvaluatorPool, SerialPool, _Chunk, build_evaluators, ignore_sigint
from robodesign.experiment.pools import auto_chunk_size as auto_chunk_size
from robodesign.experiment.pools import chunk_sizes as chunk_sizes
from robodesign.experiment.pools import chunked as chunked
from robodesign.experiment.pools import sigint_ignored as sigint_ignored
from robodesign.experiment.ray_pool import RayPool
from robodesign.solvers import ik_kernel

_WORKER: Dict[str, Evaluator] = {}


def _watch_parent(parent_pid: int, interval: float = 0.5) -> None:
    """Exit when the driver is gone. A spawn worker of ``ProcessPoolExecutor`` holds both ends of its call
    queue's pipe, so it never sees EOF: after a ``kill -9`` of the driver it would wait forever (an orphan
    holding its models in memory)."""
    import threading

    def watch():
        while True:
            time.sleep(interval)
            if os.getppid() != parent_pid:
                os._exit(0)
    threading.Thread(target=watch, name="robodesign-parent-watch", daemon=True).start()


def _init_worker(specs: Dict[str, EvaluatorSpec], parent_pid: Optional[int] = None) -> None:
    ignore_sigint()
    if parent_pid is not None:
        _watch_parent(parent_pid)
    _WORKER.clear()
    _WORKER.update(build_evaluators(specs))
    warm_up()  # the first candidates of this worker cost what the others do
    freeze_worker_heap()  # (imports and evaluators: skipped by the collector from now on)


def _evaluate_chunk(spec_id: str, candidates: List[Candidate]) -> List[Evaluation]:
    ev = _WORKER[spec_id]
    return [ev(c) for c in candidates]


def _ping() -> int:
    time.sleep(0.05)  # long enough for the other warm-up pings to need their own workers
    return os.getpid()



class ProcessPool(ChunkedPool):
    """``concurrent.futures.ProcessPoolExecutor`` with the spawn context; each worker builds its
    evaluators once in the initializer and warms up (:func:`~robodesign.design.solve.warm_up`). Candidates travel
    in chunks (:class:`ChunkedPool`). A dead worker (``BrokenProcessPool``) is survived: the pool is
    restarted and the chunks without a result are re-run."""
    kind = "process"
    worker_noun = "a worker process"

    def __init__(self, specs, workers: Optional[int] = None, chunk_size: Optional[int] = None):
        super().__init__(specs, workers or max(1, os.cpu_count() or 1), chunk_size)
        self._pool: Optional[ProcessPoolExecutor] = None
        t0 = time.perf_counter()
        # the IK loop is decided here, once: with a cold kernel cache every worker, a restarted one too, runs
        # the Python loop (ROBODESIGN_JIT=0 in their environment), whenever the background compilation ends
        ik_kernel.ready()
        self._start()
        self.startup_seconds = time.perf_counter() - t0

    def _start(self) -> None:
        ctx = multiprocessing.get_context("spawn")
        # start every worker now (and surface initializer errors before the first run); they are spawned by
        # the submits (a spawn pool starts a process per submit while none is idle), SIGINT ignored
        with sigint_ignored():
            pool = self._pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=ctx,
                                                    initializer=_init_worker, initargs=(self.specs, os.getpid()))
            futs = [pool.submit(_ping) for _ in range(self.workers)]
        self.pids = sorted({f.result() for f in futs})

    def _restart(self) -> None:
        try:
            if self._pool is not None:
                self._pool.shutdown(wait=False, cancel_futures=True)
        except Exception:  # noqa: BLE001 - a broken pool may fail to shut down cleanly
            pass
        self._start()

    def _send(self, spec_id: str, chunk: _Chunk) -> None:
        if self._pool is None:
            raise RuntimeError("the pool is closed")
        try:
            chunk.future = self._pool.submit(_evaluate_chunk, spec_id, chunk.candidates)
        except BrokenProcessPool as e:  # answered like a chunk whose worker died
            chunk.future = Future()
            chunk.future.set_exception(e)

    def _lost_worker(self, exc):
        return isinstance(exc, BrokenProcessPool)

    def _settle(self, pending):
        wait([c.future for c in pending])  # a broken pool answers every chunk it had

    def _replace_workers(self, lost):
        self._restart()
        return 1

    def close(self, now: bool = False):
        """Shut the workers down: after their chunks in flight, or ``now`` (after an interrupt: the workers are
        terminated, their chunks dropped; nothing is stored from them)."""
        if self._pool is not None:
            if now:
                for proc in list((getattr(self._pool, "_processes", None) or {}).values()):
                    try:
                        proc.terminate()
                    except Exception:  # noqa: BLE001 - already gone
                        pass
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None


def make_pool(kind: str, specs: Dict[str, EvaluatorSpec], workers: Optional[int] = None,
              address: Optional[str] = None, chunk_size: Optional[int] = None) -> EvaluatorPool:
    if kind == "serial":
        return SerialPool(specs)
    if kind == "process":
        return ProcessPool(specs, workers, chunk_size)
    if kind == "ray":
        return RayPool(specs, workers, address, chunk_size=chunk_size)
    raise InputError(f"unknown executor {kind!r} (serial, process or ray)")
