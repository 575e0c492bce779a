"""Keeping the website responsive under load: per-client rate limits and the bounded queue of checks.

* :class:`RateLimiter`: a token bucket per client (``rate`` requests per second, bursts of ``burst``); a refused
  request learns how long to wait (HTTP 429 with ``Retry-After``).
* :class:`CheckQueue`: the checker threads and the line in front of them. An upload takes a place only once its
  body has arrived completely (:meth:`CheckQueue.reserve` after reading it): a client that sends its body slowly
  holds no place, only one of the ``max_receiving`` bodies being received (at most ``per_client_receiving`` per
  client, by default as many as its places but at least 16, each with its deadline); each client holds at most
  ``per_client`` places. Big checks (many trajectory values) run on at most ``big_slots`` of the threads, so a small
  upload never waits behind two slow ones. Every job has a random ID whose status (place in the line, result) the
  uploader can ask for.
"""
from __future__ import annotations

import math
import secrets
import threading
import time
from collections import OrderedDict
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional


class Busy(Exception):
    """The request is refused for now: HTTP 429 with ``Retry-After: retry_after`` seconds."""

    def __init__(self, message: str, retry_after: float):
        super().__init__(message)
        self.retry_after = max(1, int(math.ceil(retry_after)))


class RateLimiter:
    """Token buckets per client key; at most ``max_clients`` buckets are kept (least recently used go first)."""

    def __init__(self, rate: float, burst: float, max_clients: int = 10_000, clock=time.monotonic):
        self.rate, self.burst, self.max_clients, self.clock = float(rate), float(burst), max_clients, clock
        self._buckets: "OrderedDict[str, List[float]]" = OrderedDict()
        self._lock = threading.Lock()

    @property
    def enabled(self) -> bool:
        return self.rate > 0

    def wait_time(self, key: str) -> float:
        """Take one token for ``key``: 0 if allowed, else the seconds until a token is free (nothing taken)."""
        if not self.enabled:
            return 0.0
        now = self.clock()
        with self._lock:
            tokens, last = self._buckets.pop(key, (self.burst, now))
            tokens = min(self.burst, tokens + (now - last) * self.rate)
            wait = 0.0
            if tokens >= 1:
                tokens -= 1
            else:
                wait = (1 - tokens) / self.rate
            self._buckets[key] = [tokens, now]
            while len(self._buckets) > self.max_clients:
                self._buckets.popitem(last=False)
        return wait


@dataclass
class Job:
    id: str
    client: str
    state: str = "receiving"  # receiving → queued → checking → done | failed
    big: bool = False
    fn: Optional[Callable] = None
    future: Future = field(default_factory=Future)
    created: float = field(default_factory=time.monotonic)
    finished: float = 0.0
    result: Optional[dict] = None  # {"status": HTTP status, "body": JSON} once done / failed


class CheckQueue:
    """``workers`` checker threads and at most ``max_waiting`` jobs waiting or being received in front of them."""

    def __init__(self, workers: int, max_waiting: int, per_client: int, big_slots: Optional[int] = None,
                 keep_done: int = 1000, keep_seconds: float = 3600.0, max_receiving: int = 64,
                 per_client_receiving: Optional[int] = None):
        self.workers = max(1, int(workers))
        self.max_waiting, self.per_client = max(0, int(max_waiting)), max(1, int(per_client))
        self.big_slots = max(1, self.workers - 1) if big_slots is None else max(1, int(big_slots))
        self.keep_done, self.keep_seconds = keep_done, keep_seconds
        # a client may be sending as many bodies as it may hold places in the line (at least 16)
        self.max_receiving = max(1, int(max_receiving))
        self.per_client_receiving = max(16, self.per_client) if per_client_receiving is None \
            else max(1, int(per_client_receiving))
        self._receiving: Dict[str, int] = {}
        self._cond = threading.Condition()
        self._jobs: "OrderedDict[str, Job]" = OrderedDict()  # every job still known, oldest first
        self._line: List[Job] = []  # queued, in arrival order
        self._running_big = 0
        self._running = 0
        self._avg_seconds = 1.0  # running mean of check times, for Retry-After
        self._stop = False
        self._threads = [threading.Thread(target=self._work, name=f"bench-check-{i}", daemon=True)
                         for i in range(self.workers)]
        for t in self._threads:
            t.start()

    # ------------------------------------------------------------------------------------------------ intake
    def _active(self, client: Optional[str] = None) -> int:
        return sum(1 for j in self._jobs.values() if j.state in ("receiving", "queued", "checking")
                   and (client is None or j.client == client))

    def start_receiving(self, client: str) -> None:
        """Count a body about to be read (:class:`Busy` beyond the limits); :meth:`done_receiving` when read."""
        with self._cond:
            total = sum(self._receiving.values())
            mine = self._receiving.get(client, 0)
            if mine >= self.per_client_receiving:
                raise Busy(f"you are already sending {mine} uploads; wait until they have arrived", 5)
            if total >= self.max_receiving:
                raise Busy(f"the server is receiving {total} uploads; try again later", 5)
            self._receiving[client] = mine + 1

    def done_receiving(self, client: str) -> None:
        with self._cond:
            n = self._receiving.get(client, 0) - 1
            if n > 0:
                self._receiving[client] = n
            else:
                self._receiving.pop(client, None)

    def restore(self, job_id: str, client: str = "resumed") -> Job:
        """A job of an upload accepted before a restart (its ID kept; no limits: it was accepted already)."""
        with self._cond:
            job = Job(job_id, client)
            self._jobs[job.id] = job
            return job

    def reserve(self, client: str) -> Job:
        """A place in the line for an upload whose body has arrived, or :class:`Busy`."""
        with self._cond:
            if self._active(client) >= self.per_client:
                raise Busy(f"you already have {self.per_client} upload(s) being checked; wait for a result",
                           self._avg_seconds)
            waiting = self._active() - self._running
            if waiting >= self.max_waiting:
                raise Busy(f"the check queue is full ({waiting} uploads waiting); try again later",
                           self._avg_seconds * (waiting + 1) / self.workers)
            job = Job(secrets.token_urlsafe(16), client)
            self._jobs[job.id] = job
            self._forget_old()
            return job

    def release(self, job: Job) -> None:
        """Give the place back (the upload was refused before it reached the checker)."""
        with self._cond:
            if job.state == "receiving":
                self._jobs.pop(job.id, None)

    def submit(self, job: Job, fn: Callable[[], dict], big: bool) -> Future:
        """Put a reserved job in line: ``fn()`` runs on a checker thread and returns ``{"status", "body"}``."""
        with self._cond:
            job.fn, job.big, job.state = fn, bool(big), "queued"
            self._line.append(job)
            self._cond.notify_all()
        return job.future

    # ------------------------------------------------------------------------------------------------ status
    def get(self, job_id: str) -> Optional[Job]:
        with self._cond:
            return self._jobs.get(job_id)

    def status(self, job: Job) -> dict:
        """``{job, state, position (jobs that start before it; 0 = next or being checked), waiting, checking}`` and,
        once finished, ``status`` (the HTTP status of the upload) and ``result`` (its answer)."""
        with self._cond:
            out = {"job": job.id, "state": job.state, "position": self._ahead(job),
                   "waiting": len(self._line), "checking": self._running}
            if job.result is not None:
                out["status"] = job.result["status"]
                out["result"] = job.result["body"]
            return out

    def _ahead(self, job: Job) -> int:
        """Jobs in line that start before ``job``: every one ahead of a big job, the small ones ahead of a small
        job (small jobs never wait for the big-check slots)."""
        if job not in self._line:
            return 0
        ahead = self._line[: self._line.index(job)]
        return len(ahead) if job.big else sum(1 for j in ahead if not j.big)

    def stats(self) -> dict:
        with self._cond:
            return {"workers": self.workers, "checking": self._running, "waiting": len(self._line),
                    "receiving": sum(self._receiving.values()), "max_waiting": self.max_waiting}

    # ------------------------------------------------------------------------------------------------ workers
    def _next(self) -> Optional[Job]:
        for job in self._line:
            if not job.big or self._running_big < self.big_slots:
                return job
        return None

    def _work(self):
        while True:
            with self._cond:
                job = self._next()
                while job is None and not self._stop:
                    self._cond.wait()
                    job = self._next()
                if self._stop:
                    return
                self._line.remove(job)
                job.state = "checking"
                self._running += 1
                self._running_big += job.big
            t0 = time.monotonic()
            try:
                result = job.fn()
                state = "done"
                error = None
            except BaseException as e:  # noqa: BLE001 (the error goes to the waiting request)
                result, state, error = {"status": 500, "body": {"detail": f"internal error ({type(e).__name__})"}}, \
                    "failed", e
            with self._cond:
                self._running -= 1
                self._running_big -= job.big
                self._avg_seconds = 0.8 * self._avg_seconds + 0.2 * (time.monotonic() - t0)
                job.state, job.finished, job.fn = state, time.monotonic(), None
                job.result = result
                self._cond.notify_all()
            if error is not None:
                job.future.set_exception(error)
            else:
                job.future.set_result(result)

    def _forget_old(self) -> None:
        now = time.monotonic()
        done = [j for j in self._jobs.values() if j.state in ("done", "failed")]
        for j in done[: max(0, len(done) - self.keep_done)]:
            self._jobs.pop(j.id, None)
        for j in done:
            if now - j.finished > self.keep_seconds:
                self._jobs.pop(j.id, None)

    def close(self) -> None:
        with self._cond:
            self._stop = True
            for job in self._line:
                job.future.cancel()
            self._line.clear()
            self._cond.notify_all()
