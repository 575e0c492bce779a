"""solve_ik's acceptance of a converged configuration (issue 25): its duplicate test and its shortcut past
Robot.nearest_equivalent decide exactly as the plain forms they replace."""
from __future__ import annotations

import math

import numpy as np
import pytest

from robodesign import Robot, load_module_set
from robodesign.solvers.ik_accept import near_any as _near_any

TWO_PI = 2 * math.pi


def _reference_near_any(q, sols, tol):
    return any(float(np.linalg.norm(q - s)) <= tol for s in sols)


@pytest.mark.parametrize("n", [1, 6, 7])
def test_duplicate_test_equals_the_norm_loop_on_and_next_to_the_tolerance(n):
    rng = np.random.default_rng(n)
    tol = 0.1
    counts = {True: 0, False: 0}
    for trial in range(400):
        q = rng.uniform(-3, 3, n)
        k = int(rng.integers(0, 40))
        sols = []
        for _ in range(k):
            u = rng.normal(size=n)
            u /= np.linalg.norm(u)
            # at the tolerance (its rounding puts some just inside, some just outside), an ulp-scale step off it,
            # or well away
            r = [tol, np.nextafter(tol, 0), np.nextafter(tol, 1), tol * (1 + 1e-12), tol * (1 - 1e-12),
                 rng.uniform(0.2, 4.0)][int(rng.integers(6))]
            sols.append(q + r * u if rng.uniform() < 0.5 else q + rng.uniform(0.15, 3.0) * u)
        want = _reference_near_any(q, sols, tol)
        assert _near_any(q, sols, tol) is want
        counts[want] += 1
    assert counts[True] > 200 and counts[False] > 25


def test_duplicate_test_with_exact_copies_and_a_zero_tolerance():
    q = np.array([0.1, -0.2, 0.3])
    sols = [q + 1.0 for _ in range(12)] + [q.copy()]
    assert _near_any(q, sols, 0.0) is _reference_near_any(q, sols, 0.0) is True
    assert _near_any(q, sols[:12], 0.0) is _reference_near_any(q, sols[:12], 0.0) is False
    assert _near_any(q, sols[:12], 1.8) is _reference_near_any(q, sols[:12], 1.8) is True    # √3 ≈ 1.73


def test_a_configuration_within_half_a_turn_of_the_reference_is_its_own_nearest_equivalent():
    """solve_ik asks Robot.nearest_equivalent only when a joint lies more than half a turn (|ref − q|/2π > 0.5)
    from the reference: within it, the result is q itself (robodesign_heavy: six revolute joints, ±2π)."""
    r = Robot.from_order(load_module_set("robodesign_heavy"), "1,21,22,8,24,12,25,26,25,16".split(","))
    lo, hi = r.q_lower, r.q_upper
    rng = np.random.default_rng(0)
    skipped = asked = 0
    for trial in range(3000):
        q = rng.uniform(lo, hi) if trial % 4 == 0 else rng.uniform(-3.3, 3.3, 6)
        if trial % 3 == 0:     # right at half a turn from the reference
            q[int(rng.integers(6))] = [math.pi, -math.pi, np.nextafter(math.pi, 4), np.nextafter(-math.pi, -4)][
                int(rng.integers(4))]
        seed = None if trial % 2 else rng.uniform(lo, hi)
        ref = (np.clip(0.0, lo, hi) if seed is None else seed).tolist()
        got = r.nearest_equivalent(q, seed)
        if all(-0.5 <= (a - v) / TWO_PI <= 0.5 for a, v in zip(ref, q.tolist())):
            assert np.array_equal(got, q)
            skipped += 1
        else:
            asked += 1
    assert skipped > 300 and asked > 1000
