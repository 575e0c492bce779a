"""solvers/ik_accept.py: the acceptance's joint-limit test decides as the chained comparison it replaced
(``all(lo <= v <= hi)`` per joint) on random, on-bound, just-outside, infinite and NaN values (seeded)."""
import math

import numpy as np
import pytest

from robodesign.solvers.ik_accept import Acceptance, near_any


def reference_within(q, lo, hi) -> bool:
    """The plain test: every joint within its limits (NaN fails)."""
    return all(a <= v <= b for v, a, b in zip(q.tolist(), lo.tolist(), hi.tolist()))


def cases(rng, n):
    """Configurations around the limits ``lo``/``hi`` of an ``n``-joint arm: inside, on a bound, one ulp outside,
    far outside, infinite and NaN entries."""
    lo = -rng.uniform(0.5, 3.5, n)
    hi = rng.uniform(0.5, 3.5, n)
    lo[0], hi[-1] = -math.inf, math.inf
    out = []
    for _ in range(400):
        q = rng.uniform(lo.clip(-4, None), hi.clip(None, 4))
        j = int(rng.integers(n))
        pick = int(rng.integers(7))
        if pick == 1:
            q[j] = lo[j] if math.isfinite(lo[j]) else q[j]
        elif pick == 2:
            q[j] = hi[j] if math.isfinite(hi[j]) else q[j]
        elif pick == 3:
            q[j] = np.nextafter(hi[j], math.inf)
        elif pick == 4:
            q[j] = np.nextafter(lo[j], -math.inf)
        elif pick == 5:
            q[j] = math.nan
        elif pick == 6:
            q[j] = -math.inf if rng.random() < 0.5 else math.inf
        out.append(q)
    return lo, hi, out


@pytest.mark.filterwarnings("ignore::RuntimeWarning")   # (infinite joints: near_any subtracts them)
def test_limit_verdicts_equal_the_chained_comparison():
    rng = np.random.default_rng(3)
    seen = set()
    for n in (1, 3, 6, 7):
        lo, hi, qs = cases(rng, n)
        stats = {"rejected_limits": 0, "rejected_collision": 0, "rejected_duplicate": 0}
        sols = []
        accept = Acceptance(None, None, lo, hi, None, False, False, 1e-12, stats, sols)
        for q in qs:
            before = len(sols)
            verdict = accept(q)
            assert (verdict != "limits") == reference_within(q, lo, hi), (q, lo, hi)
            assert len(sols) == before + (verdict == "added")
            seen.add(verdict)
            if verdict == "added" and rng.random() < 0.3:
                seen.add(accept(q.copy()))   # the same configuration again
        assert stats["rejected_limits"] == sum(not reference_within(q, lo, hi) for q in qs)
    assert seen == {"limits", "added", "duplicate"}


def test_duplicates_with_the_stacked_solutions_equal_the_plain_norms():
    """near_any given the solutions stacked (the acceptance's rows) and without them decides as
    ``any(np.linalg.norm(q - s) <= tol)``: random sets of 1-60 solutions, queries at, just inside and just outside
    tol of one of them (seeded); the acceptance's own stack holds its solutions row by row."""
    rng = np.random.default_rng(11)
    tol = 1e-3
    for trial in range(300):
        n = int(rng.integers(1, 9))
        sols = [rng.uniform(-3, 3, n) for _ in range(int(rng.integers(1, 61)))]
        rows = np.vstack(sols + [np.full(n, np.nan)] * int(rng.integers(0, 5)))   # room beyond: ignored
        s = sols[int(rng.integers(len(sols)))]
        u = rng.normal(size=n)
        u /= np.linalg.norm(u)
        for q in (s.copy(), s + u * tol * (1 - 1e-12), s + u * tol * (1 + 1e-12), s + u * tol, rng.uniform(-3, 3, n)):
            plain = any(np.linalg.norm(q - p) <= tol for p in sols)
            assert near_any(q, sols, tol, rows) == plain == near_any(q, sols, tol)
    stats = {"rejected_limits": 0, "rejected_collision": 0, "rejected_duplicate": 0}
    got: list = []
    accept = Acceptance(None, None, np.full(3, -4.0), np.full(3, 4.0), None, False, False, 1e-3, stats, got)
    for q in rng.uniform(-3, 3, (100, 3)):
        accept(q)
    assert len(got) == 100 and np.array_equal(accept._rows[:100], np.array(got))
