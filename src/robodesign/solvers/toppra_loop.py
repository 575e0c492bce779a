"""toppra's TOPP-RA passes for a rest-to-rest profile without toppra's per-stage Python overhead (issue 25: the time
scaling's largest part is toppra's own loop over the grid points).

:func:`rest_to_rest` makes the same calls of the same seidel solver with the same arguments as toppra's
``compute_parameterization(0, 0)`` (its ``compute_controllable_sets``/``_one_step`` backward pass and its
``_forward_step`` forward pass) and the same arithmetic between them, so its path velocities are toppra's bit
for bit (tests/test_timing.py); it returns None wherever toppra's loop would leave the common path, and the
caller then runs toppra's own loop.
"""
from __future__ import annotations

from typing import Optional

import numpy as np


def rest_to_rest(algo) -> Optional[np.ndarray]:
    """``algo.compute_parameterization(0, 0)``'s path velocities (toppra's TOPPRA with its seidel solver
    wrapper) without toppra's per-stage Python overhead: the same solver calls with the same arguments and the
    same arithmetic between them, so the same numbers. None where toppra's loop would take another branch (a
    NaN controllable set, an uncontrollable start, a forward step that fails and is retried slower): then
    toppra's own loop is run."""
    from toppra.constants import SMALL, TINY
    sw = algo.solver_wrapper
    N = algo._N
    solve = sw.solve_stagewise_optim
    nv = sw.get_no_vars()
    nan = np.nan
    K = np.zeros((N + 1, 2))
    K[N] = [0.0 ** 2, 0.0 ** 2]
    g_up = np.zeros(nv)
    g_up[0] = 1e-9
    g_up[1] = -1
    g_lo = -g_up
    sw.setup_solver()
    for i in range(N - 1, -1, -1):   # the controllable sets (toppra: compute_controllable_sets, _one_step)
        k0, k1 = K[i + 1]
        if k0 != k0 or k1 != k1:
            return None
        x_up = solve(i, None, g_up, nan, nan, k0, k1)[1]
        x_lo = solve(i, None, g_lo, nan, nan, k0, k1)[1]
        K[i] = [x_lo, x_up]
        if K[i, 0] < 0:
            K[i, 0] = 0
        if np.isnan(K[i]).any():
            return None
    sw.close_solver()
    if 0.0 + SMALL < K[0, 0] or K[0, 1] + SMALL < 0.0:
        return None
    deltas = sw.get_deltas()
    xs = np.zeros(N + 1)
    us = np.zeros(N)
    sw.setup_solver()
    for i in range(N):               # the forward pass (toppra: compute_parameterization, _forward_step)
        x = xs[i]
        if x != x:
            return None
        g = np.zeros(nv)
        g[1] = -1
        g[0] = -2 * deltas[i]
        u = solve(i, None, g, x, x, K[i + 1][0], K[i + 1][1])[0]
        if np.isnan(u):
            return None
        us[i] = u
        x_next = xs[i] + 2 * deltas[i] * us[i]
        x_next = max(x_next - TINY, 0.9999 * x_next)
        xs[i + 1] = min(K[i + 1, 1], max(K[i + 1, 0], x_next))
    sw.close_solver()
    sd = np.sqrt(xs)
    return None if np.isnan(sd).any() else sd
