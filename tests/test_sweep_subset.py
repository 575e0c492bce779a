"""SweepChecker.subset by a range of consecutive pairs (sliced, issue 25) against the same pairs given one by one
(numpy's fancy indexing, the former path): the same pairs, names, bounds and owners, the same dtypes and memory
layouts, fresh memory, and the same events and queries on the solved PTP_3 motion and motions nudged into the mesh."""
from __future__ import annotations

import numpy as np
import pytest
from test_sweep_clearance import _into_obstacle

from robodesign.model import sweep, sweep_kernel
from robodesign.model.cell import solution_robot

pytestmark = pytest.mark.skipif(not sweep_kernel.available(), reason="numba unavailable or ROBODESIGN_JIT=0")

_FIELDS = ("pairs", "W", "_owner", "margins", "is_env", "pair_names", "_mov", "_ref", "_obst")


def _same_field(a, b) -> bool:
    if isinstance(b, np.ndarray):
        return (isinstance(a, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape and a.strides == b.strides
                and a.tobytes() == b.tobytes())
    return type(a) is type(b) and a == b


def test_a_range_is_the_pairs_one_by_one(ptp3_solved):
    assert sweep_kernel.warm_up()
    task, ms, sol = ptp3_solved
    robot = solution_robot(task, sol, ms)
    full = sweep.SweepChecker(robot, check_self=True, check_env=True, posed_arms=True)
    P, n_self = len(full.pairs), robot.n_self_collision_pairs
    rng = np.random.default_rng(9)
    ranges = [range(n_self), range(n_self, P), range(0, P), range(3, 3), range(5, 17)]
    ranges += [range(a, int(rng.integers(a, P + 1))) for a in rng.integers(0, P, 10)]
    Q0 = np.asarray(sol.trajectory.q)
    motions = [Q0]
    for k in (60, 175, 290):
        Q = Q0.copy()
        hit = _into_obstacle(robot, Q, k)
        if hit is not None:
            Q[k] = hit[0]
            motions.append(Q)
    found = 0
    for cols in ranges:
        a, b = full.subset(cols), full.subset(list(cols))
        for name in _FIELDS:
            x, y = getattr(a, name), getattr(b, name)
            assert _same_field(x, y), name
            if isinstance(x, np.ndarray) and x.size:
                assert not np.shares_memory(x, getattr(full, name))
        if len(cols) in (n_self, P - n_self):
            for Q in motions:
                ea, eb = a.check(Q, first_only=False), b.check(Q, first_only=False)
                key = lambda es: [(e.sample, e.s, e.first, e.second, e.distance, e.environment) for e in es]  # noqa: E731
                assert key(ea) == key(eb) and a.queries == b.queries
                found += len(ea)
    assert found > 0 and len(motions) > 1
    with pytest.raises(IndexError):   # beyond the pairs: as numpy's indexing, not a shorter slice
        full.subset(range(P - 2, P + 1))
