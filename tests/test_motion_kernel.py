"""The judged motion's position and velocity extremes per step by the compiled kernels (judge.interval_kernel) are
the numpy path's, entry for entry (issue 25): on random motions through random samples, with steps of one arc,
arcs of zero acceleration, switches at the ends, huge, infinite and undefined values."""
from __future__ import annotations

import numpy as np
import pytest

from robodesign.judge import interval_kernel, motion
from robodesign.judge.motion import StepMotion


def _same_numbers(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal shapes, NaN at the same entries, every other entry equal byte for byte (the sign of a zero included)."""
    nan = np.isnan(a)
    return a.shape == b.shape and np.array_equal(nan, np.isnan(b)) and a[~nan].tobytes() == b[~nan].tobytes()


def _motions(rng, count: int):
    """Random StepMotions: smooth and rough samples, equal neighbours, rest, one-arc steps, non-finite entries."""
    for i in range(count):
        n, dof = int(rng.integers(2, 60)), int(rng.integers(1, 8))
        t = np.cumsum(np.r_[0.0, rng.uniform(1e-4, 0.05, n - 1)])
        q = np.cumsum(rng.normal(0, 0.02, (n, dof)), axis=0) * 10.0 ** rng.integers(-3, 3)
        v = rng.normal(0, 1, (n, dof)) * 10.0 ** rng.integers(-3, 3)
        v[rng.random((n, dof)) < 0.2] = 0.0
        q[rng.random((n, dof)) < 0.1] = q[0, 0]  # equal samples: zero steps
        if i % 3 == 0:  # one constant acceleration per step (robodesign's samples): single arcs
            a = rng.normal(0, 2, (n - 1, dof))
            h = np.diff(t)[:, None]
            v = np.vstack([v[:1], v[:1] + np.cumsum(a * h, axis=0)])
            q = np.vstack([q[:1], q[:1] + np.cumsum(v[:-1] * h + a * h * h / 2, axis=0)])
        if i % 4 == 1:
            for x in (q, v):
                x[rng.integers(0, n), rng.integers(0, dof)] = rng.choice([np.inf, -np.inf, np.nan, 1e300, -0.0])
        with np.errstate(all="ignore"):
            yield StepMotion.through(t, q, v)


@pytest.fixture(scope="module")
def kernels():
    assert interval_kernel.warm_up()
    return interval_kernel


def test_extremes_compiled_are_the_numpy_path(kernels, monkeypatch):
    rng = np.random.default_rng(5)
    checked = 0
    for m in _motions(rng, 150):
        with np.errstate(all="ignore"):
            got = (m._position_extremes, m._velocity_extremes)
            monkeypatch.setattr(motion, "judge_kernels", lambda: None)
            plain = StepMotion(m.t, m.q, m.v, m.h, m.a1, m.a2, m.tau)
            want = (plain._position_extremes, plain._velocity_extremes)
            monkeypatch.undo()
        for g, w in zip(got[0] + got[1], want[0] + want[1]):
            assert _same_numbers(np.asarray(g), np.asarray(w))
        checked += 1
    assert checked == 150


def test_the_kernels_run_in_the_judge(kernels):
    """The check's StepMotion takes the kernels (not the numpy path) once they are compiled."""
    m = next(_motions(np.random.default_rng(1), 1))
    assert motion.judge_kernels() is kernels
    mn, tmn, mx, tmx = m.position_extremes()
    assert np.all(mn <= np.minimum(m.q[:-1], m.q[1:])) and np.all(mx >= np.maximum(m.q[:-1], m.q[1:]))
    vmax, when = m.velocity_extremes()
    assert np.all(vmax >= np.abs(m.v[:-1])) and np.all((when >= 0) & (when <= m.h))


def test_arcs_compiled_are_the_numpy_path(kernels, monkeypatch):
    """StepMotion.through's arcs (a1, a2, tau) by the kernel: every entry the numpy path's, zeros' signs included,
    also with repeated times (h = 0), resting joints and non-finite samples."""
    rng = np.random.default_rng(9)
    for i in range(200):
        n, dof = int(rng.integers(1, 60)), int(rng.integers(1, 8))
        t = np.cumsum(np.r_[0.0, rng.uniform(1e-4, 0.05, n - 1)])
        if i % 5 == 0 and n > 2:
            t[2] = t[1]  # a step of no duration
        q = np.cumsum(rng.normal(0, 0.02, (n, dof)), axis=0) * 10.0 ** rng.integers(-3, 3)
        v = rng.normal(0, 1, (n, dof)) * 10.0 ** rng.integers(-3, 3)
        v[rng.random((n, dof)) < 0.2] = rng.choice([0.0, -0.0])
        q[rng.random((n, dof)) < 0.1] = q[0, 0]
        if i % 4 == 1:
            for x in (q, v):
                x[rng.integers(0, n), rng.integers(0, dof)] = rng.choice([np.inf, -np.inf, np.nan, 1e300, -0.0])
        with np.errstate(all="ignore"):
            got = StepMotion.through(t, q, v)
            monkeypatch.setattr(motion, "judge_kernels", lambda: None)
            want = StepMotion.through(t, q, v)
            monkeypatch.undo()
        for name in ("h", "a1", "a2", "tau"):
            assert _same_numbers(getattr(got, name), getattr(want, name)), name


def _at_plain(m: StepMotion, k: int, s: float) -> np.ndarray:
    """StepMotion.at as written before the kernel (an independent copy of the formula): first arc up to
    min(x, tau), then the second arc."""
    x = s * m.h[k, 0]
    u, w = np.minimum(x, m.tau[k]), np.maximum(x - m.tau[k], 0.0)
    return m.q[k] + m.v[k] * u + m.a1[k] * u ** 2 / 2 + (m.v[k] + m.a1[k] * u) * w + m.a2[k] * w ** 2 / 2


def test_positions_inside_a_step_compiled_are_the_numpy_path(kernels, monkeypatch):
    """StepMotion.at by the kernel (what the collision sweep asks; from a motion's _LAY_OUT_AFTER-th call on): the
    numpy path's numbers, byte for byte, at random fractions, both ends, the switch and just beyond it, on the random
    motions (non-finite entries included), and the formula's as written before the kernel; a step index outside
    [0, N − 1) keeps numpy's answer (a negative one counts from the end, as numpy's)."""
    rng = np.random.default_rng(21)
    compiled = 0
    for m in _motions(rng, 150):
        calls = []
        for k in range(len(m.tau)):
            switch = [float(x) for x in m.tau[k] / m.h[k, 0] if np.isfinite(x)]
            calls += [(k, s) for s in [0.0, 1.0, *rng.uniform(0, 1, 4).tolist(), *switch,
                                       *np.nextafter(switch, 2.0).tolist()]]
        calls += [(-1, 0.5)] if len(m.tau) else []
        with monkeypatch.context() as patch, np.errstate(all="ignore"):
            patch.setattr(motion, "judge_kernels", lambda: None)
            plain = StepMotion(m.t, m.q, m.v, m.h, m.a1, m.a2, m.tau)
            want = [plain.at(k, s) for k, s in calls]
            assert plain._arc_rows.array is None
        with np.errstate(all="ignore"):
            got = [m.at(k, s) for k, s in calls]
            formula = [_at_plain(m, k, s) for k, s in calls]
        for g, w, f, call in zip(got, want, formula, calls):
            assert _same_numbers(g, w) and _same_numbers(g, f), call
        assert (m._arc_rows.kernel is kernels) == (len(calls) >= motion._LAY_OUT_AFTER)
        compiled += max(0, len(calls) - motion._LAY_OUT_AFTER + 1)
    assert compiled > 5000
