"""Executors: evaluate batches of candidates serially, in local processes or on a Ray cluster.

An *evaluator pool* is created once per experiment with the :class:`~robodesign.evaluator.EvaluatorSpec`
of every (task, evaluation seed) the runs need, keyed by a spec id. Each worker (the main process, a
spawned process, a Ray actor) builds its :class:`~robodesign.evaluator.Evaluator` objects **once**, when it
starts; the specs' problems travel as file references, so tasks and module sets (the heavy models) are
loaded once per worker and shared between specs.
``pool.bind(spec_id)`` gives the object a :class:`~robodesign.optimize.Study` uses as its executor
(``map(candidates) -> list[Evaluation]`` in the order given, ``close()``).

Results do not depend on the executor: evaluations are pure functions of the candidate (per-candidate
seeds) and the study tells them in ask order.

Faults: a process-pool worker that dies (``BrokenProcessPool``) makes the pool restart and re-run the
candidates that had no result. A Ray actor that dies is restarted by Ray (``max_restarts``) and its
in-flight call retried (``max_task_retries``); should the actor be gone for good, a new actor is created
and the candidate re-submitted. Either way no candidate is lost, and none is stored twice (only the main
process stores results).
"""
from __future__ import annotations

import logging
import multiprocessing
import os
import time
from collections import deque
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Dict, List, Optional, Sequence

from ..errors import InputError
from ..evaluator import Evaluation, Evaluator, EvaluatorSpec
from ..search_space import Candidate

log = logging.getLogger(__name__)

MAX_ATTEMPTS = 4  # per candidate, counting the first


def build_evaluators(specs: Dict[str, EvaluatorSpec]) -> Dict[str, Evaluator]:
    """One Evaluator per spec (the problems' tasks and module sets are loaded once per process)."""
    return {sid: Evaluator(spec) for sid, spec in specs.items()}


class BoundExecutor:
    """The executor a Study sees: one spec of a pool. A candidate evaluated before through this executor
    (or twice in a batch) is not sent to a worker again: its evaluation is a pure function of the candidate,
    so the result is the same, as with the in-process evaluator's cache (a worker's own cache misses when
    the repeat lands on another worker)."""

    def __init__(self, pool: "EvaluatorPool", spec_id: str):
        self.pool = pool
        self.spec_id = spec_id
        self.name = pool.kind
        self.cache: Dict[str, Evaluation] = {}

    def map(self, candidates: Sequence[Candidate]) -> List[Evaluation]:
        todo: Dict[str, Candidate] = {}
        for c in candidates:
            if c.key() not in self.cache:
                todo.setdefault(c.key(), c)
        if todo:
            self.cache.update(zip(todo, self.pool.map(self.spec_id, list(todo.values()))))
        return [self.cache[c.key()] for c in candidates]

    def close(self) -> None:  # the pool outlives the runs; closed by its owner
        pass


class EvaluatorPool:
    kind = "?"

    def __init__(self, specs: Dict[str, EvaluatorSpec], workers: int = 1):
        self.specs = dict(specs)
        self.workers = int(workers)
        self.failures = 0  # workers lost (and recovered from)
        self.startup_seconds = 0.0

    def bind(self, spec_id: str) -> BoundExecutor:
        if spec_id not in self.specs:
            raise KeyError(spec_id)
        return BoundExecutor(self, spec_id)

    def map(self, spec_id: str, candidates: List[Candidate]) -> List[Evaluation]:
        raise NotImplementedError

    def close(self) -> None:
        pass

    def info(self) -> dict:
        return {"kind": self.kind, "workers": self.workers, "startup_seconds": round(self.startup_seconds, 3),
                "worker_failures": self.failures}

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


# ------------------------------------------------------------------------------------------------
class SerialPool(EvaluatorPool):
    """Evaluates in this process (evaluators built on first use of a spec)."""
    kind = "serial"

    def __init__(self, specs, workers: int = 1):
        super().__init__(specs, 1)
        self.evaluators: Dict[str, Evaluator] = {}

    def evaluator(self, spec_id: str) -> Evaluator:
        ev = self.evaluators.get(spec_id)
        if ev is None:
            t0 = time.perf_counter()
            ev = self.evaluators[spec_id] = Evaluator(self.specs[spec_id])
            self.startup_seconds += time.perf_counter() - t0
        return ev

    def map(self, spec_id, candidates):
        ev = self.evaluator(spec_id)
        return [ev(c) for c in candidates]


# ------------------------------------------------------------------------------------------------
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
    if parent_pid is not None:
        _watch_parent(parent_pid)
    _WORKER.clear()
    _WORKER.update(build_evaluators(specs))


def _evaluate(spec_id: str, candidate: Candidate) -> Evaluation:
    return _WORKER[spec_id](candidate)


def _ping() -> int:
    time.sleep(0.05)  # long enough for the other warm-up pings to need their own workers
    return os.getpid()


class ProcessPool(EvaluatorPool):
    """``concurrent.futures.ProcessPoolExecutor`` with the spawn context; each worker builds its
    evaluators once in the initializer. A dead worker (``BrokenProcessPool``) is survived: the pool is
    restarted and the candidates without a result are re-run."""
    kind = "process"

    def __init__(self, specs, workers: Optional[int] = None):
        super().__init__(specs, workers or max(1, os.cpu_count() or 1))
        self._pool: Optional[ProcessPoolExecutor] = None
        t0 = time.perf_counter()
        self._start()
        self.startup_seconds = time.perf_counter() - t0

    def _start(self) -> None:
        ctx = multiprocessing.get_context("spawn")
        self._pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=ctx, initializer=_init_worker,
                                         initargs=(self.specs, os.getpid()))
        # start every worker now (and surface initializer errors before the first run)
        futs = [self._pool.submit(_ping) for _ in range(self.workers)]
        self.pids = sorted({f.result() for f in futs})

    def _restart(self) -> None:
        try:
            self._pool.shutdown(wait=False, cancel_futures=True)
        except Exception:  # noqa: BLE001 - a broken pool may fail to shut down cleanly
            pass
        self._start()

    def map(self, spec_id, candidates):
        results: List[Optional[Evaluation]] = [None] * len(candidates)
        attempts = [0] * len(candidates)
        pending = list(range(len(candidates)))
        while pending:
            futs = {}
            broken = False
            try:
                for i in pending:
                    attempts[i] += 1
                    futs[i] = self._pool.submit(_evaluate, spec_id, candidates[i])
            except BrokenProcessPool:
                broken = True
            for i, f in futs.items():
                try:
                    results[i] = f.result()
                except BrokenProcessPool:
                    broken = True
            pending = [i for i in pending if results[i] is None]
            if pending:
                if not broken:  # cannot happen: other exceptions propagate from f.result()
                    raise RuntimeError("process pool returned no result")
                worst = max(attempts[i] for i in pending)
                if worst >= MAX_ATTEMPTS:
                    raise RuntimeError(f"a worker process died {worst} times while evaluating "
                                       f"{candidates[pending[0]].key()!r}; giving up")
                self.failures += 1
                log.warning("a worker process died; restarting the pool and re-running %d candidate(s)", len(pending))
                self._restart()
        return results  # type: ignore[return-value]

    def close(self):
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None


# ------------------------------------------------------------------------------------------------
def ray_env() -> None:
    """Environment every robodesign Ray driver sets (docs/ray.md)."""
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    os.environ.setdefault("RAY_AUTH_MODE", "disabled")


class EvaluatorActor:
    """A Ray actor holding the evaluators of an experiment (built once, in ``__init__``)."""

    def __init__(self, specs: Dict[str, EvaluatorSpec]):
        self.evaluators = build_evaluators(specs)

    def evaluate(self, spec_id: str, candidate: Candidate) -> Evaluation:
        return self.evaluators[spec_id](candidate)

    def pid(self) -> int:
        return os.getpid()


class RayPool(EvaluatorPool):
    """Candidates are evaluated by ``workers`` Ray actors (one CPU each), one call in flight per actor.

    ``address=None`` starts a private local Ray instance (``num_cpus=workers``, no dashboard, bound to
    127.0.0.1); otherwise it connects to the cluster at ``address`` (``HOST:PORT`` of ``ray start --head``)
    and defaults ``workers`` to the cluster's CPU count.
    """
    kind = "ray"

    def __init__(self, specs, workers: Optional[int] = None, address: Optional[str] = None,
                 max_restarts: int = 4, start_timeout: float = 300.0):
        ray_env()
        import ray
        t0 = time.perf_counter()
        self._owns = False
        if not ray.is_initialized():
            if address:
                host = address.rsplit(":", 1)[0]
                # a cluster on this machine's loopback: the driver must present itself with the same
                # address, or Ray looks for a local node under the machine's external IP and fails
                local = host in ("127.0.0.1", "localhost") or host.startswith("127.")
                ray.init(address=address, logging_level=logging.WARNING, log_to_driver=True,
                         **({"_node_ip_address": "127.0.0.1"} if local else {}))
            else:
                ray.init(address="local", num_cpus=workers or max(1, os.cpu_count() or 1), include_dashboard=False,
                         _node_ip_address="127.0.0.1", logging_level=logging.WARNING, log_to_driver=True)
            self._owns = True
        if not workers:
            workers = max(1, int(ray.cluster_resources().get("CPU", 1)))
        super().__init__(specs, workers)
        self.address = address
        self.max_restarts = int(max_restarts)
        self._actor_cls = ray.remote(EvaluatorActor).options(num_cpus=1, max_restarts=self.max_restarts,
                                                              max_task_retries=-1)
        self.actors = [self._new_actor() for _ in range(self.workers)]
        try:
            self.pids = ray.get([a.pid.remote() for a in self.actors], timeout=start_timeout)
        except ray.exceptions.GetTimeoutError:
            cpus = ray.cluster_resources().get("CPU", 0)
            self.close()
            raise InputError(f"Ray could not start {self.workers} evaluator actors within {start_timeout:.0f} s "
                             f"(the cluster has {cpus:g} CPUs; use --workers)") from None
        self.startup_seconds = time.perf_counter() - t0

    def _new_actor(self):
        # the specs are small plain data, passed inline: a restarted actor never depends on the object store
        return self._actor_cls.remote(self.specs)

    def map(self, spec_id, candidates):
        import ray
        from ray.exceptions import RayActorError, RayTaskError, WorkerCrashedError
        results: List[Optional[Evaluation]] = [None] * len(candidates)
        attempts = [0] * len(candidates)
        queue = deque(range(len(candidates)))
        busy: Dict[int, object] = {}  # actor index → ref
        inflight: Dict[object, tuple] = {}  # ref → (candidate index, actor index)
        while queue or inflight:
            for a in range(len(self.actors)):
                if not queue:
                    break
                if a in busy:
                    continue
                i = queue.popleft()
                attempts[i] += 1
                ref = self.actors[a].evaluate.remote(spec_id, candidates[i])
                busy[a] = ref
                inflight[ref] = (i, a)
            done, _ = ray.wait(list(inflight), num_returns=1)
            for ref in done:
                i, a = inflight.pop(ref)
                busy.pop(a, None)
                try:
                    results[i] = ray.get(ref)
                except RayTaskError:
                    raise  # the evaluation itself raised: a bug, not a lost worker
                except (RayActorError, WorkerCrashedError) as e:
                    self.failures += 1
                    if attempts[i] >= MAX_ATTEMPTS:
                        raise RuntimeError(f"Ray workers died {attempts[i]} times while evaluating "
                                           f"{candidates[i].key()!r}; giving up") from e
                    log.warning("Ray evaluator actor %d failed (%s); re-submitting %s", a, type(e).__name__,
                                candidates[i].key())
                    if isinstance(e, getattr(ray.exceptions, "ActorDiedError", ())) or \
                            not isinstance(e, getattr(ray.exceptions, "ActorUnavailableError", ())):
                        # dead for good (restarts exhausted): replace it
                        try:
                            ray.kill(self.actors[a], no_restart=True)
                        except Exception:  # noqa: BLE001
                            pass
                        self.actors[a] = self._new_actor()
                    queue.appendleft(i)
        return results  # type: ignore[return-value]

    def actor_pids(self) -> List[int]:
        import ray
        return ray.get([a.pid.remote() for a in self.actors])

    def close(self):
        import ray
        if not ray.is_initialized():
            return
        for a in getattr(self, "actors", []):
            try:
                ray.kill(a, no_restart=True)
            except Exception:  # noqa: BLE001
                pass
        self.actors = []
        if self._owns:
            ray.shutdown()
            self._owns = False

    def info(self) -> dict:
        d = super().info()
        d["address"] = self.address
        return d


def make_pool(kind: str, specs: Dict[str, EvaluatorSpec], workers: Optional[int] = None,
              address: Optional[str] = None) -> EvaluatorPool:
    if kind == "serial":
        return SerialPool(specs)
    if kind == "process":
        return ProcessPool(specs, workers)
    if kind == "ray":
        return RayPool(specs, workers, address)
    raise InputError(f"unknown executor {kind!r} (serial, process or ray)")
