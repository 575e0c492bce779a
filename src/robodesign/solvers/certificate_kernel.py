"""The planner's pair certificates (:mod:`robodesign.solvers.pair_certificates`) applied by compiled loops (numba)
instead of a dozen numpy calls per state (issue 25: on PTP_3's fresh arms ~1 s of a 900-candidate stream went to
those calls' overhead, a state's rows and pairs being few).

A certificate (clearance ``f`` of pair k beyond its margin at configuration a) proves pair k free at q when
``f − Σᵢ |qᵢ − aᵢ| · W[i, k] > slack``. :func:`clear_pending` applies the kept certificates to a block of states,
:func:`keep_and_clear` keeps a new one and applies it to the block's later states. Only the entries still pending
are bounded (a cleared one stays cleared), and a pair is cleared at a state by the first certificate that proves it.
A clearance of at most ``slack`` proves nothing anywhere (the bound is a sum of products of ``|qᵢ − aᵢ|`` and lever
arms ``W ≥ 0``, so ``f − bound ≤ f ≤ slack``): no bound is summed for it (a pair whose faces touch at a joint, within
``slack`` at every state, cost a bound per later state and kept certificate for nothing).
The sums run over the joints in order; numpy's matrix product (BLAS) may round the last bit differently, which
moves a pair between "proven free" and "asked" only where its bound is within that bit of ``slack`` (1e-4 m beyond
the margin): either way the verdict is the collision test's, free there (tests/test_certificate_kernel.py compares
both paths' pending pairs on random robots).

Readiness as :mod:`robodesign.model.sweep_kernel`: with a cold cache a background process compiles them
(``python -m robodesign.solvers.certificate_kernel``) and the numpy path runs meanwhile.
"""
from __future__ import annotations

import sys

import numpy as np

from robodesign.core.jit_cache import KernelModule, njit


@njit(cache=True, nogil=True)
def _proves(free, R, r, a, W, k, slack):  # pragma: no cover - compiled
    """Whether clearance ``free`` of pair k at configuration ``a`` proves the pair free at ``R[r]``."""
    b = 0.0
    for i in range(R.shape[1]):
        b += abs(R[r, i] - a[i]) * W[i, k]
    return free - b > slack


@njit(cache=True, nogil=True)
def clear_pending(P, R, anchors, frees, m, W, cols, slack):  # pragma: no cover - compiled
    """``P[r, k] = False`` (k in ``cols``) where one of the first ``m`` kept certificates (``anchors``, their
    clearances ``frees``; NaN: none for that pair; at most ``slack``: proves nothing) proves pair k free at ``R[r]``."""
    for r in range(R.shape[0]):
        for k in cols:
            if not P[r, k]:
                continue
            for a in range(m):
                f = frees[a, k]
                if f > slack and _proves(f, R, r, anchors[a], W, k, slack):
                    P[r, k] = False
                    break


@njit(cache=True, nogil=True)
def keep_and_clear(P, R, j, own, free, W, slack, anchors, frees, row):  # pragma: no cover - compiled
    """A new certificate at ``R[j]`` (clearances ``free`` of the pairs ``own``) kept in row ``row`` of ``anchors``
    and ``frees``, and ``P[r, own[c]] = False`` at ``r = j`` and every later row where it proves the pair free (none
    where its clearance is at most ``slack``)."""
    anchors[row, :] = R[j]
    frees[row, :] = np.nan
    q = anchors[row]
    for c in range(len(own)):
        k = own[c]
        frees[row, k] = free[c]
        if not free[c] > slack:
            continue
        P[j, k] = False
        for r in range(j + 1, R.shape[0]):
            if P[r, k] and _proves(free[c], R, r, q, W, k, slack):
                P[r, k] = False


def _warm() -> None:
    """Every kernel called once on tiny arguments (compiles or loads them)."""
    P, R, i = np.ones((2, 1), np.bool_), np.zeros((2, 1)), np.zeros(1, np.int64)
    clear_pending(P, R, np.zeros((1, 1)), np.zeros((1, 1)), 1, np.ones((1, 1)), i, 1e-4)
    keep_and_clear(P, R, 0, i, np.zeros(1), np.ones((1, 1)), 1e-4, np.zeros((1, 1)), np.zeros((1, 1)), 0)


KERNELS = KernelModule("robodesign.solvers.certificate_kernel", __file__, clear_pending,
                       ("clear_pending", "keep_and_clear"), _warm, every=5.0)
available, compiled, warm_up, ready = KERNELS.available, KERNELS.compiled, KERNELS.warm_up, KERNELS.ready
compile_into_cache = KERNELS.compile_into_cache

if __name__ == "__main__":
    sys.exit(KERNELS.main())
