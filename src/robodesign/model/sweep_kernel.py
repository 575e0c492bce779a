"""The posed lever arms of :class:`robodesign.model.sweep._PosedArms`, compiled (numba): two loops over the steps
instead of a few dozen numpy passes over (samples × arms × 3) arrays (issue 25: 5–6 ms of a 350-sample check).

The kernels make **the same floating-point operations in the same order** as the numpy path they replace
(``_PosedArms._arms_numpy`` and ``_PosedArms._gather_numpy``: the frame sums ((0 + a₀) + a₁) + a₂, the cross
product's squares summed left to right, the drift's terms in the order of the joints, the gather's per-joint
terms summed from the first joint on), so both give the same bounds **bit for bit** (tests/test_sweep_kernel.py)
and a schedule never depends on which one ran. Covered: finite joint steps (a step with an infinite or undefined
|Δq| keeps the numpy path).

Readiness as :mod:`robodesign.judge.interval_kernel`: a process that finds no stamp of a finished compilation
starts one background process (``python -m robodesign.model.sweep_kernel``) that compiles into numba's on-disk
cache, and runs the numpy path meanwhile. ``ROBODESIGN_JIT=0`` switches the kernels off, ``ROBODESIGN_JIT=wait``
compiles at first use.
"""
from __future__ import annotations

import os
import sys
from typing import Optional

import numpy as np

from robodesign.core.jit_cache import NUMBA_IMPORTED, KernelCache, background_compile, njit


@njit(cache=True, nogil=True)
def posed_arms(J, geom_joint, joints, t_g, axes, jv, g, jid, R, rad, dQ, d_row, d_ptr, d_col, d_val,
               slack):  # pragma: no cover - compiled
    """(n−1, dof·G) |Δq_j| times the arm of joint j for geometry g per step, as _PosedArms._arms_numpy: J (n,
    njoints, 4, 4) joint poses; (jv, g, jid) the arms to tighten (velocity index, geometry, pinocchio joint);
    the drift's terms per joint d_row[t] (columns d_col, values d_val of d_ptr[t]:d_ptr[t + 1])."""
    n = J.shape[0]
    dof, G = R.shape
    K = len(g)
    X = np.empty((n - 1, dof * G))
    for k in range(n - 1):
        for j in range(dof):
            for gg in range(G):
                X[k, j * G + gg] = dQ[k, j] * R[j, gg]
    if K == 0:
        return X
    centre = np.empty((n, G, 3))
    axis = np.empty((n, dof, 3))
    for k in range(n):
        for gg in range(G):
            T = J[k, geom_joint[gg]]
            for i in range(3):
                s = 0.0 + T[i, 0] * t_g[gg, 0]
                s = s + T[i, 1] * t_g[gg, 1]
                s = s + T[i, 2] * t_g[gg, 2]
                centre[k, gg, i] = T[i, 3] + s
        for j in range(dof):
            T = J[k, joints[j]]
            for i in range(3):
                s = 0.0 + T[i, 0] * axes[j, 0]
                s = s + T[i, 1] * axes[j, 1]
                axis[k, j, i] = s + T[i, 2] * axes[j, 2]
    rho = np.empty((n, K))
    for k in range(n):
        for c in range(K):
            jj, gc, vc = jid[c], g[c], jv[c]
            rx, ry, rz = (centre[k, gc, 0] - J[k, jj, 0, 3], centre[k, gc, 1] - J[k, jj, 1, 3],
                          centre[k, gc, 2] - J[k, jj, 2, 3])
            ux, uy, uz = axis[k, vc, 0], axis[k, vc, 1], axis[k, vc, 2]
            a, b, e = ry * uz - rz * uy, rz * ux - rx * uz, rx * uy - ry * ux
            rho[k, c] = np.sqrt((a * a + b * b) + e * e)
    drift = np.zeros((n - 1, K))
    for t in range(len(d_row)):
        i = d_row[t]
        for p in range(d_ptr[t], d_ptr[t + 1]):
            col, v = d_col[p], d_val[p]
            for k in range(n - 1):
                drift[k, col] += dQ[k, i] * v
    for k in range(n - 1):
        for c in range(K):
            r0, r1 = rho[k, c], rho[k + 1, c]
            m = r0 if (r0 != r0 or r0 <= r1) and r1 == r1 else r1  # numpy.minimum: nan if either is nan
            arm = ((m + drift[k, c]) + rad[g[c]]) * slack + 1e-12
            if not np.isfinite(arm):
                arm = np.inf
            st = R[jv[c], g[c]]
            X[k, jv[c] * G + g[c]] = dQ[k, jv[c]] * (st if st <= arm else arm)
    return X


@njit(cache=True, nogil=True)
def gather(X, dof, G, uniq, inverse):  # pragma: no cover - compiled
    """(n−1, P): per pair c the sum over joints j of X[:, j·G + uniq[j, inverse[c]]] (G: no term, +0.0), summed
    from j = 0 on, as _PosedArms._gather_numpy."""
    m = X.shape[0]
    U = uniq.shape[1]
    P = len(inverse)
    S = np.empty(U)
    out = np.empty((m, P))
    for k in range(m):
        for u in range(U):
            col = uniq[0, u]
            s = X[k, col] if col < G else 0.0
            for j in range(1, dof):
                col = uniq[j, u]
                s = s + (X[k, j * G + col] if col < G else 0.0)
            S[u] = s
        for c in range(P):
            out[k, c] = S[inverse[c]]
    return out


# ---------------------------------------------------------------------------------------------------------
# readiness: compile in the background, never stall a check on the compilation
# ---------------------------------------------------------------------------------------------------------
_STATE: Optional[str] = None  # None (not decided) | "numpy" (cold cache: compiling elsewhere) | "ready" | "failed"


def available() -> bool:
    """True when numba imports and ``ROBODESIGN_JIT`` is not ``0``."""
    return NUMBA_IMPORTED and os.environ.get("ROBODESIGN_JIT", "1").strip().lower() not in ("0", "false", "no",
                                                                                             "off")


def _cache() -> KernelCache:
    return KernelCache("robodesign.model.sweep_kernel", __file__, posed_arms, ("posed_arms", "gather"))


def compiled() -> bool:
    """True when the cache holds the compiled kernels for this numba, Python, CPU and source."""
    return _cache().compiled()


def warm_up() -> bool:
    """Compile (or load) the kernels in this process now; False when numba is unavailable."""
    global _STATE
    if not available():
        return False
    i, f = np.zeros(1, np.int64), np.zeros(1)
    X = posed_arms(np.zeros((2, 2, 4, 4)), i, i, np.zeros((1, 3)), np.zeros((1, 3)), i, i, i, np.zeros((1, 1)), f,
                   np.zeros((1, 1)), i, np.zeros(2, np.int64), i, f, 1.0)
    gather(X, 1, 1, np.zeros((1, 1), np.int64), i)
    _STATE = "ready"
    return True


def ready() -> bool:
    """True when the compiled kernels run in this process. With a cold cache the background compilation starts
    (once per process) and the numpy path runs until a later call finds the stamp: both give the same numbers."""
    global _STATE
    if _STATE == "ready" or not available():
        return _STATE == "ready"
    if compiled():
        warm_up()
    elif os.environ.get("ROBODESIGN_JIT", "").strip().lower() == "wait":
        compile_into_cache()
        warm_up()
    elif _STATE is None:
        _STATE = "numpy" if _cache().start_compiler() is not None else "failed"
    return _STATE == "ready"


def compile_into_cache() -> int:
    """Compile the kernels into numba's cache and write the stamp (under a lock shared with concurrent compilers)."""
    return _cache().compile_into_cache(warm_up)


if __name__ == "__main__":
    sys.exit(background_compile(available(), compile_into_cache))
