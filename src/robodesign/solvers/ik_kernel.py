"""The compiled inner loop of :func:`robodesign.solvers.ik.solve_ik` (numba).

One Levenberg–Marquardt descent (``descend``) runs here without Python overhead: forward kinematics and
the world Jacobian of the TCP over the serial chain from the world to the TCP, the goal's dead-zone
residual rows and their Jacobian, the damped step (Cholesky of a ≤ 7×7 matrix), the step cap, clamping
and the stall test — the same arithmetic as the Python loop it replaces (``ik.py``), about 1 µs per
iteration instead of 15–20 µs.

What it covers (everything else keeps the Python loop, which is the reference):

* joints: revolute and prismatic about ±z of the joint frame (every robot :class:`~robodesign.model.robot.Robot`
  builds: ``JointModelRZ``/``PZ`` and their ``…Unaligned(0, 0, −1)`` for reversed modules);
* goal constraints with one tolerance interval each: ``x``, ``y``, ``z``, ``N_x``, ``N_y``, ``N_z`` (in any
  frame), ``r_sph``, ``Theta_R`` and ``r_cyl``; not the periodic ``phi_*``/``theta`` rows, multi-piece
  tolerances or the R/P/Y, Euler and quaternion fall-backs.

The proof of validity (:func:`proven_valid`): a converged descent whose values prove ``ToleratedPose.valid`` true
spares the caller that call (the conditions and the margin: :mod:`.ik_proof`).

``ROBODESIGN_JIT=0`` in the environment switches the kernel off (the Python loop then runs everything);
tests compare both on the same inputs (same solutions to 1e-8).

No cold-start stall (:func:`ready`): compiling the kernels takes about 5 s (on a quiet machine) and is
cached on disk (numba's cache: ``__pycache__`` next to this file, or ``NUMBA_CACHE_DIR``), where later
processes load it in about 0.1 s. A process that finds no compiled kernels in the cache does not wait
for them: it starts one background process (``python -m robodesign.solvers.ik_kernel``; niced, in the
command's session, its own process group) that compiles them into the cache, and runs the Python loop
for the rest of its life; the processes it starts (evaluation workers) do the same (it sets
``ROBODESIGN_JIT=0`` in its environment). Later commands use the compiled loop. So the first command after
an install is not held up by the compilation (tests/test_cold_start.py: within 20 % of the pure-Python
path), and a run never switches loops midway: the two loops agree to about 1e-15 rad, not bit for bit, so a
switch at a moment that depends on the machine's load would make a seed's results differ in their last
digits between runs and between worker counts. To compile ahead of a long first run:
``python -m robodesign.solvers.ik_kernel`` (or ``ROBODESIGN_JIT=wait``: compile in the process at the first
use; :func:`warm_up` does the same on request). A stamp file beside numba's cache
(``robodesign_ik_kernel.ready``) records that the kernels are compiled for this numba, Python (its resolved
executable), CPU and source; concurrent processes serialise the compilation with a lock file beside it.
"""
from __future__ import annotations

import math
import os
import subprocess
import sys
import weakref
from pathlib import Path
from typing import Optional

import numpy as np

from robodesign.core.jit_cache import NUMBA_IMPORTED, KernelCache, background_compile, njit

__all__ = ["available", "ChainKernel", "chain_kernel", "compile_goal", "fk_jacobian", "goal_rows", "lm_descend",
           "lm_repair", "lm_batch", "warm_up"]

# term kinds of the goal program
K_P_ROW, K_R_ROW, K_SPH, K_THETA, K_CYL = 0, 1, 2, 3, 4
#: the bounds on the entries of T's (and Ninv's) rotation and position (m) under which :func:`proven_valid` holds
PROOF_ROT, PROOF_POS = 1.01, 16.0
_ROWS = {K_P_ROW: 1, K_R_ROW: 1, K_SPH: 3, K_THETA: 3, K_CYL: 2}

_IMPORTED = NUMBA_IMPORTED  # without numba the Python loop runs


def _jit_mode() -> str:
    return os.environ.get("ROBODESIGN_JIT", "1").strip().lower()


def available() -> bool:
    """True when numba imports and ``ROBODESIGN_JIT`` is not ``0``."""
    if _jit_mode() in ("0", "false", "no", "off"):
        return False
    return _IMPORTED


# ---------------------------------------------------------------------------------------------------------
# kernels (module level, so that numba's on-disk cache finds them again in a new process)
# ---------------------------------------------------------------------------------------------------------
@njit(cache=True, nogil=True)
def fk_jacobian(q, chain, kind, sign, iq, tcp, T, Jv, Jw):
    """T (4×4 world pose of the TCP) and its world-frame Jacobian (Jv linear, Jw angular; columns by
    joint index). ``chain[k]`` is the 4×4 placement of chain joint k in its parent (the previous
    chain joint, the world for k = 0); ``kind`` 0 revolute / 1 prismatic about ``sign``·z."""
    nk = chain.shape[0]
    fk_jacobian_ws(q, chain, kind, sign, iq, tcp, T, Jv, Jw, np.empty((4, 4)), np.empty((4, 4)),
                   np.empty((nk, 3)), np.empty((nk, 3)))

@njit(cache=True, nogil=True)
def fk_jacobian_ws(q, chain, kind, sign, iq, tcp, T, Jv, Jw, M, tmp, origins, axes):
    """:func:`fk_jacobian` with its scratch arrays given (M, tmp: 4×4; origins, axes: k×3): no allocation
    in the LM loop."""
    nk = chain.shape[0]
    n = q.shape[0]
    for r in range(4):
        for c in range(4):
            M[r, c] = 1.0 if r == c else 0.0
    for j in range(n):
        for r in range(3):
            Jv[r, j] = 0.0
            Jw[r, j] = 0.0
    for k in range(nk):
        P = chain[k]
        # tmp = M @ P
        for r in range(3):
            for c in range(4):
                s = M[r, 0] * P[0, c] + M[r, 1] * P[1, c] + M[r, 2] * P[2, c]
                if c == 3:
                    s += M[r, 3]
                tmp[r, c] = s
        v = q[iq[k]] * sign[k]
        if kind[k] == 0:
            ca, sa = math.cos(v), math.sin(v)
            for r in range(3):
                a, b = tmp[r, 0], tmp[r, 1]
                M[r, 0] = a * ca + b * sa
                M[r, 1] = -a * sa + b * ca
                M[r, 2] = tmp[r, 2]
                M[r, 3] = tmp[r, 3]
        else:
            for r in range(3):
                M[r, 0] = tmp[r, 0]
                M[r, 1] = tmp[r, 1]
                M[r, 2] = tmp[r, 2]
                M[r, 3] = tmp[r, 3] + tmp[r, 2] * v
        for r in range(3):
            origins[k, r] = M[r, 3]
            axes[k, r] = M[r, 2] * sign[k]
    for r in range(3):
        for c in range(4):
            s = M[r, 0] * tcp[0, c] + M[r, 1] * tcp[1, c] + M[r, 2] * tcp[2, c]
            if c == 3:
                s += M[r, 3]
            T[r, c] = s
    T[3, 0] = 0.0
    T[3, 1] = 0.0
    T[3, 2] = 0.0
    T[3, 3] = 1.0
    px, py, pz = T[0, 3], T[1, 3], T[2, 3]
    for k in range(nk):
        j = iq[k]
        zx, zy, zz = axes[k, 0], axes[k, 1], axes[k, 2]
        if kind[k] == 0:
            dx, dy, dz = px - origins[k, 0], py - origins[k, 1], pz - origins[k, 2]
            Jv[0, j] += zy * dz - zz * dy
            Jv[1, j] += zz * dx - zx * dz
            Jv[2, j] += zx * dy - zy * dx
            Jw[0, j] += zx
            Jw[1, j] += zy
            Jw[2, j] += zz
        else:
            Jv[0, j] += zx
            Jv[1, j] += zy
            Jv[2, j] += zz

@njit(cache=True, nogil=True)
def log3(R, out):
    """pinocchio.log3 (rotation vector of R, angle in [0, π]); returns the angle."""
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    c = 0.5 * (tr - 1.0)
    wx = 0.5 * (R[2, 1] - R[1, 2])
    wy = 0.5 * (R[0, 2] - R[2, 0])
    wz = 0.5 * (R[1, 0] - R[0, 1])
    s = math.sqrt(wx * wx + wy * wy + wz * wz)
    th = math.atan2(s, c)
    if th < 1e-4:
        f = 1.0 + th * th / 6.0            # θ / sin θ
        out[0], out[1], out[2] = wx * f, wy * f, wz * f
    elif th < math.pi - 1e-3:
        f = th / s
        out[0], out[1], out[2] = wx * f, wy * f, wz * f
    else:
        # near π: the axis from the symmetric part, R + Rᵀ = 2cI + 2(1 − c) a aᵀ
        d = 1.0 - c
        ax = math.sqrt(max(0.0, (R[0, 0] - c) / d))
        ay = math.sqrt(max(0.0, (R[1, 1] - c) / d))
        az = math.sqrt(max(0.0, (R[2, 2] - c) / d))
        if ax >= ay and ax >= az:
            ay = (R[0, 1] + R[1, 0]) / (2.0 * d * ax)
            az = (R[0, 2] + R[2, 0]) / (2.0 * d * ax)
            if wx < 0.0:
                ax, ay, az = -ax, -ay, -az
        elif ay >= az:
            ax = (R[0, 1] + R[1, 0]) / (2.0 * d * ay)
            az = (R[1, 2] + R[2, 1]) / (2.0 * d * ay)
            if wy < 0.0:
                ax, ay, az = -ax, -ay, -az
        else:
            ax = (R[0, 2] + R[2, 0]) / (2.0 * d * az)
            ay = (R[1, 2] + R[2, 1]) / (2.0 * d * az)
            if wz < 0.0:
                ax, ay, az = -ax, -ay, -az
        nrm = math.sqrt(ax * ax + ay * ay + az * az)
        out[0], out[1], out[2] = ax / nrm * th, ay / nrm * th, az / nrm * th
    return th

@njit(cache=True, nogil=True)
def jlog3(th, w, out):
    """pinocchio.Jlog3: I + ½[w]× + (1/θ² − cot(θ/2)/(2θ))·[w]×²."""
    if th < 1e-3:
        a = 1.0 / 12.0 + th * th / 720.0
    else:
        a = 1.0 / (th * th) - math.cos(0.5 * th) / (2.0 * th * math.sin(0.5 * th))
    x, y, z = w[0], w[1], w[2]
    # [w]×² = w wᵀ − θ² I
    out[0, 0] = 1.0 + a * (x * x - th * th)
    out[1, 1] = 1.0 + a * (y * y - th * th)
    out[2, 2] = 1.0 + a * (z * z - th * th)
    out[0, 1] = -0.5 * z + a * x * y
    out[1, 0] = 0.5 * z + a * x * y
    out[0, 2] = 0.5 * y + a * x * z
    out[2, 0] = -0.5 * y + a * x * z
    out[1, 2] = -0.5 * x + a * y * z
    out[2, 1] = 0.5 * x + a * y * z

@njit(cache=True, nogil=True)
def dead(v, ta, tb):
    if v > tb:
        return v - tb
    if v < ta:
        return v - ta
    return 0.0

@njit(cache=True, nogil=True)
def goal_rows(T, Jv, Jw, Ninv, tkind, tvec, E, JJ, work):
    """The residual rows E and their Jacobian JJ (rows × n) of the goal program at pose T;
    True when every term's value lies in its exact interval. ``tvec[t]`` = (a, b, ta, tb, Q row 0..2,
    Q row 1 0..2, proof interval) — the exact interval, the target interval, the frame rows used by the term and
    :func:`proven_valid`'s interval."""
    n = Jv.shape[1]
    return goal_rows_ws(T, Jv, Jw, Ninv, tkind, tvec, E, JJ, work, np.empty((3, 3)), np.empty((3, n)),
                        np.empty((3, n)), np.empty((3, 3)), np.empty((3, 3)))

@njit(cache=True, nogil=True)
def goal_rows_ws(T, Jv, Jw, Ninv, tkind, tvec, E, JJ, work, Rd, Jp, Jr, JL, G):
    """:func:`goal_rows` with its scratch arrays given (Rd, JL, G: 3×3; Jp, Jr: 3×n)."""
    n = Jv.shape[1]
    pd = work[0]
    rv = work[1]
    for r in range(3):
        for c in range(3):
            Rd[r, c] = Ninv[r, 0] * T[0, c] + Ninv[r, 1] * T[1, c] + Ninv[r, 2] * T[2, c]
        pd[r] = Ninv[r, 0] * T[0, 3] + Ninv[r, 1] * T[1, 3] + Ninv[r, 2] * T[2, 3] + Ninv[r, 3]
    need_r = False
    for t in range(tkind.shape[0]):
        if tkind[t] == K_R_ROW or tkind[t] == K_THETA:
            need_r = True
    # d p_Δ/dq = R_N⁻¹ Jv ;  d log3(R_Δ)/dq = Jlog3(R_Δ) Rᵀ Jw
    for r in range(3):
        for j in range(n):
            Jp[r, j] = Ninv[r, 0] * Jv[0, j] + Ninv[r, 1] * Jv[1, j] + Ninv[r, 2] * Jv[2, j]
    th = 0.0
    if need_r:
        th = log3(Rd, rv)
        jlog3(th, rv, JL)
        # G = Jlog3 · Rᵀ
        for r in range(3):
            for c in range(3):
                G[r, c] = JL[r, 0] * T[c, 0] + JL[r, 1] * T[c, 1] + JL[r, 2] * T[c, 2]
        for r in range(3):
            for j in range(n):
                Jr[r, j] = G[r, 0] * Jw[0, j] + G[r, 1] * Jw[1, j] + G[r, 2] * Jw[2, j]
    ok = True
    row = 0
    for t in range(tkind.shape[0]):
        k = tkind[t]
        a, b, ta, tb = tvec[t, 0], tvec[t, 1], tvec[t, 2], tvec[t, 3]
        if k == K_P_ROW or k == K_R_ROW:
            X = pd if k == K_P_ROW else rv
            JX = Jp if k == K_P_ROW else Jr
            q0, q1, q2 = tvec[t, 4], tvec[t, 5], tvec[t, 6]
            v = q0 * X[0] + q1 * X[1] + q2 * X[2]
            e = dead(v, ta, tb)
            E[row] = e
            if e != 0.0:
                for j in range(n):
                    JJ[row, j] = q0 * JX[0, j] + q1 * JX[1, j] + q2 * JX[2, j]
            else:
                for j in range(n):
                    JJ[row, j] = 0.0
            if not (a <= v <= b):
                ok = False
            row += 1
        elif k == K_SPH or k == K_THETA:
            X = pd if k == K_SPH else rv
            JX = Jp if k == K_SPH else Jr
            v = math.sqrt(X[0] * X[0] + X[1] * X[1] + X[2] * X[2])
            e = dead(v, ta, tb)
            if e != 0.0:
                if v > 1e-12:
                    for r in range(3):
                        E[row + r] = X[r] * (e / v)
                else:
                    E[row] = e
                    E[row + 1] = 0.0
                    E[row + 2] = 0.0
                for r in range(3):
                    for j in range(n):
                        JJ[row + r, j] = JX[r, j]
            else:
                for r in range(3):
                    E[row + r] = 0.0
                    for j in range(n):
                        JJ[row + r, j] = 0.0
            if not (a <= v <= b):
                ok = False
            row += 3
        else:  # K_CYL: (x, y) = Q2 · p_Δ
            x = tvec[t, 4] * pd[0] + tvec[t, 5] * pd[1] + tvec[t, 6] * pd[2]
            y = tvec[t, 7] * pd[0] + tvec[t, 8] * pd[1] + tvec[t, 9] * pd[2]
            v = math.sqrt(x * x + y * y)
            e = dead(v, ta, tb)
            if e != 0.0:
                if v > 1e-12:
                    E[row] = x * (e / v)
                    E[row + 1] = y * (e / v)
                else:
                    E[row] = e
                    E[row + 1] = 0.0
                for j in range(n):
                    JJ[row, j] = tvec[t, 4] * Jp[0, j] + tvec[t, 5] * Jp[1, j] + tvec[t, 6] * Jp[2, j]
                    JJ[row + 1, j] = tvec[t, 7] * Jp[0, j] + tvec[t, 8] * Jp[1, j] + tvec[t, 9] * Jp[2, j]
            else:
                E[row] = 0.0
                E[row + 1] = 0.0
                for j in range(n):
                    JJ[row, j] = 0.0
                    JJ[row + 1, j] = 0.0
            if not (a <= v <= b):
                ok = False
            row += 2
    return ok

@njit(cache=True, nogil=True)
def proven_valid(T, Rd, pd, tkind, tvec):
    """True when the tolerance's own test (``ToleratedPose.valid(T)``) is sure to hold at the TCP pose T, from the
    kernel's Δ = (Rd, pd) of T: T's rotation entries within ±:data:`PROOF_ROT`, its position within
    ±:data:`PROOF_POS`, and every term's value inside its proof interval ``tvec[t, 10:12]`` (the goal's own
    interval where :meth:`~robodesign.solvers.ik.GoalModel.program` allows the proof, else empty). A Theta_R value
    is the angle ``atan2(s, c)`` as ``valid`` computes it, asked ``s² + c² ≥ 1/4``. ``valid``'s values then lie
    within its slack (1e-12) of the kernel's (:mod:`.ik_proof`)."""
    for r in range(3):
        if not (abs(T[r, 0]) <= PROOF_ROT and abs(T[r, 1]) <= PROOF_ROT and abs(T[r, 2]) <= PROOF_ROT
                and abs(T[r, 3]) <= PROOF_POS):
            return False
    for t in range(tkind.shape[0]):
        k = tkind[t]
        if k == K_P_ROW:
            v = tvec[t, 4] * pd[0] + tvec[t, 5] * pd[1] + tvec[t, 6] * pd[2]
        elif k == K_SPH:
            v = math.sqrt(pd[0] * pd[0] + pd[1] * pd[1] + pd[2] * pd[2])
        elif k == K_CYL:
            x = tvec[t, 4] * pd[0] + tvec[t, 5] * pd[1] + tvec[t, 6] * pd[2]
            y = tvec[t, 7] * pd[0] + tvec[t, 8] * pd[1] + tvec[t, 9] * pd[2]
            v = math.sqrt(x * x + y * y)
        elif k == K_THETA:
            c = 0.5 * (Rd[0, 0] + Rd[1, 1] + Rd[2, 2] - 1.0)
            wx, wy, wz = 0.5 * (Rd[2, 1] - Rd[1, 2]), 0.5 * (Rd[0, 2] - Rd[2, 0]), 0.5 * (Rd[1, 0] - Rd[0, 1])
            s2 = wx * wx + wy * wy + wz * wz
            if not s2 + c * c >= 0.25:
                return False
            v = math.atan2(math.sqrt(s2), c)
        else:
            return False
        if not tvec[t, 10] <= v <= tvec[t, 11]:
            return False
    return True

@njit(cache=True, nogil=True)
def chol_solve(A, b, x):
    """x = A⁻¹ b for a symmetric positive definite A (in place on A)."""
    m = A.shape[0]
    for j in range(m):
        s = A[j, j]
        for k in range(j):
            s -= A[j, k] * A[j, k]
        if s <= 0.0:
            return False
        d = math.sqrt(s)
        A[j, j] = d
        for i in range(j + 1, m):
            s = A[i, j]
            for k in range(j):
                s -= A[i, k] * A[j, k]
            A[i, j] = s / d
    for i in range(m):
        s = b[i]
        for k in range(i):
            s -= A[i, k] * x[k]
        x[i] = s / A[i, i]
    for i in range(m - 1, -1, -1):
        s = x[i]
        for k in range(i + 1, m):
            s -= A[k, i] * x[k]
        x[i] = s / A[i, i]
    return True

@njit(cache=True, nogil=True)
def lm_descend(q, iters, lo, hi, chain, kind, sign, iq, tcp, Ninv, tkind, tvec, E, JJ, T, params):
    """One LM descent from q (modified in place). Returns (status, iterations): status 1 = every
    analytic constraint holds at q (T holds its TCP pose), 2 = they hold and :func:`proven_valid` proves the
    tolerance's own test true at T, 0 = stalled / out of iterations / zero residual outside the exact set,
    −1 = non-finite step."""
    ws = Workspace(q.shape[0], E.shape[0], chain.shape[0])
    return lm_descend_ws(q, iters, lo, hi, chain, kind, sign, iq, tcp, Ninv, tkind, tvec, E, JJ, T, params, ws)

@njit(cache=True, nogil=True)
def lm_repair(found, noise, iters, lo, hi, chain, kind, sign, iq, tcp, Ninv, tkind, tvec, E, JJ, T, params, q):
    """:func:`lm_descend` from numpy's ``clip(found + noise, lo, hi)`` made in q (the start, then the result): per value
    the sum, then ``x if x > lo else lo`` and ``x if x < hi else hi``, NaN kept (numpy's clip loop for floats)."""
    for j in range(q.shape[0]):
        x = found[j] + noise[j]
        x = x if x != x or x > lo[j] else lo[j]
        q[j] = x if x != x or x < hi[j] else hi[j]
    return lm_descend(q, iters, lo, hi, chain, kind, sign, iq, tcp, Ninv, tkind, tvec, E, JJ, T, params)

@njit(cache=True, nogil=True)
def Workspace(n, m, nk):
    """Every scratch array of one LM descent (allocated once per batch of descents, not per iteration)."""
    msz = m if m <= n else n
    return (np.empty((3, n)), np.empty((3, n)), np.empty((2, 3)), np.empty((msz, msz)), np.empty(msz),
            np.empty(msz), np.empty(n), np.empty((4, 4)), np.empty((4, 4)), np.empty((nk, 3)), np.empty((nk, 3)),
            np.empty((3, 3)), np.empty((3, n)), np.empty((3, n)), np.empty((3, 3)), np.empty((3, 3)))

@njit(cache=True, nogil=True)
def lm_descend_ws(q, iters, lo, hi, chain, kind, sign, iq, tcp, Ninv, tkind, tvec, E, JJ, T, params, ws):
    """:func:`lm_descend` with its scratch arrays given (``Workspace``): the same arithmetic."""
    n = q.shape[0]
    m = E.shape[0]
    lam_f, lam_b, max_step, stall_ratio, stall_window = params[0], params[1], params[2], params[3], int(params[4])
    Jv, Jw, work, A, rhs, x, dq, M4, tmp4, origins, axes, Rd, Jp, Jr, JL, G = ws
    small = m <= n
    best = math.inf
    since = 0
    for it in range(iters):
        fk_jacobian_ws(q, chain, kind, sign, iq, tcp, T, Jv, Jw, M4, tmp4, origins, axes)
        ok = goal_rows_ws(T, Jv, Jw, Ninv, tkind, tvec, E, JJ, work, Rd, Jp, Jr, JL, G)
        if ok:
            return (2 if proven_valid(T, Rd, work[0], tkind, tvec) else 1), it + 1
        err = 0.0
        for i in range(m):
            err += E[i] * E[i]
        if err == 0.0:
            return 0, it + 1
        if err < best * stall_ratio:
            best = err
            since = 0
        else:
            since += 1
            if since >= stall_window:
                return 0, it + 1
        lam = lam_f * err + lam_b
        if small:                 # dq = Jᵀ (J Jᵀ + λI)⁻¹ e
            for r in range(m):
                for c in range(r + 1):
                    s = 0.0
                    for j in range(n):
                        s += JJ[r, j] * JJ[c, j]
                    A[r, c] = s
                    A[c, r] = s
                A[r, r] += lam
                rhs[r] = E[r]
            if not chol_solve(A, rhs, x):
                return -1, it + 1
            for j in range(n):
                s = 0.0
                for r in range(m):
                    s += JJ[r, j] * x[r]
                dq[j] = s
        else:                     # dq = (JᵀJ + λI)⁻¹ Jᵀ e
            for r in range(n):
                for c in range(r + 1):
                    s = 0.0
                    for i in range(m):
                        s += JJ[i, r] * JJ[i, c]
                    A[r, c] = s
                    A[c, r] = s
                A[r, r] += lam
                s = 0.0
                for i in range(m):
                    s += JJ[i, r] * E[i]
                rhs[r] = s
            if not chol_solve(A, rhs, dq):
                return -1, it + 1
        s2 = 0.0
        for j in range(n):
            s2 += dq[j] * dq[j]
        if not s2 <= max_step * max_step:
            if not math.isfinite(s2):
                return -1, it + 1
            f = max_step / math.sqrt(s2)
            for j in range(n):
                dq[j] *= f
        for j in range(n):
            v = q[j] - dq[j]
            if v > hi[j]:
                v = hi[j]
            if v < lo[j]:
                v = lo[j]
            q[j] = v
    return 0, iters

@njit(cache=True, nogil=True)
def lm_batch(starts, a, stop, iters, lo, hi, chain, kind, sign, iq, tcp, Ninv, tkind, tvec, E, JJ, T, params,
             q_out):
    """Descents from ``starts[a]``, ``starts[a+1]``, … up to ``stop`` (exclusive) until one satisfies the
    analytic constraints: returns (its index or ``stop``, iterations of all descents, whether
    :func:`proven_valid` holds at its pose); the configuration is left in ``q_out`` and its TCP pose in T."""
    total = 0
    ws = Workspace(q_out.shape[0], E.shape[0], chain.shape[0])
    for r in range(a, stop):
        for j in range(q_out.shape[0]):
            q_out[j] = starts[r, j]
        status, its = lm_descend_ws(q_out, iters, lo, hi, chain, kind, sign, iq, tcp, Ninv, tkind, tvec, E, JJ, T,
                                    params, ws)
        total += its
        if status >= 1:
            return r, total, status == 2
    return stop, total, False


def _kernels():
    """The compiled functions by name (for tests and tools)."""
    return {"fk_jacobian": fk_jacobian, "goal_rows": goal_rows, "lm_descend": lm_descend, "lm_batch": lm_batch,
            "lm_repair": lm_repair, "log3": log3, "jlog3": jlog3, "proven_valid": proven_valid}


# ---------------------------------------------------------------------------------------------------------
# inputs: the robot's chain and the goal's program
# ---------------------------------------------------------------------------------------------------------
class ChainKernel:
    """The serial chain from the world to a robot's TCP as kernel arrays (for the robot's current base
    pose): ``chain`` (k×4×4 joint placements), ``kind``, ``sign``, ``iq`` and ``tcp`` (the TCP in its joint)."""

    __slots__ = ("chain", "kind", "sign", "iq", "tcp", "key")

    def __init__(self, robot):
        m = robot.kinematic_model
        fr = m.frames[robot.tcp_frame]
        js = robot.tcp_chain()
        kinds, signs, iqs = [], [], []
        for j in js:
            jm = m.joints[j]
            name = jm.shortname()
            if name == "JointModelRZ":
                kinds.append(0), signs.append(1.0)
            elif name == "JointModelPZ":
                kinds.append(1), signs.append(1.0)
            elif name in ("JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned"):
                ax = np.asarray(jm.extract().axis if hasattr(jm, "extract") else jm.axis, float)
                if not np.allclose(ax, (0.0, 0.0, -1.0)) and not np.allclose(ax, (0.0, 0.0, 1.0)):
                    raise NotImplementedError(f"joint axis {ax}")
                kinds.append(0 if "Revolute" in name else 1)
                signs.append(float(ax[2]))
            else:
                raise NotImplementedError(name)
            if jm.nq != 1 or jm.idx_q != jm.idx_v:
                raise NotImplementedError("multi-DoF joint")
            iqs.append(jm.idx_q)
        self.chain = np.ascontiguousarray(np.array([m.jointPlacements[j].homogeneous for j in js],
                                                   dtype=float).reshape(len(js), 4, 4))
        self.kind = np.array(kinds, dtype=np.int64)
        self.sign = np.array(signs, dtype=float)
        self.iq = np.array(iqs, dtype=np.int64)
        self.tcp = np.ascontiguousarray(fr.placement.homogeneous, dtype=float)
        self.key = robot.base_pose.tobytes()


_CHAINS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def chain_kernel(robot) -> Optional[ChainKernel]:
    """The robot's :class:`ChainKernel` (cached per robot and base pose) or None if the chain has a joint
    the kernel does not model or no joint at all."""
    key = robot.base_pose.tobytes()
    hit = _CHAINS.get(robot)
    if hit is not None and (hit is False or hit.key == key):
        return hit or None
    ck: Optional[ChainKernel]
    try:
        ck = ChainKernel(robot)
        if len(ck.iq) == 0:
            ck = None
    except (NotImplementedError, AttributeError):
        ck = None
    try:
        _CHAINS[robot] = ck if ck is not None else False
    except TypeError:
        pass
    return ck


def compile_goal(terms, provable: bool = False) -> Optional[tuple]:
    """``(tkind, tvec)`` from ``[(projection, Q or None, pieces, target), …]`` or None if a term is not
    supported (periodic, several pieces, or a projection without a kernel row). ``provable``: the terms' proof
    intervals (``tvec[:, 10:12]``, :func:`proven_valid`) are their own intervals, else empty."""
    kinds, vecs = [], []
    for name, Q, pieces, target, periodic in terms:
        if periodic or len(pieces) != 1 or len(target) != 1:
            return None
        (a, b), (ta, tb) = pieces[0], target[0]
        v = np.zeros(12)
        v[:4] = (a - 1e-12, b + 1e-12, ta, tb)
        v[10:12] = (a, b) if provable else (math.inf, -math.inf)
        Qm = np.eye(3) if Q is None else np.asarray(Q, float)
        if name in ("x", "y", "z"):
            kinds.append(K_P_ROW)
            v[4:7] = Qm["xyz".index(name)]
        elif name in ("N_x", "N_y", "N_z"):
            kinds.append(K_R_ROW)
            v[4:7] = Qm["xyz".index(name[-1])]
        elif name == "r_sph":
            kinds.append(K_SPH)
        elif name == "Theta_R":
            kinds.append(K_THETA)
        elif name == "r_cyl":
            kinds.append(K_CYL)
            v[4:7] = Qm[0]
            v[7:10] = Qm[1]
        else:
            return None
        vecs.append(v)
    if not kinds:
        return None
    return np.array(kinds, dtype=np.int64), np.ascontiguousarray(np.array(vecs, dtype=float))


def rows_of(tkind) -> int:
    return int(sum(_ROWS[int(k)] for k in tkind))


def warm_up() -> bool:
    """Compile (or load from the cache) every kernel now, in this process; False when the kernel is
    unavailable. Afterwards :func:`ready` is True in this process."""
    global _STATE
    if not available():
        return False
    _warm_up_kernels()
    _STATE = "ready"
    return True


def _warm_up_kernels() -> None:
    n = 2
    chain = np.tile(np.eye(4), (2, 1, 1))
    q = np.zeros(n)
    T = np.eye(4)
    tkind = np.array([K_P_ROW, K_SPH, K_THETA, K_CYL], dtype=np.int64)
    tvec = np.zeros((4, 12))
    lm_batch(np.zeros((1, n)), 0, 1, 1, -np.ones(n), np.ones(n), chain, np.zeros(2, np.int64), np.ones(2),
             np.arange(2, dtype=np.int64), np.eye(4), np.eye(4), tkind, tvec, np.zeros(9), np.zeros((9, n)), T,
             np.array([0.02, 1e-6, 1.0, 0.9, 3.0]), q)
    lm_repair(np.zeros(n), np.zeros(n), 1, -np.ones(n), np.ones(n), chain, np.zeros(2, np.int64), np.ones(2),
              np.arange(2, dtype=np.int64), np.eye(4), np.eye(4), tkind, tvec, np.zeros(9), np.zeros((9, n)), T,
              np.array([0.02, 1e-6, 1.0, 0.9, 3.0]), q)


# ---------------------------------------------------------------------------------------------------------
# readiness: compile in the background, never stall a command on the compilation
# ---------------------------------------------------------------------------------------------------------
_STATE: Optional[str] = None   # None (not decided yet) | "python" (cold cache: compiling elsewhere) | "ready" | "failed"
_COMPILER: Optional[subprocess.Popen] = None
_KERNELS = ("lm_batch", "lm_repair")   # what solve_ik calls (the others are compiled into them)


def _cache() -> KernelCache:
    return KernelCache("robodesign.solvers.ik_kernel", __file__, lm_batch, _KERNELS)


def stamp_path() -> Path:
    return _cache().stamp_path()


def compiled() -> bool:
    """True when the cache holds the compiled kernels for this numba, Python, CPU and source (loading them
    then takes about 0.1 s, no compilation)."""
    return _cache().compiled()


def _start_compiler() -> Optional[subprocess.Popen]:
    return _cache().start_compiler()


def ready() -> bool:
    """True when the compiled loop runs in this process. Decided at the first call and kept for the
    process's life: with the kernels in the cache, True; with a cold cache, the background compilation
    starts and the answer stays False (the Python loop runs; ``ROBODESIGN_JIT=0`` is set for the processes
    this one starts, so that a run's workers use the same loop). ``ROBODESIGN_JIT=wait``: compile now, in
    this process."""
    global _STATE, _COMPILER
    if _STATE is None and available():
        if compiled():
            _STATE = "ready"
        elif _jit_mode() == "wait":
            warm_up()
        else:
            _COMPILER = _start_compiler()
            _STATE = "python" if _COMPILER is not None else "failed"
            os.environ["ROBODESIGN_JIT"] = "0"   # the workers this process starts: the same loop
    return _STATE == "ready"


def compile_into_cache() -> int:
    """Compile every kernel into numba's cache and write the stamp (once, under a lock shared with
    concurrent compilers); what ``python -m robodesign.solvers.ik_kernel`` does, niced, in the background."""
    return _cache().compile_into_cache(_warm_up_kernels)


if __name__ == "__main__":
    sys.exit(background_compile(available(), compile_into_cache))
