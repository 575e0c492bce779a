"""The sweep's queue of pair queries (robodesign.model.sweep_clearance.DueQueue): its compiled batches and
settling against its Python path, and the batches of both against the former heap of (sample, pair) that the
sweep popped (the pairs due at the earliest sample, ascending, the clearance bounds' skips applied), on the judge's
motion of a solved IMPROV arm in PTP_3 with random schedules, distances and skips (seeded); and the sweep's events
and query counts on either path, with contacts."""
from __future__ import annotations

import heapq

import numpy as np
import pytest
from test_sweep_clearance import _into_obstacle
from test_sweep_kernel import _posed_motion

from robodesign.model import sweep, sweep_clearance, sweep_kernel
from robodesign.model.cell import solution_robot

pytestmark = pytest.mark.skipif(not sweep_kernel.available(), reason="numba unavailable or ROBODESIGN_JIT=0")


@pytest.fixture(scope="module")
def ptp3(ptp3_solved):
    assert sweep_kernel.warm_up()
    task, ms, solution = ptp3_solved
    return task, ms, solution, solution_robot(task, solution, ms)


def _heap_batch(heap, n, skip):
    """The former sweep's batch: pop the earliest sample's pairs from the heap, apply the skips, until one is due."""
    while heap:
        k, due = heap[0][0], []
        while heap and heap[0][0] == k:
            c = heapq.heappop(heap)[1]
            j = int(skip[c, k]) if skip is not None and k < n - 1 else k
            if j == k:
                due.append(c)
            elif j < n - 1:
                heapq.heappush(heap, (j, c))
        if due:
            return k, due
    return -1, []


def _random_skip(rng, P, n):
    """(P, n − 1) skips as open_steps makes them: entry k the first step ≥ k not certified (n − 1: none)."""
    opened = rng.random((P, n - 1)) < rng.choice([0.05, 0.3, 0.9])
    out = np.empty((P, n - 1), np.int64)
    for c in range(P):
        nxt = n - 1
        for k in range(n - 2, -1, -1):
            nxt = k if opened[c, k] else nxt
            out[c, k] = nxt
    return out


def _queues(chk, n, skip, rows, TG, sched, monkeypatch):
    """The queue on the kernel's path and on the Python path."""
    a = sweep_clearance.DueQueue(chk, n, skip, rows, TG, sched, 4e-6, True)
    with monkeypatch.context() as m:
        m.setattr(sweep_clearance, "_kernel", lambda count=True: None)
        b = sweep_clearance.DueQueue(chk, n, skip, rows, TG, sched, 4e-6, True)
    assert a._kernel is not None and b._kernel is None
    return a, b


def test_queue_kernel_equals_python_and_the_former_heap(ptp3, monkeypatch):
    task, ms, sol, robot = ptp3
    tq, Q, chk, sched, TG, rows = _posed_motion(task, sol, robot)
    n, P = len(Q), len(chk.pairs)
    rng = np.random.default_rng(25)
    kinds, batches = set(), 0
    for trial in range(60):
        skip = None if trial % 4 == 0 else _random_skip(rng, P, n)
        a, b = _queues(chk, n, skip, rows, TG, sched, monkeypatch)
        heap = [(0, c) for c in range(P)]
        heapq.heapify(heap)
        while True:
            k, due = a.batch()
            assert (k, due) == b.batch() == _heap_batch(heap, n, skip) and np.array_equal(a.nxt, b.nxt)
            if k < 0:
                break
            batches += 1
            d = rng.choice([-0.01, 0.0, 1e-5, 1e-3, 0.01, 0.05, 0.3, 2.0, np.inf, np.nan], len(due))
            left = a.settle(k, due, d)
            assert repr(left) == repr(b.settle(k, due, d))  # (NaN distances too)
            for c in due:  # the former loop's pushes: the rescheduled pairs (the Python path's: the kernel's may
                if n > b.nxt[c] > k:  # have taken its next batch already), and the left ones by hand
                    heapq.heappush(heap, (int(b.nxt[c]), c))
            for c, dist, v in left:
                kinds.add(-1 if v == -1 else -2 if v == -2 else 0 if v == k else 1)
                assert dist == d[due.index(c)] or np.isnan(dist)
                if rng.random() < 0.5 and k + 1 < n:  # as the sweep does after an advance or look-ahead
                    again = int(rng.integers(k + 1, n))
                    a.push(c, again)
                    b.push(c, again)
                    heapq.heappush(heap, (again, c))
    assert kinds == {-2, -1, 0, 1} and batches > 500


class _PythonQueue(sweep_clearance.DueQueue):
    """The queue on its Python path (the other kernels, open_steps' among them, still run)."""

    def __init__(self, *args):
        super().__init__(*args)
        self._kernel = None


def _events(chk, Q, first_only):
    evs = chk.check(Q, first_only=first_only)
    return [(e.sample, e.s, e.first, e.second, e.distance, e.environment) for e in evs], chk.queries


def test_sweep_is_the_same_on_either_path(ptp3, monkeypatch):
    """Events and query counts of the judge's sweep with the compiled queue and with its Python path, on the solved
    motion, random walks, and motions nudged into the mesh (contacts at and between the samples)."""
    task, ms, sol, robot = ptp3
    Q0 = np.asarray(sol.trajectory.q)
    rng = np.random.default_rng(3)
    motions = [Q0]
    for trial in range(6):
        Q, k = Q0.copy(), int(rng.integers(1, len(Q0) - 1))
        hit = _into_obstacle(robot, Q, k)
        if hit is not None:
            Q[k] = hit[0]
            motions.append(Q)
        motions.append(Q0[0] + np.cumsum(rng.normal(0, 0.4, (40, robot.dof)), axis=0))
    found = 0
    for Q in motions:
        for first_only in (False, True):
            a = _events(sweep.SweepChecker(robot, posed_arms=True), Q, first_only)
            with monkeypatch.context() as m:
                m.setattr(sweep, "DueQueue", _PythonQueue)
                b = _events(sweep.SweepChecker(robot, posed_arms=True), Q, first_only)
            assert a == b
            found += len(a[0])
    assert found > 100 and len(motions) > 7  # contacts at and between the samples; a nudged motion or more
