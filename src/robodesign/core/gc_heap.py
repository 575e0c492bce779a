"""The garbage collector and the heap a process starts with: a search's full collections need not scan it.

Importing what an evaluation uses (numba's type registry, scipy, toppra, which imports matplotlib, pinocchio)
leaves about 200,000 container objects that live as long as the process. Every full collection of CPython's
collector traverses all of them: 0.2–0.6 s each on the machines of docs/benchmarks.md, and a 200-evaluation
genetic search meets one or two (issue 25). :func:`gc.freeze` moves the objects alive now to a permanent
generation that collections skip; the objects made afterwards are collected as before.

- :func:`startup_heap_frozen` does so for the length of a study (:meth:`robodesign.design.optimize.Study.run`)
  and gives the objects back to the collector at its end (:func:`gc.unfreeze`): an object frozen that became
  cyclic garbage meanwhile is collected then, so nothing lasts beyond the study.
- :func:`freeze_worker_heap` does so for the rest of a worker process's life, after its warm-up (process pool
  and Ray workers: their heap then is imports and evaluators, all kept to the end).

Neither changes a result: when objects are freed is not something an evaluation reads.
"""
from __future__ import annotations

import contextlib
import gc
import threading
from typing import Iterator

_LOCK = threading.Lock()


@contextlib.contextmanager
def startup_heap_frozen() -> Iterator[bool]:
    """Within: the objects alive at entry are skipped by the collector (:func:`gc.freeze`); at exit they are the
    collector's again (:func:`gc.unfreeze`). Yields whether it froze them: not when the collector is off or the
    heap is frozen already (by the caller, an enclosing study or another thread's: that one unfreezes it)."""
    with _LOCK:
        mine = gc.isenabled() and gc.get_freeze_count() == 0
        if mine:
            gc.freeze()
    try:
        yield mine
    finally:
        if mine:
            with _LOCK:
                gc.unfreeze()


def freeze_worker_heap() -> None:
    """In a worker process after its warm-up: the objects alive now are skipped by every later collection."""
    gc.freeze()
