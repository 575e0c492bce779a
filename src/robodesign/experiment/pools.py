"""What every evaluator pool shares (the executors module describes them): chunk sizes, the executor a Study
sees (:class:`BoundExecutor`), the pool interface, the serial pool and :class:`ChunkedPool`, the chunked sending,
streaming and recovery of the process and Ray pools. A module of its own so that both pools build on it."""
from __future__ import annotations

import contextlib
import logging
import signal
import threading
import time
from collections import deque
from concurrent.futures import FIRST_COMPLETED, Future, wait
from itertools import islice
from typing import Any, Dict, Iterable, Iterator, List, Optional, Sequence, Tuple

from robodesign.core.errors import InputError
from robodesign.design.evaluator import Evaluation, Evaluator, EvaluatorSpec
from robodesign.design.optimize import SerialExecutor
from robodesign.design.search_space import Candidate

log = logging.getLogger("robodesign.experiment.executors")  # the executors' logger, as before the split

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
    """Evaluates in this process (evaluators built on first use of a spec): the study's
    :class:`~robodesign.design.optimize.SerialExecutor` per problem."""
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
        return SerialExecutor(self.evaluator(spec_id)).map(candidates)



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
