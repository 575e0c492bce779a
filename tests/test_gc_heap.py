"""The garbage collector's frozen start-up heap (core/gc_heap.py): what a study and a worker leave out of full
collections, and that a study gives it back."""
from __future__ import annotations

import gc
import multiprocessing
import weakref
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from robodesign.core.gc_heap import startup_heap_frozen
from robodesign.design.optimize import optimize
from robodesign.design.problem import Problem
from robodesign.experiment.executors import _init_worker

SHARED = Path(__file__).resolve().parents[2] / "shared" / "cobra"


class _Node:
    def __init__(self):
        self.other = self   # a reference cycle: only the collector frees it


def test_a_frozen_cycle_is_collected_only_after_the_freeze_ends():
    assert gc.isenabled() and gc.get_freeze_count() == 0
    holder = [_Node()]
    alive = weakref.ref(holder[0])
    with startup_heap_frozen() as froze:
        assert froze and gc.get_freeze_count() > 0
        holder.clear()          # the cycle is garbage now, but frozen: full collections skip it
        gc.collect()
        assert alive() is not None
        young = _Node()         # made after the freeze: collected as usual
        young_alive = weakref.ref(young)
        del young
        gc.collect()
        assert young_alive() is None
    assert gc.get_freeze_count() == 0
    gc.collect()
    assert alive() is None


def test_nested_and_disabled_collectors_are_left_alone():
    with startup_heap_frozen() as outer:
        frozen = gc.get_freeze_count()
        with startup_heap_frozen() as inner:
            assert outer and not inner
        assert gc.get_freeze_count() == frozen   # the inner one did not unfreeze the outer one's heap
    assert gc.get_freeze_count() == 0
    gc.disable()
    try:
        with startup_heap_frozen() as froze:
            assert not froze and gc.get_freeze_count() == 0
    finally:
        gc.enable()


def test_a_study_runs_with_the_heap_frozen_and_gives_it_back():
    problem = Problem.build(SHARED / "tasks" / "simple" / "PTP_1.json", SHARED / "modules" / "IMPROV", "cyc")
    counts = []
    res = optimize(problem, "random", "3evals", seed=1,
                   on_evaluation=lambda i, ev, best: counts.append(gc.get_freeze_count()))
    assert len(res.history) == 3 and len(counts) == 3
    assert min(counts) > 1000      # the imports' objects at least (numpy, pinocchio, the evaluator, ...)
    assert gc.get_freeze_count() == 0


def test_a_pool_worker_freezes_its_heap_after_warming_up():
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"), initializer=_init_worker,
                             initargs=({}, None)) as pool:
        assert pool.submit(gc.get_freeze_count).result(timeout=300) > 1000
