"""The one motion a solution file describes, and its limits between samples (docs/checker.md, "The motion").

Between samples k and k+1 (step h) a joint moves along the **least-acceleration motion** through
(q_k, v_k) and (q_k+1, v_k+1): two constant-acceleration arcs, +a then −a (or −a then +a), switching once
at ``tau``. With r = Δq − h·(v_k + v_k+1)/2 (the trapezoid residual) and Δv = v_k+1 − v_k::

    a = (2|r| + sqrt(4r² + h²Δv²)) / h²

the smallest peak acceleration of *any* motion through the two samples (so a file whose samples need more
than a joint's acceleration limit describes no motion within it). When the samples are those of a
piecewise-constant acceleration (robodesign's solvers: ddq_k over [t_k, t_k+1]), r = 0 and the arcs are that
motion exactly. Positions are piecewise quadratic, velocities piecewise linear: their extrema per step are
closed-form (:class:`StepMotion`).

The velocities v_k are the file's dq_k, moved by at most ``slack`` when the file's own velocities need more
than the limit: files whose dq is ``numpy.gradient`` of q (the reference's way) report velocities off by up
to A·h/2 (central difference of a motion with |q̈| ≤ A), which makes even an exact sample of a motion at
the limit look up to 1.5× too fast. :func:`witness_velocities` finds velocities within ``slack`` of the file's
(exactly the file's where dq = 0: a joint reported at rest is at rest) that a motion within the acceleration
limit passes through, or the first step where none exists. The judged motion is then a real motion within
the limit through every q sample at its time: what fits inside the slack is a misreported velocity, never
a faster motion.
"""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Optional, Tuple

import numpy as np

ACC_RTOL = 1e-6  # relative slack on the acceleration (rounding: a motion exactly at the limit has a one-point witness)


def judge_kernels() -> Any:
    """The judge's compiled kernels (:mod:`~robodesign.judge.interval_kernel`) when they run in this process (numba
    already imported, the kernels compiled), else None: the numpy paths they replace give the same numbers."""
    if "numba" not in sys.modules:
        return None
    from robodesign.judge import interval_kernel
    return interval_kernel if interval_kernel.ready() else None


def _contiguous(*arrays: np.ndarray) -> Tuple[np.ndarray, ...]:
    """The arrays as C-contiguous float arrays (what the kernels take; no copy of one that is)."""
    return tuple(np.ascontiguousarray(a, dtype=float) for a in arrays)


_LAY_OUT_AFTER = 8  # StepMotion.at calls on the numpy path before the motion's rows are laid out for the kernel


class _ArcRows:
    """What the compiled :meth:`StepMotion.at` reads: the motion's rows per step (q and v at the step's start, a1,
    a2, tau and h: one (N − 1, 6, dof) array) and the kernel module, laid out at the motion's
    :data:`_LAY_OUT_AFTER`-th call (the layout costs a few numpy-path calls; most motions are asked once or twice)."""

    def __init__(self) -> None:
        self.asked = 0
        self.kernel: Any = None
        self.array: Optional[np.ndarray] = None

    def laid_out(self, m: "StepMotion") -> Optional[np.ndarray]:
        """The rows of ``m`` if this call takes the kernel (laid out now if this is the call to), else None."""
        if self.asked < _LAY_OUT_AFTER:
            self.asked += 1
            if self.asked < _LAY_OUT_AFTER:
                return None
            kernel = judge_kernels()
            if kernel is not None and m.q.ndim == 2 and m.q.shape == m.v.shape and m.tau.shape == m.a1.shape \
                    and len(m.q) == len(m.tau) + 1:
                rows = [m.q[:-1], m.v[:-1], m.a1, m.a2, m.tau, np.broadcast_to(m.h, m.tau.shape)]
                self.kernel, self.array = kernel, np.ascontiguousarray(np.stack(rows, axis=1), dtype=float)
        return self.array


def least_acceleration(h, dq_, v0, v1) -> np.ndarray:
    """Smallest peak |q̈| of a motion from (0, v0) to (dq_, v1) in time h (arrays broadcast)."""
    r2 = 2 * dq_ - (v0 + v1) * h  # 2r
    return (np.abs(r2) + np.sqrt(r2 ** 2 + (h * (v1 - v0)) ** 2)) / h ** 2


@dataclass(frozen=True)
class StepMotion:
    """The two-arc motion of every step and joint (arrays (N−1, dof); h is (N−1, 1))."""
    t: np.ndarray
    q: np.ndarray  # (N, dof) samples
    v: np.ndarray  # (N, dof) velocities at the samples (the file's dq or the witness)
    h: np.ndarray
    a1: np.ndarray  # acceleration of the first arc
    a2: np.ndarray  # of the second arc (= −a1, or a1 when the step is one constant acceleration)
    tau: np.ndarray  # switch time in [0, h]

    @classmethod
    def through(cls, t, q, v) -> "StepMotion":
        t, q, v = (np.asarray(x, dtype=float) for x in (t, q, v))
        h = np.diff(t)[:, None]
        kernel = judge_kernels()
        if kernel is not None and q.ndim == 2 and q.shape == v.shape and len(q) == len(t):
            arcs = kernel.step_arcs(*_contiguous(q, v, h[:, 0]))
            return cls(t, q, v, h, arcs[0], arcs[1], arcs[2])
        D = np.diff(q, axis=0)
        v0, v1 = v[:-1], v[1:]
        dv = v1 - v0
        r2 = 2 * D - (v0 + v1) * h
        a = least_acceleration(h, D, v0, v1)
        sigma = np.where(r2 >= 0, 1.0, -1.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            tau = np.where(a > 0, (h + sigma * dv / np.where(a > 0, a, 1.0)) / 2, h / 2)
        tau = np.clip(tau, 0.0, h)
        # one constant acceleration (robodesign's samples) up to rounding: one arc, no zero-length other arc
        tau = np.where(tau < 1e-9 * h, 0.0, np.where(tau > (1 - 1e-9) * h, np.broadcast_to(h, tau.shape), tau))
        return cls(t, q, v, h, sigma * a, -sigma * a, tau)

    @property
    def peak_acceleration(self) -> np.ndarray:
        return np.maximum(np.abs(self.a1), np.abs(self.a2))

    @cached_property
    def v_switch(self) -> np.ndarray:
        return self.v[:-1] + self.a1 * self.tau

    @cached_property
    def q_switch(self) -> np.ndarray:
        return self.q[:-1] + self.v[:-1] * self.tau + self.a1 * self.tau ** 2 / 2

    def at(self, k: int, s: float) -> np.ndarray:
        """q at fraction ``s`` ∈ [0, 1] of step k (compiled where the kernels run: the same numbers)."""
        rows = self._arc_rows
        array = rows.laid_out(self)
        if array is not None and 0 <= k < len(array):
            return rows.kernel.step_at(array, k, float(s))
        x = s * self.h[k, 0]
        tau = self.tau[k]
        u = np.minimum(x, tau)
        w = np.maximum(x - tau, 0.0)
        # first arc up to min(x, tau), then the second arc for the rest
        return (self.q[k] + self.v[k] * u + self.a1[k] * u ** 2 / 2
                + (self.v[k] + self.a1[k] * u) * w + self.a2[k] * w ** 2 / 2)

    @cached_property
    def _arc_rows(self) -> "_ArcRows":
        """The compiled :meth:`at`'s rows of this motion (laid out at its :data:`_LAY_OUT_AFTER`-th call)."""
        return _ArcRows()

    def velocity_extremes(self) -> Tuple[np.ndarray, np.ndarray]:
        """Per step: (largest |velocity|, time of it within the step)."""
        return self._velocity_extremes

    @cached_property
    def _velocity_extremes(self) -> Tuple[np.ndarray, np.ndarray]:
        kernel = judge_kernels()
        if kernel is not None:
            out = kernel.velocity_extremes(*_contiguous(self.v, self.v_switch, self.tau, self.h))
            return out[0], out[1]
        c = np.stack([np.abs(self.v[:-1]), np.abs(self.v_switch), np.abs(self.v[1:])])
        i = np.argmax(c, axis=0)
        when = np.choose(i, [np.zeros_like(self.tau), self.tau, np.broadcast_to(self.h, self.tau.shape)])
        return np.max(c, axis=0), when

    def position_extremes(self) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Per step: (min q, time of it, max q, time of it) over the step, closed-form."""
        return self._position_extremes

    @cached_property
    def _position_extremes(self) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        kernel = judge_kernels()
        if kernel is not None:
            out = kernel.position_extremes(*_contiguous(self.q, self.v, self.a1, self.a2, self.tau, self.h,
                                                        self.q_switch, self.v_switch))
            return out[0], out[1], out[2], out[3]
        q0, v0, a1, a2, tau = self.q[:-1], self.v[:-1], self.a1, self.a2, self.tau
        qs, vs = self.q_switch, self.v_switch
        with np.errstate(divide="ignore", invalid="ignore"):
            s1 = np.where(a1 != 0, -v0 / np.where(a1 != 0, a1, 1.0), -1.0)
            u2 = np.where(a2 != 0, -vs / np.where(a2 != 0, a2, 1.0), -1.0)
        in1 = (s1 > 0) & (s1 < tau)
        in2 = (u2 > 0) & (u2 < self.h - tau)
        q1 = np.where(in1, q0 + v0 * s1 + a1 * s1 ** 2 / 2, q0)
        q2 = np.where(in2, qs + vs * u2 + a2 * u2 ** 2 / 2, q0)
        cand = np.stack([q0, self.q[1:], qs, q1, q2])
        hb = np.broadcast_to(self.h, tau.shape)
        times = np.stack([np.zeros_like(tau), hb, tau, np.where(in1, s1, 0.0), np.where(in2, tau + u2, 0.0)])
        imin, imax = np.argmin(cand, axis=0), np.argmax(cand, axis=0)
        pick = lambda a, i: np.take_along_axis(a, i[None], axis=0)[0]  # noqa: E731
        return pick(cand, imin), pick(times, imin), pick(cand, imax), pick(times, imax)

    def path_bound(self) -> np.ndarray:
        """Per step and joint: a bound on how far the joint moves from any instant of the step to any later one
        (h · max |velocity|; ≥ |Δq|), what the collision sweep advances with."""
        return self._path_bound

    @cached_property
    def _path_bound(self) -> np.ndarray:
        return np.maximum(self.h * self.velocity_extremes()[0], np.abs(np.diff(self.q, axis=0)))


def _v1_range(v0, D, h, A):
    """(min, max) final velocity of a motion from (0, v0) to (D, ·) in time h with |q̈| ≤ A; NaN where none."""
    b = 2 * D / h - v0  # the trapezoid residual changes sign at v1 = b
    c = (A * h) ** 2
    d1 = 2 * c - 4 * A * h * v0 + 4 * A * D  # v1 ≥ b: roots v0 − Ah ± sqrt(d1)
    d2 = 2 * c + 4 * A * h * v0 - 4 * A * D  # v1 ≤ b: roots v0 + Ah ± sqrt(d2)
    s1, s2 = np.sqrt(np.maximum(d1, 0.0)), np.sqrt(np.maximum(d2, 0.0))
    tol = 1e-12 * (np.abs(v0) + np.abs(b) + A * h)  # rounding at the ends of the feasible start velocities
    cross = (b - v0) ** 2 <= c + 2 * tol * A * h
    above = ~cross & (d1 >= -tol * A * h) & (v0 - A * h - s1 >= b - tol)
    below = ~cross & ~above & (d2 >= -tol * A * h) & (v0 + A * h + s2 <= b + tol)
    lo = np.where(cross, v0 + A * h - s2, np.where(above, v0 - A * h - s1, v0 + A * h - s2))
    hi = np.where(cross, v0 - A * h + s1, np.where(above, v0 - A * h + s1, v0 + A * h + s2))
    ok = cross | above | below
    return np.where(ok, lo, np.nan), np.where(ok, hi, np.nan)


def reachable(lo, hi, D, h, A) -> Tuple[np.ndarray, np.ndarray]:
    """Final velocities reachable from any start velocity in [lo, hi] over displacement D in time h with
    |q̈| ≤ A: an interval (NaN where empty). The largest final velocity is a concave function of the start
    velocity with its maximum at D/h − Ah/2, the smallest a convex one with its minimum at D/h + Ah/2."""
    m = D / h
    lo_f, hi_f = np.maximum(lo, m - A * h / 2), np.minimum(hi, m + A * h / 2)  # start velocities that work
    tol = 1e-9 * (A * h + np.abs(m))  # rounding: the two can meet in a single point
    touch = (lo_f > hi_f) & (lo_f <= hi_f + tol)
    lo_f, hi_f = np.where(touch, hi_f, lo_f), np.where(touch, lo_f, hi_f)
    empty = lo_f > hi_f
    # braking (accelerating) all the way gives the smallest (largest) final velocity of all: m ∓ Ah/2
    vmin = np.where((lo_f <= m + A * h / 2) & (m + A * h / 2 <= hi_f), m - A * h / 2,
                    _v1_range(np.clip(m + A * h / 2, lo_f, hi_f), D, h, A)[0])
    vmax = np.where((lo_f <= m - A * h / 2) & (m - A * h / 2 <= hi_f), m + A * h / 2,
                    _v1_range(np.clip(m - A * h / 2, lo_f, hi_f), D, h, A)[1])
    return np.where(empty, np.nan, vmin), np.where(empty, np.nan, vmax)


def witness_velocities(t, q, dq, a_max, slack) -> Tuple[np.ndarray, Optional[np.ndarray]]:
    """Velocities v with |v − dq| ≤ slack (v = dq where dq = 0) such that a motion with |q̈| ≤ a_max passes
    through every (t_k, q_k, v_k), as close to dq as the forward/backward pass finds.

    Returns (v (N, dof), first infeasible step per joint or None): joints without a witness keep dq and have
    their first step where no velocity within the slack continues the motion (−1: none).

    The passes are a recurrence over the steps (each step's interval depends on the one before), joints are
    independent: :func:`_passes_scalar` runs them on Python floats, one joint at a time (about 10× faster than
    numpy calls on arrays of ``dof`` elements, and the same IEEE operations in the same order, so the same
    numbers); :func:`_passes_numpy` is the array form of the same arithmetic, which runs where a value is not
    finite or a step not positive (the scalar form would raise where numpy yields inf or nan)."""
    t, q, dq = (np.asarray(x, dtype=float) for x in (t, q, dq))
    n, dof = q.shape
    A = np.asarray(a_max, dtype=float) * (1 + ACC_RTOL) + 1e-12
    if n < 2 or np.all(least_acceleration(np.diff(t)[:, None], np.diff(q, axis=0), dq[:-1], dq[1:]) <= A):
        return dq.copy(), None  # the file's own velocities work (every robodesign solution): no search
    sl = np.where(dq == 0, 0.0, np.broadcast_to(np.asarray(slack, dtype=float), dq.shape))
    eps = 1e-12 * (1 + np.abs(dq)) + 1e-6 * sl  # rounding: a true velocity can sit exactly at the slack's edge
    lo_b, hi_b = dq - sl - eps, dq + sl + eps
    h = np.diff(t)
    D = np.diff(q, axis=0)
    A = np.broadcast_to(A, (dof,)).copy()
    scalar = (np.all(h > 0) and all(np.all(np.isfinite(x)) and np.all(np.abs(x) < 1e100)
                                    for x in (t, q, dq, A, lo_b, hi_b)))
    v, fail = (_passes_scalar if scalar else _passes_numpy)(dq, lo_b, hi_b, D, h, A)
    v[:, fail >= 0] = dq[:, fail >= 0]
    return v, (fail if np.any(fail >= 0) else None)


def _passes_numpy(dq, lo_b, hi_b, D, h, A):
    """The forward pass (reachable velocity intervals) and the backward pass (witness closest to dq), all joints
    at once: (v, first failing step per joint or −1)."""
    n, dof = dq.shape
    lo, hi = np.empty_like(dq), np.empty_like(dq)
    lo[0], hi[0] = lo_b[0], hi_b[0]
    fail = np.full(dof, -1)
    for k in range(n - 1):
        a, b = reachable(lo[k], hi[k], D[k], h[k], A)
        a, b = np.maximum(a, lo_b[k + 1]), np.minimum(b, hi_b[k + 1])
        bad = ~(a <= b) & (fail < 0)
        fail[bad] = k
        # a failed joint keeps going from its own interval so later steps stay defined
        lo[k + 1] = np.where(a <= b, a, lo_b[k + 1])
        hi[k + 1] = np.where(a <= b, b, hi_b[k + 1])
    v = np.empty_like(dq)
    v[-1] = np.clip(dq[-1], lo[-1], hi[-1])
    for k in range(n - 2, -1, -1):
        rlo, rhi = _v1_range(-v[k + 1], -D[k], h[k], A)  # time-reversed: start velocities that reach v[k+1]
        # v[k+1] at an end of what the step can reach (constant ±A over the step): one start velocity, which
        # rounding can lose: the constant-acceleration one, 2·Δq/h − v[k+1]
        single = -(2 * D[k] / h[k] - v[k + 1])
        rlo, rhi = np.where(np.isnan(rlo), single, rlo), np.where(np.isnan(rhi), single, rhi)
        a, b = np.maximum(-rhi, lo[k]), np.minimum(-rlo, hi[k])
        # rounding can make the intersection empty by a hair: then stay consistent with step k (the back range)
        v[k] = np.where(a <= b, np.clip(dq[k], a, b),
                        np.where(np.isnan(rlo), np.clip(dq[k], lo[k], hi[k]), np.clip(np.clip(dq[k], lo[k], hi[k]),
                                                                                    -rhi, -rlo)))
    return v, fail


_NAN = float("nan")


def _v1_range_f(v0, D, h, A):
    """:func:`_v1_range` of one joint and step on Python floats (the same operations in the same order)."""
    b = 2 * D / h - v0
    Ah = A * h
    c = Ah * Ah
    d1 = 2 * c - 4 * A * h * v0 + 4 * A * D
    d2 = 2 * c + 4 * A * h * v0 - 4 * A * D
    s1, s2 = math.sqrt(d1 if d1 > 0.0 else 0.0), math.sqrt(d2 if d2 > 0.0 else 0.0)
    tol = 1e-12 * (abs(v0) + abs(b) + A * h)
    if (b - v0) * (b - v0) <= c + 2 * tol * A * h:
        return v0 + A * h - s2, v0 - A * h + s1
    if d1 >= -tol * A * h and v0 - A * h - s1 >= b - tol:
        return v0 - A * h - s1, v0 - A * h + s1
    if d2 >= -tol * A * h and v0 + A * h + s2 <= b + tol:
        return v0 + A * h - s2, v0 + A * h + s2
    return _NAN, _NAN


def _reachable_f(lo, hi, D, h, A):
    """:func:`reachable` of one joint and step on Python floats."""
    m = D / h
    lo_f = lo if lo >= m - A * h / 2 else m - A * h / 2
    hi_f = hi if hi <= m + A * h / 2 else m + A * h / 2
    tol = 1e-9 * (A * h + abs(m))
    if lo_f > hi_f and lo_f <= hi_f + tol:
        lo_f, hi_f = hi_f, lo_f
    if lo_f > hi_f:
        return _NAN, _NAN
    up, down = m + A * h / 2, m - A * h / 2
    if lo_f <= up and up <= hi_f:
        vmin = m - A * h / 2
    else:
        vmin = _v1_range_f(min(max(up, lo_f), hi_f), D, h, A)[0]
    if lo_f <= down and down <= hi_f:
        vmax = m + A * h / 2
    else:
        vmax = _v1_range_f(min(max(down, lo_f), hi_f), D, h, A)[1]
    return vmin, vmax


def _passes_scalar(dq, lo_b, hi_b, D, h, A):
    """:func:`_passes_numpy` one joint at a time on Python floats (finite inputs, positive steps)."""
    n, dof = dq.shape
    v = np.empty_like(dq)
    fail = np.full(dof, -1)
    hs = h.tolist()
    for j in range(dof):
        Aj = float(A[j])
        dqj, lbj, hbj, Dj = dq[:, j].tolist(), lo_b[:, j].tolist(), hi_b[:, j].tolist(), D[:, j].tolist()
        lo, hi = [0.0] * n, [0.0] * n
        lo[0], hi[0] = lbj[0], hbj[0]
        for k in range(n - 1):
            a, b = _reachable_f(lo[k], hi[k], Dj[k], hs[k], Aj)
            # np.maximum/np.minimum propagate nan: a nan bound stays nan (and a <= b is then False)
            a = a if a != a or a >= lbj[k + 1] else lbj[k + 1]
            b = b if b != b or b <= hbj[k + 1] else hbj[k + 1]
            if a <= b:
                lo[k + 1], hi[k + 1] = a, b
            else:
                if fail[j] < 0:
                    fail[j] = k
                lo[k + 1], hi[k + 1] = lbj[k + 1], hbj[k + 1]
        vj = [0.0] * n
        vj[-1] = min(max(dqj[-1], lo[-1]), hi[-1])
        for k in range(n - 2, -1, -1):
            rlo, rhi = _v1_range_f(-vj[k + 1], -Dj[k], hs[k], Aj)
            single = -(2 * Dj[k] / hs[k] - vj[k + 1])
            if rlo != rlo:
                rlo = single
            if rhi != rhi:
                rhi = single
            a = -rhi if -rhi >= lo[k] else lo[k]
            b = -rlo if -rlo <= hi[k] else hi[k]
            if a <= b:
                vj[k] = min(max(dqj[k], a), b)
            elif rlo != rlo:  # as in the array form (never, once single replaced a nan)
                vj[k] = min(max(dqj[k], lo[k]), hi[k])
            else:
                vj[k] = min(max(min(max(dqj[k], lo[k]), hi[k]), -rhi), -rlo)
        v[:, j] = vj
    return v, fail
