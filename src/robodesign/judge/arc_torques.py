"""Torque limits certified on the judged motion between samples (docs/checker.md, "Torques between samples").

Inside a step each joint of the judged motion (:mod:`robodesign.judge.motion`) follows one or two
constant-acceleration arcs; cut at every joint's switch instant, a step becomes **pieces** on which every
joint has a constant acceleration, so the drivetrain torque τ(t) = RNEA(q(t), q̇(t), q̈) + k²I_m·q̈ + f_v·q̇ +
f_c·σ(q̇) is smooth on each piece. Per piece and joint:

* τ is evaluated exactly at both ends of the piece, with the piece's acceleration (so at every sample with the
  acceleration just before and just after it, and at every switch instant with both arcs' accelerations);
* :class:`~robodesign.judge.interval_rnea.IntervalDynamics` encloses τ̇ over the whole piece, [d_lo, d_hi]
  (the friction term's rate (f_v + f_c·σ'(q̇))·q̈ with σ' over the piece's velocity interval);
* then τ(t) ≤ min(τ(t₀) + d_hi·(t − t₀), τ(t₁) − d_lo·(t₁ − t)) and τ(t) ≥ max(τ(t₀) + d_lo·(t − t₀),
  τ(t₁) − d_hi·(t₁ − t)) for every t of the piece: an upper and a lower bound of τ over the piece.

First whole steps: they are grouped (CHUNK_STEPS = 16), one rate enclosure over each group's box (the motion's
q and q̇ extremes over its steps, all its accelerations) bounds every piece in it, and a mass-matrix enclosure
bounds the jumps of τ where a joint's acceleration switches inside a step; from τ just after and just before
the step's samples (already computed for the checks at the samples) that certifies the steps far from the
limit without evaluating anything. The steps left are cut into pieces with exact end values and their own,
tighter enclosures. A piece is **certified** when both bounds lie within ±peakTorque·(1 + LIMIT_RTOL).
Otherwise τ is evaluated at
its midpoint: above the limit there, it is a violation (joint, time, value); else the piece is split in two
and the halves are bounded again, down to pieces of h/2^MAX_DEPTH. The bounds' excess shrinks with the piece
(linearly, quadratically near an interior extremum), so a motion whose torque stays inside the limit is
certified after a few splits where it comes close (a peak touching the limit needs about two pieces per
level). A piece still undecided at the deepest split (its torque within about (h/2^MAX_DEPTH)²·|τ̈| of the limit
without a point found above it), or when the pieces bounded one by one would exceed PIECES_PER_STEP per step
on average (a file made to keep every step a hair below the limit would otherwise cost 2^MAX_DEPTH pieces per
step), is reported as a violation that could not be certified: the judge never accepts a torque limit it has
not proven, and a file cannot make it work without bound.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import List, Optional, Tuple

import numpy as np

from robodesign.judge.interval_rnea import IntervalDynamics
from robodesign.judge.motion import judge_kernels
from robodesign.model.robot import COULOMB_SMOOTHING

MAX_DEPTH = 12  # pieces are split down to h / 4096
CHUNK_STEPS = 16  # steps per group of the first, coarse rate bound
PIECES_PER_STEP = 64  # bound on the pieces bounded one by one, on average per step (the work a file can cause)
ROUND_RTOL = 1e-12  # the pieces' q and q̇ intervals are widened by this (relative) against rounding


@dataclass
class ArcTorqueViolation:
    step: int  # samples step → step + 1
    joint: int
    time: float  # absolute time of the instant found (or of the undecided piece's midpoint)
    value: float  # τ there (signed), or the bound when not certified
    certified_over: bool  # True: τ(time) itself exceeds the limit; False: the limit could not be certified


@dataclass
class ArcTorqueReport:
    violations: List[ArcTorqueViolation]
    pieces: int  # pieces bounded one by one (of the steps the groups' bound left open, and every split)
    evaluations: int  # exact torque evaluations (piece ends and midpoints)
    depth: int  # deepest split used


def _piece_state(m, k, s, acc_arc2):
    """q, q̇ (P, dof) of the motion at local time s (P,) of step k (P,); acc_arc2 (P, dof) bool: the joint is on
    its second arc over the piece (the two arcs' formulas agree at the switch instant, and a piece never straddles
    a switch where the acceleration changes)."""
    tau = m.tau[k]
    s_ = s[:, None]
    u = np.where(acc_arc2, tau, s_)
    w = np.where(acc_arc2, s_ - tau, 0.0)
    v0, a1, a2 = m.v[k], m.a1[k], m.a2[k]
    q = m.q[k] + v0 * u + a1 * u * u / 2 + (v0 + a1 * u) * w + a2 * w * w / 2
    v = v0 + a1 * u + a2 * w
    return q, v


def _interval(lo, hi):
    mid = (lo + hi) / 2
    return mid, (hi - lo) / 2 + ROUND_RTOL * (np.abs(mid) + np.abs(hi - lo) + 1.0)


def _bounds(ta, tb, d_lo, d_hi, delta):
    """Upper and lower bound of τ over [0, δ] from its end values and the interval of its rate (arrays)."""
    return _upper(ta, tb, d_lo, d_hi, delta), _lower(ta, tb, d_lo, d_hi, delta)


def _upper(ta, tb, d_lo, d_hi, delta):
    """The upper bound of :func:`_bounds`."""
    with np.errstate(divide="ignore", invalid="ignore"):
        ts = np.clip(np.nan_to_num((tb - ta - d_lo * delta) / (d_hi - d_lo)), 0.0, delta)
    up = lambda t: np.minimum(ta + d_hi * t, tb - d_lo * (delta - t))  # noqa: E731
    z = np.zeros_like(ta)
    return np.maximum(np.maximum(up(z), up(delta + z)), up(ts))


def _lower(ta, tb, d_lo, d_hi, delta):
    """The lower bound of :func:`_bounds`."""
    with np.errstate(divide="ignore", invalid="ignore"):
        tl = np.clip(np.nan_to_num((tb - ta - d_hi * delta) / (d_lo - d_hi)), 0.0, delta)
    lo = lambda t: np.maximum(ta + d_lo * t, tb - d_hi * (delta - t))  # noqa: E731
    z = np.zeros_like(ta)
    return np.minimum(np.minimum(lo(z), lo(delta + z)), lo(tl))


def _rate_bounds(dyn, robot, Q, V, acc_lo, acc_hi, wr):
    """[d_lo, d_hi] (P, dof) enclosing dτ/dt of the drivetrain torque along any arc with q in Q, q̇ in V and a
    constant q̈ in [acc_lo, acc_hi]: the link-side rate (interval RNEA) plus the friction term's
    (f_v + f_c·σ'(q̇))·q̈, σ'(x) = k / (1 + (kx)²)^1.5 (largest at the q̇ nearest 0); k²I_m·q̈ is constant."""
    return _with_friction(_link_rates(dyn, Q, V, acc_lo, acc_hi, wr), robot, V, acc_lo, acc_hi)


def _link_rates(dyn, Q, V, acc_lo, acc_hi, wr):
    """The link-side enclosure of :func:`_rate_bounds` (interval RNEA; its fields dm ± dr bound the rate)."""
    am, ar = (acc_lo + acc_hi) / 2, (acc_hi - acc_lo) / 2
    return dyn.link_torques(Q, V, (am, ar), wr if np.any(wr) else None)


def _with_friction(T, robot, V, acc_lo, acc_hi):
    """[d_lo, d_hi] of :func:`_rate_bounds` from the link-side rate enclosure ``T``."""
    fv, fc = np.asarray(robot.friction_viscous, dtype=float), np.asarray(robot.friction_coulomb, dtype=float)
    vlo, vhi = V[0] - V[1], V[0] + V[1]
    near = np.clip(0.0, vlo, vhi)
    far = np.where(np.abs(vlo) > np.abs(vhi), vlo, vhi)
    dsig = lambda x: COULOMB_SMOOTHING / (1.0 + (COULOMB_SMOOTHING * x) ** 2) ** 1.5  # noqa: E731
    f_lo, f_hi = fv + np.minimum(fc * dsig(near), fc * dsig(far)), fv + np.maximum(fc * dsig(near), fc * dsig(far))
    prods = np.stack([f_lo * acc_lo, f_lo * acc_hi, f_hi * acc_lo, f_hi * acc_hi])
    return T.dm - T.dr + prods.min(axis=0), T.dm + T.dr + prods.max(axis=0)


def _boxes(motion, steps) -> tuple:
    """The groups of :func:`_step_prefilter` (the sorted ``steps`` cut every CHUNK_STEPS from the first) and their
    boxes: (each step's group, Q and V (mid, radius) of q and q̇ over the group's steps, (a_lo, a_hi) of all its
    accelerations, h (S, 1), |a2 − a1| where a joint's acceleration switches inside a step (0 elsewhere), the groups
    with such a switch). The compiled kernel (the same operations, interval_kernel.prefilter_boxes) where it runs."""
    kernel = judge_kernels()
    mn, _, mx, _ = motion.position_extremes()
    if kernel is not None:
        f = lambda x: np.ascontiguousarray(x, dtype=float)  # noqa: E731
        c, q0, q1, v0, v1, a_lo, a_hi, h, dA, need = kernel.prefilter_boxes(
            np.ascontiguousarray(steps, dtype=np.int64), CHUNK_STEPS, f(mn), f(mx), f(motion.v), f(motion.v_switch),
            f(motion.a1), f(motion.a2), f(motion.h[:, 0]), f(motion.tau), ROUND_RTOL)
        return c, (q0, q1), (v0, v1), (a_lo, a_hi), h, dA, np.nonzero(need)[0]
    first = int(steps[0])
    ch_of_step = (steps - first) // CHUNK_STEPS
    starts = np.nonzero(np.r_[True, np.diff(ch_of_step) != 0])[0]
    v_all = np.stack([motion.v[:-1], motion.v_switch, motion.v[1:]])
    red = lambda f, x: f.reduceat(x[steps], starts, axis=0)  # noqa: E731
    q_lo, q_hi = red(np.minimum, mn), red(np.maximum, mx)
    v_lo, v_hi = red(np.minimum, v_all.min(axis=0)), red(np.maximum, v_all.max(axis=0))
    a_lo = red(np.minimum, np.minimum(motion.a1, motion.a2))
    a_hi = red(np.maximum, np.maximum(motion.a1, motion.a2))
    c = np.repeat(np.arange(len(starts)), np.diff(np.r_[starts, len(steps)]))  # each step's group
    h = motion.h[steps]
    tau = motion.tau[steps]
    dA = np.where((tau > 0) & (tau < h) & (motion.a1[steps] != motion.a2[steps]),
                  np.abs(motion.a2[steps] - motion.a1[steps]), 0.0)
    return c, _interval(q_lo, q_hi), _interval(v_lo, v_hi), (a_lo, a_hi), h, dA, np.unique(c[np.any(dA != 0, axis=1)])


def _step_prefilter(dyn, robot, motion, W, steps, ta, tb, lim):
    """(len(steps), dof) True where the whole step is certified at once. The steps are grouped by CHUNK_STEPS;
    one interval RNEA pass over each group's box (q and q̇ extremes of the motion over its steps, all its
    accelerations) bounds τ̇ on every piece in it, and another bounds the mass matrix there, so the jumps of τ
    where a joint's acceleration switches inside a step: |Δτ_j| ≤ Σ_i (|M_ji| + k²I_m·δ_ij)·|a2_i − a1_i|, J_j
    in all. From τ just after sample k (ta) and just before k + 1 (tb), τ over the step is within the
    mean-value bounds of the pieces moved by J. Groups whose wrench changes are not prefiltered."""
    c, Q, V, (a_lo, a_hi), h, dA, need = _boxes(motion, steps)
    G = len(a_lo)
    wr = np.zeros((G, 6))
    same = np.ones(G, dtype=bool)
    if np.any(W):  # (no wrench: all the same, zero)
        starts = np.searchsorted(c, np.arange(G))
        for g, (i0, i1) in enumerate(zip(starts, np.r_[starts[1:], len(steps)])):
            rows = W[steps[i0]:steps[i1 - 1] + 2]
            same[g] = bool(np.all(rows == rows[0]))
            wr[g] = rows[0]
    J = np.zeros_like(dA)
    wr = np.where(same[:, None], wr, 0.0)
    if len(need) and not np.any(wr):  # the rate and the mass matrix in one interval pass
        T, Mb = dyn.rates_and_mass_bound(Q, V, ((a_lo + a_hi) / 2, (a_hi - a_lo) / 2), need)
    else:
        T = _link_rates(dyn, Q, V, a_lo, a_hi, wr)
        Mb = dyn.mass_matrix_bound((Q[0][need], Q[1][need])) if len(need) else None
    if Mb is not None:
        M_all = np.zeros((G,) + Mb.shape[1:])  # groups without a switch: J = 0 (dA = 0 there)
        M_all[need] = Mb
        J = np.einsum("sji,si->sj", M_all[c], dA) + np.asarray(robot.model.armature, dtype=float) * dA
    return _steps_within(T, robot, V, (a_lo, a_hi), c, (ta, tb, J), h, lim) & same[c][:, None]


def _steps_within(T, robot, V, acc: tuple, c: np.ndarray, ends: tuple, h: np.ndarray, lim: np.ndarray) -> np.ndarray:
    """(steps, dof) True where τ over the whole step stays within ±lim: the groups' rate bounds (:func:`_with_friction`
    of the link-side enclosure T, q̇ in V, q̈ in acc = (lo, hi)) on each step of group c, from τ just after and just
    before its samples ± the switch jumps, ``ends`` = (ta, tb, J); h (steps, 1). The compiled kernel (the same
    operations, judge.interval_kernel.steps_certified) where it runs and the inputs are finite and below 1e100."""
    ta, tb, J = ends
    kernel = judge_kernels()
    if kernel is not None:
        f = lambda x: np.ascontiguousarray(x, dtype=float)  # noqa: E731
        ok = kernel.steps_certified(f(T.dm), f(T.dr), f(V[0]), f(V[1]), f(acc[0]), f(acc[1]),
                                    f(robot.friction_viscous), f(robot.friction_coulomb), COULOMB_SMOOTHING,
                                    np.ascontiguousarray(c, dtype=np.int64), f(ta), f(tb), f(J), f(h[:, 0]), f(lim))
        if len(ok) == len(ta):
            return ok
    d_lo, d_hi = _with_friction(T, robot, V, acc[0], acc[1])
    lo_c, hi_c = d_lo[c], d_hi[c]
    ub, lb = _upper(ta + J, tb + J, lo_c, hi_c, h), _lower(ta - J, tb - J, lo_c, hi_c, h)
    return (ub <= lim) & (lb >= -lim)


def certify_arc_torques(robot, motion, wrenches: np.ndarray, steps: np.ndarray, limit: np.ndarray,
                        skip: Optional[np.ndarray] = None, sample_torques=None) -> ArcTorqueReport:
    """Certify |τ_j(t)| ≤ ``limit``_j over every step in ``steps`` of ``motion`` (a StepMotion), or find where it
    is not. ``wrenches`` (N, 6): the world wrench at the TCP at each sample; inside a step the wrench of its two
    samples applies when they agree, none otherwise (a follow goal's window starts and ends at samples).
    ``skip`` (N−1, dof) bool: steps and joints not to certify (already violated at a sample).
    ``sample_torques``: (before, after) (N, dof) drivetrain torques at the samples with the motion's one-sided
    accelerations and the sample's wrench (TrajectoryQuantities.motion_torques), reused at piece ends that are
    samples."""
    steps = np.asarray(steps, dtype=int)
    if len(steps) == 0:
        return ArcTorqueReport([], 0, 0, 0)
    c = _Certification(robot, motion, wrenches, limit, sample_torques)
    steps, step_open = _whole_steps(c, steps, skip)
    if len(steps) == 0:
        return ArcTorqueReport(c.violations(), 0, c.evaluations, 0)
    pieces_total, depth = _bisect(c, _first_pieces(c, steps, step_open), PIECES_PER_STEP * len(steps))
    return ArcTorqueReport(c.violations(), pieces_total, c.evaluations, depth)


class _Certification:
    """One certification's inputs, the violations found so far ((step, joint) → the first or a certain one) and
    the torque evaluations made."""

    def __init__(self, robot, motion, wrenches: np.ndarray, limit: np.ndarray, sample_torques):
        self.robot, self.motion, self.sample_torques = robot, motion, sample_torques
        self.dof = motion.q.shape[1]
        self.dyn = IntervalDynamics(robot)
        self.W = np.asarray(wrenches, dtype=float)
        self.lim = np.asarray(limit, dtype=float)
        self.evaluations = 0
        self.found: dict = {}

    def record(self, k, j, t, value, over) -> None:
        key = (int(k), int(j))
        if key not in self.found or (over and not self.found[key].certified_over):
            self.found[key] = ArcTorqueViolation(int(k), int(j), float(t), float(value), over)

    def violations(self) -> List[ArcTorqueViolation]:
        return sorted(self.found.values(), key=lambda v: (v.step, v.joint))

    def decided(self, k_arr) -> np.ndarray:
        """(piece, joint) bool: a violation is recorded for the piece's step and the joint."""
        return np.array([[(int(k), j) in self.found for j in range(self.dof)] for k in k_arr])

    def arc2_of(self, k, a, b):  # the joints on their second arc over the piece [a, b] of step k
        return ((a + b) / 2)[:, None] >= self.motion.tau[k]

    def wrench_of(self, k):
        same = np.all(self.W[k] == self.W[k + 1], axis=1)
        return np.where(same[:, None], self.W[k], 0.0)

    def torque(self, k, s, arc2, wr):
        q, v = _piece_state(self.motion, k, s, arc2)
        acc = np.where(arc2, self.motion.a2[k], self.motion.a1[k])
        self.evaluations += len(k)
        has = np.any(wr != 0, axis=1)
        return self.robot.drivetrain_torques(q, v, acc, wr if np.any(has) else None)

    def end_torque(self, k, s, arc2, wr, at_sample, sample, side):
        """τ at piece ends s of steps k: the samples' own one-sided torques where the end is a sample under the
        same wrench (the motion passes through the sample exactly), else evaluated."""
        out = np.empty((len(k), self.dof))
        reuse = at_sample & np.all(self.W[sample] == wr, axis=1) if self.sample_torques is not None else \
            np.zeros(len(s), bool)
        if np.any(reuse):
            out[reuse] = self.sample_torques[side][sample[reuse]]
        if not np.all(reuse):
            out[~reuse] = self.torque(k[~reuse], s[~reuse], arc2[~reuse], wr[~reuse])
        return out


def _whole_steps(c: _Certification, steps: np.ndarray, skip: Optional[np.ndarray]):
    """Whole steps first: τ just after sample k and just before k + 1, the groups' bounds. → (the steps left,
    (step, joint) bool: still to decide)."""
    motion, lim = c.motion, c.lim
    h_all = motion.h[steps, 0]
    zero = np.zeros(len(steps))
    w_st = c.wrench_of(steps)
    ta_st = c.end_torque(steps, zero, c.arc2_of(steps, zero, zero), w_st, np.ones(len(steps), bool), steps, 1)
    before = motion.tau[steps] < h_all[:, None]  # the acceleration just before sample k + 1: the second arc's
    tb_st = c.end_torque(steps, h_all, before, w_st, np.ones(len(steps), bool), steps + 1, 0)
    step_open = np.ones((len(steps), c.dof), dtype=bool)
    if skip is not None:
        step_open &= ~skip[steps]
    for tv, s in ((ta_st, zero), (tb_st, h_all)):  # a non-finite torque (huge input) is reported, not split
        for p, j in zip(*np.nonzero(step_open & ((np.abs(tv) > lim) | ~np.isfinite(tv)))):
            c.record(steps[p], j, motion.t[steps[p]] + s[p], tv[p, j], bool(np.abs(tv[p, j]) > lim[j]))
            step_open[p, j] = False
    if np.any(step_open):
        step_open &= ~_step_prefilter(c.dyn, c.robot, motion, c.W, steps, ta_st, tb_st, lim)
    return steps[np.any(step_open, axis=1)], step_open[np.any(step_open, axis=1)]


def _first_pieces(c: _Certification, steps: np.ndarray, step_open: np.ndarray) -> tuple:
    """The steps left, cut at their joints' switch instants where the acceleration changes (sorted, duplicates
    and empty pieces dropped), with their end torques; piece ends above the limit are recorded. → (k, s0, s1,
    τ after s0, τ before s1, open, arc2, wrench) per piece."""
    motion, lim = c.motion, c.lim
    h = motion.h[steps, 0]
    tau = motion.tau[steps]
    inner = np.where((tau > 0) & (tau < h[:, None]) & (motion.a1[steps] != motion.a2[steps]), tau, np.nan)
    cuts = np.sort(np.column_stack([np.zeros_like(h), inner, h]), axis=1)  # nan last
    a, b = cuts[:, :-1], cuts[:, 1:]
    ok = (b > a)  # False for nan and repeated cuts
    si, ci = np.nonzero(ok)
    k_arr, s0, s1 = steps[si], a[si, ci], b[si, ci]
    open_ = step_open[si].copy()  # (piece, joint) still to decide
    arc2 = c.arc2_of(k_arr, s0, s1)
    wr = c.wrench_of(k_arr)
    ta = c.end_torque(k_arr, s0, arc2, wr, s0 == 0, k_arr, 1)  # just after sample k
    tb = c.end_torque(k_arr, s1, arc2, wr, s1 == motion.h[k_arr, 0], k_arr + 1, 0)  # just before sample k + 1
    # piece ends above the limit (switch instants, and samples with the piece's acceleration)
    for tv, s in ((ta, s0), (tb, s1)):
        for p, j in zip(*np.nonzero(open_ & ((np.abs(tv) > lim) | ~np.isfinite(tv)))):
            c.record(k_arr[p], j, motion.t[k_arr[p]] + s[p], tv[p, j], bool(np.abs(tv[p, j]) > lim[j]))
    if c.found:
        open_ &= ~c.decided(k_arr)
    return k_arr, s0, s1, ta, tb, open_, arc2, wr


def _bisect(c: _Certification, pieces: tuple, budget: int) -> Tuple[int, int]:
    """Bound each open piece (its q and q̇ intervals, the torque rate's bounds), certify it or split it in two at
    its middle (where τ is evaluated), down to MAX_DEPTH or until ``budget`` pieces were bounded; what is left
    undecided is recorded as not certified. → (pieces bounded, depth reached)."""
    motion, lim, robot = c.motion, c.lim, c.robot
    k_arr, s0, s1, ta, tb, open_, arc2, wr = pieces
    depth = 0
    pieces_total = 0
    while True:
        live = np.any(open_, axis=1)
        if not np.any(live):
            break
        k_arr, s0, s1, ta, tb, open_, arc2, wr = (x[live] for x in (k_arr, s0, s1, ta, tb, open_, arc2, wr))
        pieces_total += len(k_arr)
        delta = s1 - s0
        qa, va = _piece_state(motion, k_arr, s0, arc2)
        qb, vb = _piece_state(motion, k_arr, s1, arc2)
        acc = np.where(arc2, motion.a2[k_arr], motion.a1[k_arr])
        # q over the piece: its quadratic's ends and vertex (where q̇ changes sign inside)
        with np.errstate(divide="ignore", invalid="ignore"):
            sv = np.where(acc != 0, -va / np.where(acc != 0, acc, 1.0), -1.0)
        inside = (sv > 0) & (sv < delta[:, None])
        qv = np.where(inside, qa + va * sv / 2, qa)  # q at the vertex: qa + va·sv + acc·sv²/2 = qa + va·sv/2
        Q = _interval(np.minimum(np.minimum(qa, qb), qv), np.maximum(np.maximum(qa, qb), qv))
        V = _interval(np.minimum(va, vb), np.maximum(va, vb))
        d_lo, d_hi = _rate_bounds(c.dyn, robot, Q, V, acc, acc, wr)
        ub, lb = _bounds(ta, tb, d_lo, d_hi, delta[:, None])
        certified = (ub <= lim) & (lb >= -lim)
        open_ &= ~certified
        for p, j in zip(*np.nonzero(open_ & ~(np.isfinite(ub) & np.isfinite(lb)))):  # no bound to split on
            c.record(k_arr[p], j, motion.t[k_arr[p]] + (s0[p] + s1[p]) / 2, np.inf, False)
            open_[p, j] = False
        if not np.any(open_):
            break
        live = np.any(open_, axis=1)
        k_arr, s0, s1, ta, tb, open_, arc2, wr, ub, lb = (x[live] for x in (k_arr, s0, s1, ta, tb, open_, arc2, wr,
                                                                               ub, lb))
        sm = (s0 + s1) / 2
        tm = c.torque(k_arr, sm, arc2, wr)
        over = open_ & (np.abs(tm) > lim)
        for p, j in zip(*np.nonzero(over)):
            c.record(k_arr[p], j, motion.t[k_arr[p]] + sm[p], tm[p, j], True)
        if c.found:
            open_ &= ~c.decided(k_arr)
        if depth >= MAX_DEPTH or pieces_total + 2 * int(np.count_nonzero(np.any(open_, axis=1))) > budget:
            for p, j in zip(*np.nonzero(open_)):
                b = ub[p, j] if ub[p, j] > lim[j] else lb[p, j]
                c.record(k_arr[p], j, motion.t[k_arr[p]] + sm[p], b, False)
            break
        depth += 1
        # split: [s0, sm] and [sm, s1]
        k_arr, arc2, wr, open_ = (np.concatenate([x, x]) for x in (k_arr, arc2, wr, open_))
        s0, s1 = np.concatenate([s0, sm]), np.concatenate([sm, s1])
        ta, tb = np.concatenate([ta, tm]), np.concatenate([tm, tb])
    return pieces_total, depth


def arc_torque_steps(n: int, k0: int, k1: int) -> np.ndarray:
    """Steps k0 → k0+1 … k1−1 → k1 of an n-sample trajectory."""
    return np.arange(max(k0, 0), min(k1, n - 1))


__all__ = ["ArcTorqueReport", "ArcTorqueViolation", "certify_arc_torques", "arc_torque_steps", "MAX_DEPTH"]
