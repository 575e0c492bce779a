"""toppra's rest-to-rest TOPP-RA passes with its seidel LP solver, compiled (numba): the controllable sets (backward)
and the forward pass of :func:`robodesign.solvers.toppra_loop.rest_to_rest` in one call, without a Python call per
stage LP (issue 25: the seidel calls were the time scaling's largest part); and the time scaling's sampling of the
profile that comes out (:func:`profile_rows`, :func:`zoh_rows`: the numbers of its numpy calls, issue 25, round 8).

Adapted from toppra (MIT licence, © Hung Pham; https://github.com/hungpham2511/toppra):
``toppra/solverwrapper/cy_seidel_solverwrapper.pyx`` (``cy_solve_lp1d``, ``cy_solve_lp2d``,
``seidelWrapper.solve_stagewise_optim``) and ``toppra/algorithm/reachabilitybased/reachability_algorithm.py``
(``compute_controllable_sets``/``_one_step`` and the forward ``compute_parameterization`` loop). The kernels make
**the same floating-point operations in the same order** as toppra's compiled solver (its build has no fused
multiply-adds and squares by multiplication; the constants are its ``TINY = 1e-10``, ``SMALL = 1e-8``, ±1e8 variable
bounds and ±1e10 bounds of the 1-D sub-problems, and ``toppra.constants.TINY = 1e-8`` of the forward step), so the
path velocities are toppra's **bit for bit** (tests/test_topp_kernel.py compares them with toppra's own
``compute_parameterization`` on the planner's PTP_3 paths and on random paths of two IMPROV arms and the built-in
arm, torque limits down to a fifth).

Where this kernel is not sure to follow toppra it does not guess: it returns a status other than 0 and the caller
runs toppra (as :func:`~robodesign.solvers.toppra_loop.rest_to_rest` returns None where toppra's loop takes another
branch). That is every LP toppra finds infeasible or where its 1-D sub-problem is unbounded, a zero row it would
divide by, a NaN controllable set, an uncontrollable start, and, in the forward pass (toppra 0.6.10 solves a 1-D LP
in u when x is fixed), a fixed x outside the stage's own x bounds, a u that only its ±1e8 bounds limit, or a step
too short for the objective's threshold.

Readiness as :mod:`robodesign.model.sweep_kernel`: a process that finds no stamp of a finished compilation starts
one background process (``python -m robodesign.solvers.topp_kernel``) that compiles into numba's on-disk cache,
and runs toppra meanwhile (the same numbers). ``ROBODESIGN_JIT=0`` switches the kernel off, ``ROBODESIGN_JIT=wait``
compiles at first use.
"""
from __future__ import annotations

import sys

import numpy as np

from robodesign.core.jit_cache import KernelModule, njit

# toppra's cy_seidel_solverwrapper constants
LP_TINY = 1e-10
LP_SMALL = 1e-8
VAR_MIN = -100000000.0
VAR_MAX = 100000000.0
LP_INF = 10000000000.0
# toppra.constants: the forward step's margin (TINY) and the start test (SMALL)
STEP_TINY = 1e-8
START_SMALL = 1e-5

#: statuses of :func:`rest_to_rest`: 0 the velocities are toppra's; anything else: run toppra
OK, NAN_SET, INFEASIBLE, DIVIDE, UNCONTROLLABLE, FORWARD_UNSURE = 0, 1, 2, 3, 4, 5


@njit(cache=True, nogil=True)
def _projected(a, b, c, k, index_map, zp0, zp1, d0, d1, vv, low0, low1, high0, high1, a_1d,
               b_1d):  # pragma: no cover - compiled
    """cy_solve_lp2d's step at its k-th considered row (violated): the first k rows and the box projected onto that
    row's line (through zp along d), then toppra's cy_solve_lp1d on them within ±1e10 with the objective vv.
    Returns (status, the line parameter, the 1-D active row)."""
    n1 = 4 + k
    for j in range(n1):
        if j == k:
            aj, bj, cj = -1.0, 0.0, low0
        elif j == k + 1:
            aj, bj, cj = 1.0, 0.0, -high0
        elif j == k + 2:
            aj, bj, cj = 0.0, -1.0, low1
        elif j == k + 3:
            aj, bj, cj = 0.0, 1.0, -high1
        else:
            r = index_map[j]
            aj, bj, cj = a[r], b[r], c[r]
        denom = d0 * aj + d1 * bj
        if denom > LP_TINY:
            t_limit = -(cj + zp1 * bj + zp0 * aj) / denom
            a_1d[j] = 1.0
            b_1d[j] = -t_limit
        elif denom < -LP_TINY:
            t_limit = -(cj + zp1 * bj + zp0 * aj) / denom
            a_1d[j] = -1.0
            b_1d[j] = t_limit
        else:
            if cj + zp1 * bj + zp0 * aj > LP_SMALL:
                return INFEASIBLE, 0.0, 0
            a_1d[j] = 0.0
            b_1d[j] = -1.0
    # toppra's cy_solve_lp1d on the projected rows, within ±1e10
    cmin, amin, cmax, amax = -LP_INF, -1, LP_INF, -2
    for j in range(n1):
        if a_1d[j] > LP_TINY:
            x = -b_1d[j] / a_1d[j]
            if x < cmax:
                cmax = x
                amax = j
        elif a_1d[j] < -LP_TINY:
            x = -b_1d[j] / a_1d[j]
            if x > cmin:
                cmin = x
                amin = j
    if cmin > cmax:
        return INFEASIBLE, 0.0, 0
    if abs(vv) < LP_TINY or vv < 0:
        t, act = cmin, amin
    else:
        t, act = cmax, amax
    return OK, t, act


@njit(cache=True, nogil=True)
def _lp2d(v0, v1, a, b, c, low0, low1, high0, high1, active, index_map, a_1d, b_1d,
          out):  # pragma: no cover - compiled
    """toppra's cy_solve_lp2d (maximise v0·u + v1·x subject to a·u + b·x + c ≤ 0 row by row and the box), with
    its warm start ``active`` (updated on success, as seidelWrapper does). Writes (u, x) into ``out``; returns OK,
    INFEASIBLE (toppra's result 0, or a 1-D sub-problem whose active row is one of its ±1e10 bounds) or DIVIDE (a
    violated zero row: toppra would raise ZeroDivisionError)."""
    nrows = a.shape[0]
    if low0 > high0 or low1 > high1:
        return INFEASIBLE
    if v0 > LP_TINY:
        cur0 = high0
        act0 = -2
    else:
        cur0 = low0
        act0 = -1
    if v1 > LP_TINY:
        cur1 = high1
        act1 = -4
    else:
        cur1 = low1
        act1 = -3
    w0, w1 = active[0], active[1]
    if w0 >= 0 and w0 < nrows and w1 >= 0 and w1 < nrows and w0 != w1:
        index_map[0] = w1
        index_map[1] = w0
        row = 2
        for i in range(nrows):
            if i != w0 and i != w1:
                index_map[row] = i
                row += 1
    else:
        for i in range(nrows):
            index_map[i] = i
    for k in range(nrows):
        i = index_map[k]
        if a[i] * cur0 + b[i] * cur1 + c[i] < LP_TINY:
            continue
        act0 = i
        den = a[i] * a[i] + b[i] * b[i]
        if den == 0.0:
            return DIVIDE
        zp0 = -a[i] * c[i] / den
        zp1 = -b[i] * c[i] / den
        d0 = -b[i]
        d1 = a[i]
        vv = d0 * v0 + d1 * v1
        st, t, act = _projected(a, b, c, k, index_map, zp0, zp1, d0, d1, vv, low0, low1, high0, high1, a_1d, b_1d)
        if st != OK:
            return st
        cur0 = zp0 + t * d0
        cur1 = zp1 + t * d1
        if act < 0:      # toppra compares it unsigned with k: none of its cases, result 0
            return INFEASIBLE
        if act < k:
            act1 = index_map[act]
        elif act == k:
            act1 = -1
        elif act == k + 1:
            act1 = -2
        elif act == k + 2:
            act1 = -3
        elif act == k + 3:
            act1 = -4
        else:
            return INFEASIBLE
    out[0] = cur0
    out[1] = cur1
    active[0] = act0
    active[1] = act1
    return OK


@njit(cache=True, nogil=True)
def _controllable(a, b, c, low, high, deltas, K):  # pragma: no cover - compiled
    """toppra's compute_controllable_sets(0, 0) into K (N+1, 2): per stage from the last, x_upper then x_lower
    (its _one_step), each a 2-D LP with its own warm start. Returns OK or why toppra must run instead."""
    N = len(deltas)
    nC = a.shape[1]
    index_map = np.zeros(nC, np.int64)
    a_1d = np.zeros(nC + 4)
    b_1d = np.zeros(nC + 4)
    up = np.zeros(2, np.int64)
    down = np.zeros(2, np.int64)
    out = np.zeros(2)
    K[N, 0] = 0.0
    K[N, 1] = 0.0
    for i in range(N - 1, -1, -1):
        k0, k1 = K[i + 1, 0], K[i + 1, 1]
        if k0 != k0 or k1 != k1:
            return NAN_SET
        a[i, 0] = -2 * deltas[i]
        b[i, 0] = -1.0
        c[i, 0] = k0
        a[i, 1] = 2 * deltas[i]
        b[i, 1] = 1.0
        c[i, 1] = -k1
        # x_upper: g = (1e-9, -1), toppra's lower solver (g[1] ≤ 0); x_lower: g = (-1e-9, 1), its upper solver
        st = _lp2d(-1e-9, 1.0, a[i], b[i], c[i], low[i, 0], low[i, 1], high[i, 0], high[i, 1], down, index_map,
                   a_1d, b_1d, out)
        if st != OK:
            return st
        x_up = out[1]
        st = _lp2d(1e-9, -1.0, a[i], b[i], c[i], low[i, 0], low[i, 1], high[i, 0], high[i, 1], up, index_map,
                   a_1d, b_1d, out)
        if st != OK:
            return st
        K[i, 0] = out[1]
        K[i, 1] = x_up
        if K[i, 0] < 0:
            K[i, 0] = 0
        if K[i, 0] != K[i, 0] or K[i, 1] != K[i, 1]:
            return NAN_SET
    if 0.0 + START_SMALL < K[0, 0] or K[0, 1] + START_SMALL < 0.0:
        return UNCONTROLLABLE
    return OK


@njit(cache=True, nogil=True)
def _forward(a, b, c, low, high, deltas, K, sd):  # pragma: no cover - compiled
    """toppra's forward pass from rest (compute_parameterization's _forward_step loop) into sd: x fixed, the largest
    u of a 1-D LP in u, the next x lowered by its margin and clipped into K. Returns OK or FORWARD_UNSURE."""
    N = len(deltas)
    nC = a.shape[1]
    x = 0.0
    sd[0] = 0.0
    for i in range(N):
        if x != x or x < low[i, 1] or x > high[i, 1]:
            return FORWARD_UNSURE
        d2 = 2 * deltas[i]
        if not d2 > 1e-6:
            return FORWARD_UNSURE
        a[i, 0] = -2 * deltas[i]
        b[i, 0] = -1.0
        c[i, 0] = K[i + 1, 0]
        a[i, 1] = d2
        b[i, 1] = 1.0
        c[i, 1] = -K[i + 1, 1]
        cmin, cmax = low[i, 0], high[i, 0]
        hit = False
        for j in range(nC):
            aj = a[i, j]
            bx = b[i, j] * x + c[i, j]
            if aj > LP_TINY:
                t = -bx / aj
                if t < cmax:
                    cmax = t
                    hit = True
            elif aj < -LP_TINY:
                t = -bx / aj
                if t > cmin:
                    cmin = t
        if cmin > cmax or not hit or cmax != cmax:
            return FORWARD_UNSURE
        x_next = x + 2 * deltas[i] * cmax
        lowered = x_next - STEP_TINY
        scaled = 0.9999 * x_next
        x_next = scaled if scaled > lowered else lowered
        lo = K[i + 1, 0] if not x_next > K[i + 1, 0] else x_next
        x = lo if lo < K[i + 1, 1] else K[i + 1, 1]
        sd[i + 1] = x
    for i in range(N + 1):
        sd[i] = np.sqrt(sd[i])
        if sd[i] != sd[i]:
            return FORWARD_UNSURE
    return OK


@njit(cache=True, nogil=True)
def rest_to_rest(a, b, c, low, high, deltas, sd):  # pragma: no cover - compiled
    """The path velocities of toppra's ``compute_parameterization(0, 0)`` into ``sd`` (N+1,): seidelWrapper's
    coefficient rows ``a``, ``b``, ``c`` (N+1, nC; rows 0 and 1 of every stage are the x-next rows, written
    here as toppra writes them), its bounds ``low``, ``high`` (N+1, 2) and the grid steps ``deltas`` (N,).
    Returns OK or the reason to run toppra instead (module docstring)."""
    K = np.zeros((len(deltas) + 1, 2))
    st = _controllable(a, b, c, low, high, deltas, K)
    if st != OK:
        return st
    return _forward(a, b, c, low, high, deltas, K, sd)


@njit(cache=True, nogil=True)
def _point_rows(qs, qss_r, qss_l, g, ai, bri, bli, x0, finite, fv, fc, use_torque, PA, PBR, PBL,
                PC):  # pragma: no cover - compiled
    """The per-grid-point rows (v = [q̈; τ_up; τ_lo] coefficients a, b right and left, c) of the time scaling's
    DynamicsConstraint.compute_constraint_params (solvers/timing.py), the same operations per element as its
    numpy passes (x0 floored at 1e-8, NaN kept; the viscous tangent's β and γ; rows of an infinite torque limit 0)."""
    N1, dof = qs.shape
    for p in range(N1):
        x = x0[p]
        sq = np.sqrt(x if (x != x or x > 1e-8) else 1e-8)
        for j in range(dof):
            PA[p, j] = qs[p, j]
            PBR[p, j] = qss_r[p, j]
            PBL[p, j] = qss_l[p, j]
            PC[p, j] = 0.0
            if not use_torque:
                continue
            v = qs[p, j]
            beta_up = fv[j] * v / (2 * sq) if v > 0 else 0.0
            gam_up = fc[j] + fv[j] * v * sq / 2 if v > 0 else 0.0
            beta_lo = fv[j] * -v / (2 * sq) if v < 0 else 0.0
            gam_lo = fc[j] + fv[j] * -v * sq / 2 if v < 0 else 0.0
            f = finite[j]
            PA[p, dof + j] = ai[p, j] if f else 0.0
            PA[p, 2 * dof + j] = ai[p, j] if f else 0.0
            PBR[p, dof + j] = bri[p, j] + beta_up if f else 0.0
            PBR[p, 2 * dof + j] = bri[p, j] - beta_lo if f else 0.0
            PBL[p, dof + j] = bli[p, j] + beta_up if f else 0.0
            PBL[p, 2 * dof + j] = bli[p, j] - beta_lo if f else 0.0
            PC[p, dof + j] = g[p, j] + gam_up if f else 0.0
            PC[p, 2 * dof + j] = g[p, j] - gam_lo if f else 0.0


@njit(cache=True, nogil=True)
def constraint_rows(qs, qss_r, qss_l, g, ai, bri, bli, x0, amax, tmax, fv, fc, use_torque, deltas, xbound,
                    a, b, c, low, high):  # pragma: no cover - compiled
    """seidelWrapper's coefficients of TOPPRA([velocity constraint, DynamicsConstraint]) straight from the path terms:
    what DynamicsConstraint.compute_constraint_params (interpolation: stage i at s_i⁺ and at s_{i+1}⁻ with
    x + 2Δu) followed by toppra_loop.seidel_rows (its F picks q̈, −q̈, τ_up, −τ_lo; +0 after each pick; c minus
    the limits) give, bit for bit, into a, b, c (N+1, 2 + 2k) and low, high (N+1, 2). False (nothing usable) when a
    coefficient is not finite (seidel_rows' case)."""
    N1, dof = qs.shape
    nb = 3 if use_torque else 1
    m = nb * dof
    k = 4 * dof if use_torque else 2 * dof      # rows of F: ±q̈, and τ_up, −τ_lo with torques
    finite = np.empty(dof, np.bool_)
    for j in range(dof):
        finite[j] = np.isfinite(tmax[j])
    PA, PBR, PBL, PC = np.empty((N1, m)), np.empty((N1, m)), np.empty((N1, m)), np.empty((N1, m))
    _point_rows(qs, qss_r, qss_l, g, ai, bri, bli, x0, finite, fv, fc, use_torque, PA, PBR, PBL, PC)
    for p in range(N1):
        q = p + 1 if p + 1 < N1 else p
        two_d = 2 * deltas[p] if p + 1 < N1 else 0.0
        for r in range(k):
            col = r if r < dof else r - dof
            sign = 1.0 if (r < dof or (use_torque and 2 * dof <= r < 3 * dof)) else -1.0
            lim = amax[col % dof] if r < 2 * dof else (tmax[col % dof] if finite[col % dof] else 1.0)
            a[p, 2 + r] = PA[p, col] * sign + 0.0
            b[p, 2 + r] = PBR[p, col] * sign + 0.0
            c[p, 2 + r] = (PC[p, col] * sign + 0.0) - lim
            second = PA[q, col] + two_d * PBL[q, col] if p + 1 < N1 else PA[q, col]
            a[p, 2 + k + r] = second * sign + 0.0
            b[p, 2 + k + r] = PBL[q, col] * sign + 0.0
            c[p, 2 + k + r] = (PC[q, col] * sign + 0.0) - lim
        for r in range(2, 2 + 2 * k):
            if not (np.isfinite(a[p, r]) and np.isfinite(b[p, r]) and np.isfinite(c[p, r])):
                return False
        low[p, 0] = VAR_MIN
        high[p, 0] = VAR_MAX
        low[p, 1] = VAR_MIN if VAR_MIN > xbound[p, 0] else xbound[p, 0]
        high[p, 1] = VAR_MAX if VAR_MAX < xbound[p, 1] else xbound[p, 1]
    return True


@njit(cache=True, nogil=True)
def _right_of(a, x):  # pragma: no cover - compiled
    """np.searchsorted(a, x, side="right") for a sorted, x not NaN."""
    lo, hi = 0, len(a)
    while lo < hi:
        mid = (lo + hi) // 2
        if x < a[mid]:
            hi = mid
        else:
            lo = mid + 1
    return lo


@njit(cache=True, nogil=True)
def _left_of(a, x):  # pragma: no cover - compiled
    """np.searchsorted(a, x, side="left") for a sorted, x not NaN."""
    lo, hi = 0, len(a)
    while lo < hi:
        mid = (lo + hi) // 2
        if a[mid] < x:
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True, nogil=True)
def path_orders(breaks, p0, d0, c, length, end, s, left, Q, Q1, Q2):  # pragma: no cover - compiled
    """A BlendedPolyline's q, q' and q'' at the points ``s`` into Q, Q1, Q2 (len(s), dof): its _locate (s clipped to
    [0, length] as np.clip, the piece by searchsorted, on the ``left`` side or the right) and _order, the same
    operations in the same order, so the same numbers bit for bit (tests/test_timing_profile_rows.py)."""
    last_k = len(p0) - 1
    dof = p0.shape[1]
    for j in range(len(s)):
        x = s[j]
        x = x if (x > 0.0 or x != x) else 0.0
        x = x if (x < length or x != x) else length
        k = (_left_of(breaks, x) if left else _right_of(breaks, x)) - 1
        k = min(max(k, 0), last_k)
        sig = x - breaks[k]
        for q in range(dof):
            Q[j, q] = end[q] if x >= length else p0[k, q] + d0[k, q] * sig + 0.5 * c[k, q] * (sig * sig)
            Q1[j, q] = d0[k, q] + c[k, q] * sig
            Q2[j, q] = c[k, q]


@njit(cache=True, nogil=True)
def profile_rows(T_grid, dt_i, sd, u, grid, breaks, p0, d0, c, length, end, t, order,
                 out):  # pragma: no cover - compiled
    """The time scaling's TOPP-RA profile on a BlendedPolyline at the times ``t``, into ``out`` (len(t), dof): with
    ``order`` 1 the velocity q'(s(t))·ṡ(t), with 0 the position q(s(t)) (timing._toppra_profile's ``velocity`` and
    ``position``: its s_of_t, then the path's _locate and _order). The same operations in the same order as those
    numpy calls, element by element: np.clip as max-then-min with NaN kept, np.maximum/np.minimum as numpy's
    vector loops (the second operand when both are zeros), ``x ** 2`` as x·x; so the same numbers bit for bit
    (tests/test_timing_profile_rows.py)."""
    last_i, last_k = len(dt_i) - 1, len(p0) - 1
    dof = p0.shape[1]
    for j in range(len(t)):
        tj = t[j]
        i = _right_of(T_grid, tj) - 1
        i = min(max(i, 0), last_i)
        tau = tj - T_grid[i]
        tau = tau if (tau > 0.0 or tau != tau) else 0.0
        tau = tau if (tau < dt_i[i] or tau != tau) else dt_i[i]
        s = grid[i] + sd[i] * tau + 0.5 * u[i] * (tau * tau)
        s = s if (s < grid[i + 1] or s != s) else grid[i + 1]
        s = s if (s > 0.0 or s != s) else 0.0          # the path's own clip to [0, length]
        s = s if (s < length or s != s) else length
        k = min(max(_right_of(breaks, s) - 1, 0), last_k)
        sig = s - breaks[k]
        if order == 1:
            sdot = sd[i] + u[i] * tau
            sdot = sdot if (sdot > 0.0 or sdot != sdot) else 0.0
            for q in range(dof):
                out[j, q] = (d0[k, q] + c[k, q] * sig) * sdot
        elif s >= length:
            for q in range(dof):
                out[j, q] = end[q]
        else:
            for q in range(dof):
                out[j, q] = p0[k, q] + d0[k, q] * sig + 0.5 * c[k, q] * (sig * sig)


@njit(cache=True, nogil=True)
def _pairwise_block(a, lo, n):  # pragma: no cover - compiled
    """numpy's pairwise summation of the n ≤ 128 contiguous a[lo:lo + n]: sequential from +0 below 8 terms, else
    eight accumulators, combined in pairs, then the rest in sequence."""
    if n < 8:
        res = 0.0
        for i in range(lo, lo + n):
            res += a[i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    while i < n - n % 8:
        r0 += a[lo + i]
        r1 += a[lo + i + 1]
        r2 += a[lo + i + 2]
        r3 += a[lo + i + 3]
        r4 += a[lo + i + 4]
        r5 += a[lo + i + 5]
        r6 += a[lo + i + 6]
        r7 += a[lo + i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@njit(cache=True, nogil=True)
def _pairwise(a, lo, n):  # pragma: no cover - compiled
    """numpy's pairwise summation of the n contiguous a[lo:lo + n] (np.sum adds it to +0): blocks of ≤ 128 terms,
    a longer run split at half its length rounded down to a multiple of 8, the two halves' sums added; the same
    additions in the same order (without recursion, which numba's cache does not load safely)."""
    if n <= 128:
        return _pairwise_block(a, lo, n)
    task_lo = np.empty(192, np.int64)     # a stack of runs to sum; length −1: add the last two sums
    task_n = np.empty(192, np.int64)
    sums = np.empty(96)
    task_lo[0], task_n[0] = lo, n
    nt, ns = 1, 0
    while nt > 0:
        nt -= 1
        start, m = task_lo[nt], task_n[nt]
        if m < 0:
            ns -= 1
            sums[ns - 1] = sums[ns - 1] + sums[ns]
        elif m <= 128:
            sums[ns] = _pairwise_block(a, start, m)
            ns += 1
        else:
            half = m // 2
            half -= half % 8
            task_lo[nt], task_n[nt] = 0, -1
            task_lo[nt + 1], task_n[nt + 1] = start + half, m - half
            task_lo[nt + 2], task_n[nt + 2] = start, half
            nt += 3
    return sums[0]


@njit(cache=True, nogil=True)
def zoh_rows(q0, q1, V, h, Q, A):  # pragma: no cover - compiled
    """timing._zoh_from_velocity's samples for n = len(V) − 1 ≥ 1 steps, in place: V (its ends set to 0, then the
    end-point bump added), Q and A (n + 1, dof). The same operations in the same order as its numpy calls
    (np.sum's pairwise summation of the bump's weights and, for one joint, of the increments; a column sum of
    several joints and np.linalg.norm's row sums in sequence; cumsum in sequence), so the same numbers bit for bit
    (tests/test_timing_profile_rows.py)."""
    m, dof = V.shape
    n = m - 1
    hh = 0.5 * h
    for j in range(dof):
        V[0, j] = 0.0
        V[n, j] = 0.0
    r = np.empty(dof)
    col = np.empty(n)
    for j in range(dof):
        for k in range(n):
            col[k] = hh * (V[k, j] + V[k + 1, j])
        if dof == 1:
            tot = 0.0 + _pairwise(col, 0, n)
        else:
            tot = 0.0
            for k in range(n):
                tot += col[k]
        r[j] = (q1[j] - q0[j]) - tot
    w = np.empty(m)
    sq = np.empty(dof)
    for k in range(m):
        for j in range(dof):
            sq[j] = V[k, j] * V[k, j]
        w[k] = np.sqrt(0.0 + _pairwise(sq, 0, dof))
    for k in range(n):
        col[k] = hh * (w[k] + w[k + 1])
    W = 0.0 + _pairwise(col, 0, n)
    if W > 0:
        for k in range(m):
            f = w[k] / W
            for j in range(dof):
                V[k, j] += f * r[j]
    for j in range(dof):
        acc = 0.0
        for k in range(n):
            a = (V[k + 1, j] - V[k, j]) / h
            A[k, j] = a
            step = V[k, j] * h + 0.5 * a * h * h
            acc = step if k == 0 else acc + step
            Q[k + 1, j] = q0[j] + acc
        A[n, j] = 0.0
        Q[0, j] = q0[j]
        Q[n, j] = q1[j]


# ---------------------------------------------------------------------------------------------------------
# readiness: compile in the background, never stall a caller on the compilation (core.jit_cache.KernelModule)
# ---------------------------------------------------------------------------------------------------------
def _warm() -> None:
    """The kernel called once on a tiny problem (compiles or loads it)."""
    a = np.zeros((2, 3))
    rest_to_rest(a, a.copy(), a.copy() - 1.0, np.full((2, 2), VAR_MIN), np.full((2, 2), VAR_MAX), np.ones(1),
                 np.zeros(2))
    z = np.zeros((2, 1))
    for writeable in (True, False):   # the robot's limits and friction vectors are read-only arrays
        x0, one = np.ones(2), np.ones(1)
        x0.flags.writeable = one.flags.writeable = writeable
        constraint_rows(z, z, z, z, z, z, z, x0, one, one, one, one, True, np.ones(1), np.zeros((2, 2)),
                        np.zeros((2, 10)), np.zeros((2, 10)), np.zeros((2, 10)), np.zeros((2, 2)), np.zeros((2, 2)))
    two, line = np.array([0.0, 1.0]), np.zeros((1, 1))
    for order in (0, 1):
        profile_rows(two, np.ones(1), np.ones(2), np.zeros(1), two, two, line, line + 1.0, line, 1.0, np.ones(1),
                     two, order, np.empty((2, 1)))
    for left in (True, False):
        path_orders(two, line, line + 1.0, line, 1.0, np.ones(1), two, left, np.empty((2, 1)), np.empty((2, 1)),
                    np.empty((2, 1)))
    for dof in (1, 2):
        zoh_rows(np.zeros(dof), np.ones(dof), np.ones((3, dof)), 0.1, np.empty((3, dof)), np.empty((3, dof)))


KERNELS = KernelModule("robodesign.solvers.topp_kernel", __file__, rest_to_rest,
                       ("rest_to_rest", "_controllable", "_forward", "_lp2d", "_projected", "constraint_rows",
                        "_point_rows", "_right_of", "_left_of", "path_orders", "profile_rows", "_pairwise_block",
                        "_pairwise", "zoh_rows"), _warm)
available, compiled, warm_up, ready = KERNELS.available, KERNELS.compiled, KERNELS.warm_up, KERNELS.ready
compile_into_cache = KERNELS.compile_into_cache

if __name__ == "__main__":
    sys.exit(KERNELS.main())
