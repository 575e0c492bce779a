"""Where the site runs the checks of uploads: in the server's own threads, or in separate checker processes.

A check parses up to ``--max-upload-mb`` of JSON and runs the checker: seconds of CPU, partly in C code that holds
Python's global interpreter lock. In processes (``robodesign serve``'s default) the checks never slow the threads
that serve pages, a crash or a memory spike stays in the checker process (which is replaced), and several cores are
used; they run at a lower priority (``nice`` +10) so that pages come first on a busy machine. Threads start
faster (the default of :func:`robodesign.web.create_app`, used by most tests).
"""
from __future__ import annotations

import logging
import multiprocessing
import os
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Dict, Optional

from robodesign.experiment.executors import ignore_sigint, sigint_ignored
from robodesign.web.service import Bench, Settings

log = logging.getLogger("robodesign.web")

_worker_bench: Optional[Bench] = None  # the Bench of a checker process
CHECKER_NICE = 10  # checker processes yield the CPU to the process that serves the pages


def die_with_parent(poll: float = 0.25) -> None:
    """Make this (worker) process end when the process that started it ends, even by ``kill -9``: a daemon thread
    watches the parent process ID (a killed parent's children are re-parented) and exits within ``poll`` seconds.
    (Not ``PR_SET_PDEATHSIG``: it fires when the *thread* that started the process ends, and pools start processes
    from short-lived request threads.)"""
    parent = os.getppid()

    def watch():
        while True:
            if os.getppid() != parent:
                os._exit(0)
            time.sleep(poll)
    threading.Thread(target=watch, name="parent-watchdog", daemon=True).start()


def _init_worker(settings: Settings) -> None:
    global _worker_bench
    ignore_sigint()  # Ctrl-C on `robodesign serve` reaches the whole process group: the server shuts us down
    die_with_parent()
    try:
        os.nice(CHECKER_NICE)
    except OSError:  # not permitted here: the checks run at the server's priority
        pass
    _worker_bench = Bench(settings, staging=False)


def _check_in_worker(text: str, fname: str, meta: Dict[str, Optional[str]], token: Optional[str],
                     unwrap: bool, extra: dict) -> dict:
    assert _worker_bench is not None, "_init_worker made it"
    return _worker_bench.check_upload(text, fname, meta, token, unwrap, **extra)


class ThreadChecker:
    """Checks in the calling (checker) thread."""

    def __init__(self, bench: Bench):
        self.bench = bench

    def check(self, text, fname, meta, token, unwrap, **extra) -> dict:
        return self.bench.check_upload(text, fname, meta, token, unwrap, **extra)

    def close(self) -> None:
        pass


class ProcessChecker:
    """Checks in ``processes`` spawned checker processes (started at the first check); a pool whose process died is
    replaced, and that one check answers 500."""

    def __init__(self, settings: Settings, processes: int):
        self.settings, self.processes = settings, max(1, int(processes))
        self._pool: Optional[ProcessPoolExecutor] = None
        self._lock = threading.Lock()

    def _get_pool(self) -> ProcessPoolExecutor:
        with self._lock:
            if self._pool is None:
                self._pool = ProcessPoolExecutor(self.processes, mp_context=multiprocessing.get_context("spawn"),
                                                 initializer=_init_worker, initargs=(self.settings,))
            return self._pool

    def start(self) -> None:
        """Start the processes now (instead of at the first upload), SIGINT ignored from their first instant."""
        with sigint_ignored():
            pool = self._get_pool()
            futures = [pool.submit(int, 0) for _ in range(self.processes)]
        for f in futures:
            f.result()

    def check(self, text, fname, meta, token, unwrap, **extra) -> dict:
        """``extra``: ``token_hash``, ``pending`` of :meth:`Bench.check_upload`."""
        pool = self._get_pool()
        try:
            res = pool.submit(_check_in_worker, text, fname, meta, token, unwrap, extra).result()
        except BrokenProcessPool:
            log.error("a checker process died; starting new ones")
            with self._lock:
                if self._pool is pool:
                    self._pool = None
            pool.shutdown(wait=False, cancel_futures=True)
            raise
        return res

    def close(self) -> None:
        """Stop the checker processes now (a check still running is abandoned: the server is stopping)."""
        with self._lock:
            pool, self._pool = self._pool, None
        if pool is not None:
            procs = list(getattr(pool, "_processes", {}).values())  # the stdlib keeps them there (3.9 … 3.13)
            pool.shutdown(wait=False, cancel_futures=True)
            for proc in procs:
                proc.terminate()
