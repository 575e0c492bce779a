"""The compiled interval RNEA (robodesign.judge.interval_kernel) against the numpy path it replaces: the same
enclosures bit for bit (issue 25), on robots with every joint kind the interval dynamics covers."""
from __future__ import annotations

import numpy as np
import pytest
from test_arc_torques import robots  # noqa: F401  (the fixture: IMPROV, based IMPROV, primitives, reversed)

from robodesign.judge import interval_kernel
from robodesign.judge.interval_rnea import IntervalDynamics

pytestmark = pytest.mark.skipif(not interval_kernel.available(), reason="numba unavailable or ROBODESIGN_JIT=0")


def _both(monkeypatch, call):
    """call() on the numpy path, then on the kernel."""
    with monkeypatch.context() as m:
        m.setattr(interval_kernel, "ready", lambda: False)
        a = call()
    assert interval_kernel.warm_up() and interval_kernel.ready()
    return a, call()


def test_kernel_equals_numpy_path_bit_for_bit(robots, monkeypatch):  # noqa: F811
    rng = np.random.default_rng(11)
    for r in robots:
        dyn = IntervalDynamics(r)
        P, n = 25, r.dof
        for width in (0.0, 1e-3, 0.3):
            Q = (rng.uniform(-3, 3, (P, n)), width * rng.uniform(0, 1, (P, n)))
            V = (rng.uniform(-2, 2, (P, n)), width * rng.uniform(0, 1, (P, n)))
            a = (rng.uniform(-9, 9, (P, n)), width * rng.uniform(0, 1, (P, n)))
            for gravity in (True, False, rng.uniform(size=P) < 0.5):
                A, B = _both(monkeypatch, lambda: dyn.link_torques(Q, V, a, gravity=gravity))
                for f in ("m", "r", "dm", "dr"):
                    assert np.array_equal(getattr(A, f), getattr(B, f)), (r.dof, width, f)
        # the arc-torque pass and the mass-matrix bound of arc_torques, with a plain acceleration array
        rows = np.array([0, 3, 7])
        A, B = _both(monkeypatch, lambda: dyn.link_torques(Q, V, a[0]))
        assert all(np.array_equal(getattr(A, f), getattr(B, f)) for f in ("m", "r", "dm", "dr"))
        (h0, m0), (h1, m1) = _both(monkeypatch, lambda: dyn.rates_and_mass_bound(Q, V, a, rows))
        assert np.array_equal(m0, m1) and np.array_equal(h0.m, h1.m) and np.array_equal(h0.dr, h1.dr)


def test_kernel_torques_are_pinocchios_on_a_point(robots):  # noqa: F811
    """On zero-width boxes the kernel's midpoint is pinocchio's RNEA (real values, not only the numpy path's)."""
    rng = np.random.default_rng(3)
    interval_kernel.warm_up()
    for r in robots:
        dyn = IntervalDynamics(r)
        q, v, a = rng.uniform(-2, 2, (6, r.dof)), rng.uniform(-1, 1, (6, r.dof)), rng.uniform(-5, 5, (6, r.dof))
        T = dyn.link_torques((q, 0 * q), (v, 0 * v), a)
        np.testing.assert_allclose(T.m, r.link_torques(q, v, a), rtol=0, atol=1e-9)
        assert np.all(T.r == 0)
