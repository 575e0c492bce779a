"""The compiled repair's start (ik_kernel.lm_repair): numpy's ``clip(found + noise, lo, hi)`` bit for bit (signed
zeros, values on and beyond the bounds, infinities and NaN included), and the descent from it that of lm_descend."""
from __future__ import annotations

import math

import numpy as np
import pytest

from robodesign.solvers import ik_kernel
from robodesign.solvers.ik import _clip

pytestmark = pytest.mark.skipif(not ik_kernel.available(), reason="ROBODESIGN_JIT=0")


def _args(n):
    """A two-joint chain's kernel arguments after the bounds (any: the start is what is compared)."""
    chain = np.tile(np.eye(4), (n, 1, 1))
    tkind = np.array([ik_kernel.K_SPH], dtype=np.int64)
    tvec = np.zeros((1, 12))
    tvec[0, :4] = (-1e-12, 0.1, 0.0, 0.05)
    tvec[0, 10:] = (math.inf, -math.inf)
    return (chain, np.zeros(n, np.int64), np.ones(n), np.arange(n, dtype=np.int64), np.eye(4), np.eye(4), tkind, tvec,
            np.zeros(3), np.zeros((3, n)), np.zeros((4, 4)), np.array([0.02, 1e-6, 1.0, 0.9, 3.0]))


def test_the_start_is_numpys_clip_bit_for_bit():
    rng = np.random.default_rng(4)
    edge = np.array([0.0, -0.0, 1.0, -1.0, 2.5, -2.5, math.inf, -math.inf, math.nan, 5e-324, -5e-324])
    n = 6
    checked = 0
    for k in range(3000):
        lo = np.sort(rng.choice(edge[:6], n)) if k % 3 == 0 else -rng.uniform(0.0, 3.0, n)
        hi = np.maximum(lo, rng.choice(edge[:6], n)) if k % 3 == 0 else rng.uniform(0.0, 3.0, n)
        found = np.where(rng.random(n) < 0.3, rng.choice(edge, n), rng.uniform(-4.0, 4.0, n))
        noise = np.where(rng.random(n) < 0.3, rng.choice(edge, n), rng.normal(0.0, 0.05, n))
        with np.errstate(invalid="ignore"):   # (inf − inf)
            ref = _clip(found + noise, lo, hi)
        q = np.full(n, 7.0)
        status, its = ik_kernel.lm_repair(found, noise, 0, lo, hi, *_args(n), q)
        assert (status, its) == (0, 0)
        assert np.array_equal(q.view(np.int64), ref.view(np.int64)), (found, noise, lo, hi, q, ref)
        checked += bool(np.signbit(ref[ref == 0.0]).any()) + bool(np.isnan(ref).any())
    assert checked > 100


def test_the_descent_is_lm_descends_from_that_start():
    rng = np.random.default_rng(5)
    n = 2
    lo, hi = -np.full(n, 3.0), np.full(n, 3.0)
    for _ in range(200):
        found, noise = rng.uniform(-3.0, 3.0, n), rng.normal(0.0, 0.05, n)
        a1, a2 = _args(n), _args(n)
        q = np.empty(n)
        r1 = ik_kernel.lm_repair(found, noise, 10, lo, hi, *a1, q)
        start = _clip(found + noise, lo, hi)
        r2 = ik_kernel.lm_descend(start, 10, lo, hi, *a2)
        assert r1 == r2 and np.array_equal(q, start) and np.array_equal(a1[10], a2[10])
