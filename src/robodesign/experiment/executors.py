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
"""
from __future__ import annotations

import contextlib
import logging
import multiprocessing
import os
import signal
import threading
import time
from collections import deque
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from itertools import islice
from typing import Any, Dict, Iterable, Iterator, List, Optional, Sequence, Tuple

from robodesign.core.errors import InputError
from robodesign.design.evaluator import Evaluation, Evaluator, EvaluatorSpec
from robodesign.design.search_space import Candidate
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel

log = logging.getLogger(__name__)

MAX_ATTEMPTS = 4  # per chunk (the candidates sent in one message), counting the first
#: candidates a stream (``imap``) may have evaluated ahead of the one the caller waits for: a long
#: evaluation holds back the delivery of the later ones, not the workers
MAX_AHEAD = 1024


@contextlib.contextmanager
def sigint_ignored():
    """SIGINT ignored in this process while the block runs (in the main thread; elsewhere a no-op): processes
    started in the block inherit the ignored disposition, so a Ctrl-C in the terminal does not reach them.
    A Ctrl-C during the block itself is lost (the block only starts processes)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def ignore_sigint() -> None:
    """In a worker process: leave SIGINT to the driver (it shuts the workers down)."""
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread (a Ray actor may run its __init__ elsewhere)
        pass


def auto_chunk_size(batch_size: int, workers: int) -> int:
    """Candidates per message of a stream when no chunk size is set: about two messages per worker and batch
    (a batch of 16 on 2 workers: 4), at least 1."""
    return max(1, int(batch_size) // (2 * max(1, int(workers))))


def chunk_sizes(n: int, workers: int, chunk_size: Optional[int] = None) -> List[int]:
    """The sizes of the messages a batch of ``n`` candidates is sent in: ``chunk_size`` each when it is set,
    else guided self-scheduling (each chunk ``ceil(remaining / (2·workers))``: 16 on 2 workers gives
    4, 3, 3, 2, 1, 1, 1, 1)."""
    out: List[int] = []
    left = int(n)
    while left > 0:
        k = int(chunk_size) if chunk_size else -(-left // (2 * max(1, int(workers))))
        out.append(min(k, left))
        left -= out[-1]
    return out


def chunked(items: Iterable, size: int) -> Iterator[list]:
    """Lists of ``size`` consecutive items (the last one shorter), pulled from ``items`` one list at a time."""
    it = iter(items)
    while True:
        part = list(islice(it, size))
        if not part:
            return
        yield part


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

    def imap(self, candidates: Iterable[Candidate], batch_size: int = 1) -> Iterator[Evaluation]:
        """The evaluations of ``candidates`` in their order, as a stream: candidates are pulled from the
        iterable only as the workers need them (``batch_size`` sets the automatic chunk size). Repeats are
        answered from the cache, as in :meth:`map`."""
        waiting: deque = deque()  # keys pulled from ``candidates``, not yet delivered
        sent = set()

        def fresh():
            for c in candidates:
                k = c.key()
                waiting.append(k)
                if k not in self.cache and k not in sent:
                    sent.add(k)
                    yield c

        results = self.pool.imap(self.spec_id, fresh(), batch_size)
        while True:
            # a repeat comes after its first occurrence, whose evaluation is then in the cache
            while waiting and waiting[0] in self.cache:
                yield self.cache[waiting.popleft()]
            ev = next(results, None)
            if ev is None:  # the stream is over: what is left (repeats pulled at its end) is cached
                while waiting:
                    yield self.cache[waiting.popleft()]
                return
            self.cache[ev.candidate.key()] = ev

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

    def imap(self, spec_id: str, candidates: Iterable[Candidate], batch_size: int = 1) -> Iterator[Evaluation]:
        """The evaluations of ``candidates`` in their order, pulling ``batch_size`` candidates at a time
        (pools that keep their workers busy across batches override it)."""
        for part in chunked(candidates, max(1, int(batch_size))):
            yield from self.map(spec_id, part)

    def close(self, now: bool = False) -> None:
        """Release the workers (``now``: after an interrupt, without waiting for work in flight)."""

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
    ignore_sigint()
    if parent_pid is not None:
        _watch_parent(parent_pid)
    _WORKER.clear()
    _WORKER.update(build_evaluators(specs))
    warm_up()  # the first candidates of this worker cost what the others do


def _evaluate_chunk(spec_id: str, candidates: List[Candidate]) -> List[Evaluation]:
    ev = _WORKER[spec_id]
    return [ev(c) for c in candidates]


def _ping() -> int:
    time.sleep(0.05)  # long enough for the other warm-up pings to need their own workers
    return os.getpid()


class _Chunk:
    """Consecutive candidates sent to a worker in one message, and the future of their evaluations."""
    __slots__ = ("candidates", "future", "attempts", "worker")

    def __init__(self, candidates: List[Candidate]):
        self.candidates = candidates
        self.future: Optional[Future] = None
        self.attempts = 0
        self.worker: Optional[Tuple[int, Any, Any]] = None  # where the pool sent it (Ray: actor index, handle, ref)

    def sent(self) -> Future:
        """The future of a chunk that was sent (only those are asked about)."""
        if self.future is None:
            raise RuntimeError("the chunk was not sent")
        return self.future

    def evaluated(self) -> bool:
        f = self.sent()
        return f.done() and not f.cancelled() and f.exception() is None

    def failed(self) -> bool:
        f = self.sent()
        return f.done() and not f.cancelled() and f.exception() is not None


class ChunkedPool(EvaluatorPool):
    """A pool whose workers get candidates in chunks (module docstring): batches split by
    :func:`chunk_sizes`, streams by :func:`auto_chunk_size` (``chunk_size`` fixes both), ``messages`` counts
    the chunks sent, chunks whose worker died are sent again. Subclasses send a chunk (:meth:`_send`: set
    ``chunk.future``, a ``concurrent.futures.Future`` of the chunk's evaluations), tell a lost worker from a
    failed evaluation (:meth:`_lost_worker`) and replace lost workers (:meth:`_replace_workers`)."""

    #: what died, in the give-up message
    worker_noun = "a worker"

    def __init__(self, specs, workers: int, chunk_size: Optional[int] = None):
        super().__init__(specs, workers)
        if chunk_size is not None and int(chunk_size) < 1:
            raise InputError(f"chunk size must be at least 1, got {chunk_size}")
        self.chunk_size = int(chunk_size) if chunk_size else None
        self.messages = 0  # chunks sent to the workers (each answered by one message)

    # -- what a subclass provides
    def _send(self, spec_id: str, chunk: _Chunk) -> None:
        raise NotImplementedError

    def _lost_worker(self, exc: BaseException) -> bool:
        """Whether a chunk failed with ``exc`` because its worker died (not because an evaluation raised)."""
        raise NotImplementedError

    def _settle(self, pending: Iterable[_Chunk]) -> None:
        """Called when a chunk's worker died, before the lost chunks are collected (a process pool waits for
        every chunk: a broken pool answers all of them)."""

    def _replace_workers(self, lost: List[_Chunk]) -> int:
        """Make workers available for ``lost`` again; the number of workers lost."""
        raise NotImplementedError

    def _batch_in_flight(self, chunks: int) -> int:
        """Chunks of a batch (:meth:`map`) sent before the first one is answered (the process pool: all at
        once, its executor's call queue hands them to the workers as they get free)."""
        return chunks

    def _cancel(self, chunk: _Chunk) -> None:
        chunk.sent().cancel()

    # -- shared
    def _submit(self, spec_id: str, chunk: _Chunk) -> None:
        chunk.attempts += 1
        self.messages += 1
        self._send(spec_id, chunk)

    def _recover(self, spec_id: str, lost: List[_Chunk]) -> None:
        """Replace the lost workers and send ``lost`` (chunks without a result) again."""
        worst = max(lost, key=lambda c: c.attempts)
        if worst.attempts >= MAX_ATTEMPTS:
            raise RuntimeError(f"{self.worker_noun} died {worst.attempts} times while evaluating "
                               f"{worst.candidates[0].key()!r} (or the candidates sent with it); giving up") \
                from worst.sent().exception()
        log.warning("%s died (%s); re-running %d chunk(s), %d candidate(s)", self.worker_noun,
                    type(worst.sent().exception()).__name__, len(lost), sum(len(c.candidates) for c in lost))
        self.failures += self._replace_workers(lost)
        for c in lost:
            self._submit(spec_id, c)

    def _stream(self, spec_id: str, parts: Iterator[List[Candidate]], in_flight: int) -> Iterator[Evaluation]:
        """Evaluations of the chunks ``parts`` in their order. At most ``in_flight`` chunks are sent and not
        yet evaluated (the next chunk is pulled from ``parts`` when one finishes), and at most
        :data:`MAX_AHEAD` candidates are evaluated ahead of the one delivered next. A chunk whose worker died
        is sent again (the others keep their results)."""
        pending: deque = deque()  # chunks in order, not yet delivered
        state = {"more": True, "ahead": 0}

        def fill() -> None:
            while state["more"] and state["ahead"] < MAX_AHEAD and \
                    sum(not c.future.done() for c in pending) < in_flight:
                part = next(parts, None)
                if part is None:
                    state["more"] = False
                    return
                chunk = _Chunk(part)
                self._submit(spec_id, chunk)
                pending.append(chunk)
                state["ahead"] += len(part)

        try:
            fill()
            while pending:
                head = pending[0]
                if not head.future.done():
                    wait([c.future for c in pending if not c.future.done()], return_when=FIRST_COMPLETED)
                failed = [c for c in pending if c.failed()]
                if failed:
                    for c in failed:
                        if not self._lost_worker(c.future.exception()):
                            c.future.result()  # the evaluation itself raised: a bug, not a lost worker
                    self._settle(pending)
                    self._recover(spec_id, [c for c in pending if c.failed()])
                    continue
                if not head.future.done():
                    fill()
                    continue
                pending.popleft()
                state["ahead"] -= len(head.candidates)
                results = head.future.result()
                fill()
                yield from results
        finally:  # the caller stopped early (or failed): chunks not started yet are dropped
            for c in pending:
                self._cancel(c)

    def map(self, spec_id, candidates):
        parts, k = [], 0
        for n in chunk_sizes(len(candidates), self.workers, self.chunk_size):
            parts.append(list(candidates[k:k + n]))
            k += n
        return list(self._stream(spec_id, iter(parts), in_flight=max(1, self._batch_in_flight(len(parts)))))

    def imap(self, spec_id, candidates, batch_size=1):
        size = self.chunk_size or auto_chunk_size(batch_size, self.workers)
        # two chunks per worker: one running, one waiting for it
        return self._stream(spec_id, chunked(candidates, size), in_flight=2 * self.workers)

    def info(self) -> dict:
        d = super().info()
        d["chunk_size"] = self.chunk_size or "auto"
        return d


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


# ------------------------------------------------------------------------------------------------
def ray_env() -> None:
    """Environment every robodesign Ray driver sets (docs/ray.md)."""
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    os.environ.setdefault("RAY_AUTH_MODE", "disabled")


class EvaluatorActor:
    """A Ray actor holding the evaluators of an experiment (built once, in ``__init__``). ``jit``: the IK
    loop the driver runs (:func:`robodesign.solvers.ik_kernel.ready`): False, the Python loop; True, the
    compiled one, compiled in the actor if its machine's cache is cold. An actor never decides alone, so
    evaluations do not depend on where they ran (the two loops agree to ~1e-15, not bit for bit)."""

    def __init__(self, specs: Dict[str, EvaluatorSpec], jit: Optional[bool] = None):
        ignore_sigint()
        if jit is not None:
            os.environ["ROBODESIGN_JIT"] = "wait" if jit else "0"
        self.evaluators = build_evaluators(specs)
        warm_up()  # as a process-pool worker: the first candidates cost what the others do

    def evaluate_chunk(self, spec_id: str, candidates: List[Candidate]) -> List[Evaluation]:
        ev = self.evaluators[spec_id]
        return [ev(c) for c in candidates]

    def pid(self) -> int:
        return os.getpid()

    def ik_loop(self) -> str:
        """"compiled" or "python": the IK loop this actor runs."""
        return "compiled" if ik_kernel.ready() else "python"


class RayPool(ChunkedPool):
    """Candidates are evaluated by ``workers`` Ray actors (one CPU each), in chunks (:class:`ChunkedPool`):
    a chunk goes to the actor with the fewest chunks in flight, at most two per actor (one running, one
    waiting), so the small chunks at the end of a batch go to the actors that get free first.

    ``address=None`` starts a private local Ray instance (``num_cpus=workers``, no dashboard, bound to
    127.0.0.1); otherwise it connects to the cluster at ``address`` (``HOST:PORT`` of ``ray start --head``)
    and defaults ``workers`` to the cluster's CPU count.
    """
    kind = "ray"
    worker_noun = "a Ray evaluator actor"

    def __init__(self, specs, workers: Optional[int] = None, address: Optional[str] = None,
                 max_restarts: int = 4, start_timeout: float = 300.0, chunk_size: Optional[int] = None):
        if chunk_size is not None and int(chunk_size) < 1:  # before Ray is started
            raise InputError(f"chunk size must be at least 1, got {chunk_size}")
        ray_env()
        import ray
        t0 = time.perf_counter()
        self._owns = False
        if not ray.is_initialized():
            with sigint_ignored():  # Ray's local processes leave Ctrl-C to the driver, as pool workers do
                self._init_ray(ray, address, workers)
            self._owns = True
        if not workers:
            workers = max(1, int(ray.cluster_resources().get("CPU", 1)))
        super().__init__(specs, workers, chunk_size)
        self.address = address
        self.max_restarts = int(max_restarts)
        self.jit = ik_kernel.ready()  # the driver's IK loop, which every actor (a restarted one too) runs
        self._actor_cls = ray.remote(EvaluatorActor).options(num_cpus=1, max_restarts=self.max_restarts,
                                                              max_task_retries=-1)
        self.actors = [self._new_actor() for _ in range(self.workers)]
        self._calls: List[List[Future]] = [[] for _ in range(self.workers)]  # per actor: its chunks' futures
        try:
            self.pids = ray.get([a.pid.remote() for a in self.actors], timeout=start_timeout)
        except ray.exceptions.GetTimeoutError:
            cpus = ray.cluster_resources().get("CPU", 0)
            self.close()
            raise InputError(f"Ray could not start {self.workers} evaluator actors within {start_timeout:.0f} s "
                             f"(the cluster has {cpus:g} CPUs; use --workers)") from None
        self.startup_seconds = time.perf_counter() - t0

    @staticmethod
    def _init_ray(ray, address: Optional[str], workers: Optional[int]) -> None:
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

    def _new_actor(self):
        # the specs are small plain data, passed inline: a restarted actor never depends on the object store
        return self._actor_cls.remote(self.specs, self.jit)

    def _send(self, spec_id: str, chunk: _Chunk) -> None:
        for calls in self._calls:
            calls[:] = [f for f in calls if not f.done()]
        a = min(range(len(self.actors)), key=lambda i: len(self._calls[i]))
        actor = self.actors[a]
        ref = actor.evaluate_chunk.remote(spec_id, chunk.candidates)
        chunk.worker = (a, actor, ref)
        chunk.future = ref.future()
        self._calls[a].append(chunk.future)

    def _lost_worker(self, exc):
        from ray.exceptions import RayActorError, RayTaskError, WorkerCrashedError
        return isinstance(exc, (RayActorError, WorkerCrashedError)) and not isinstance(exc, RayTaskError)

    def _replace_workers(self, lost):
        """An actor Ray could not keep (its restarts used up) is replaced by a new one; one that is only
        unavailable for now (restarting) keeps its place. Ray itself re-sends the calls of an actor it
        restarts (``max_task_retries=-1``): those chunks never fail here."""
        import ray
        unavailable = getattr(ray.exceptions, "ActorUnavailableError", ())
        died = getattr(ray.exceptions, "ActorDiedError", ())
        workers = set()  # actors lost since the last recovery (a chunk may fail after its actor was replaced)
        for c in lost:
            a, actor, _ = c.worker
            if actor is not self.actors[a]:
                continue
            workers.add(a)
            e = c.future.exception()
            if isinstance(e, died) or not isinstance(e, unavailable):
                try:
                    ray.kill(actor, no_restart=True)
                except Exception:  # noqa: BLE001
                    pass
                self.actors[a] = self._new_actor()
                self._calls[a] = []
        return len(workers)

    def _batch_in_flight(self, chunks):
        return 2 * self.workers  # the rest wait here, for the actor that gets free first

    def _cancel(self, chunk):
        """A chunk still queued at its actor is dropped (a running one finishes: actor calls are not
        interrupted)."""
        if chunk.future.done():
            return
        try:  # the future is Ray's: it is answered (TaskCancelledError) rather than cancelled here
            import ray
            ray.cancel(chunk.worker[2])
        except Exception:  # noqa: BLE001 - best effort
            pass

    def actor_pids(self) -> List[int]:
        import ray
        return ray.get([a.pid.remote() for a in self.actors])

    def close(self, now: bool = False):
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
              address: Optional[str] = None, chunk_size: Optional[int] = None) -> EvaluatorPool:
    if kind == "serial":
        return SerialPool(specs)
    if kind == "process":
        return ProcessPool(specs, workers, chunk_size)
    if kind == "ray":
        return RayPool(specs, workers, address, chunk_size=chunk_size)
    raise InputError(f"unknown executor {kind!r} (serial, process or ray)")
