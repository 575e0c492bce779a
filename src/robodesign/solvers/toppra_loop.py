"""toppra's TOPP-RA passes for a rest-to-rest profile without toppra's per-stage Python overhead (issue 25: the time
scaling's largest part is toppra's own loop over the grid points).

:func:`rest_to_rest` makes the same calls of the same seidel solver with the same arguments as toppra's
``compute_parameterization(0, 0)`` (its ``compute_controllable_sets``/``_one_step`` backward pass and its
``_forward_step`` forward pass) and the same arithmetic between them, so its path velocities are toppra's bit
for bit (tests/test_timing.py); it returns None wherever toppra's loop would leave the common path, and the
caller then runs toppra's own loop.

:func:`pass_velocities` is what the time scaling calls per TOPP-RA pass: first :func:`compiled_rest_to_rest` (the
compiled kernel of :mod:`robodesign.solvers.topp_kernel` on seidelWrapper's coefficients, built here by
:func:`seidel_rows` without toppra's set-up; issue 25), then :func:`rest_to_rest`, then toppra's own loop, each
only where the one before does not answer: the same numbers in every case (tests/test_topp_kernel.py).
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


def seidel_rows(A: np.ndarray, B: np.ndarray, C: np.ndarray, F: np.ndarray, h: np.ndarray, xbound: np.ndarray):
    """toppra's seidelWrapper coefficients (a_arr, b_arr, c_arr (N+1, 2 + rows of F); low_arr, high_arr (N+1, 2))
    of an "identical" canonical linear constraint (A, B, C (N+1, m), F (k, m), h (k,)) after a velocity constraint
    (``xbound`` (N+1, 2)), or None unless every row of F picks one column with ±1 and every coefficient is finite.
    seidelWrapper computes A·Fᵀ, B·Fᵀ and C·Fᵀ − h with BLAS, whose sums start at +0: for such an F that is the
    picked column times ±1, plus 0 (−0 becomes +0), the same numbers bit for bit (tests/test_topp_kernel.py)."""
    row, col = np.nonzero(F)
    N1, k = len(A), len(F)
    if not (len(row) == k and np.array_equal(row, np.arange(k))):
        return None
    sign = F[row, col]
    if not np.all(np.abs(sign) == 1.0):
        return None
    a, b, c = np.zeros((N1, 2 + k)), np.zeros((N1, 2 + k)), np.zeros((N1, 2 + k))
    a[:, 2:] = A[:, col] * sign + 0.0
    b[:, 2:] = B[:, col] * sign + 0.0
    c[:, 2:] = (C[:, col] * sign + 0.0) - h
    if not (np.isfinite(a).all() and np.isfinite(b).all() and np.isfinite(c).all()):
        return None
    low = np.full((N1, 2), -1e8)
    high = np.full((N1, 2), 1e8)
    # seidelWrapper's dbl_max/dbl_min: (a if a > b else b), (a if a < b else b)
    low[:, 1] = np.where(low[:, 1] > xbound[:, 0], low[:, 1], xbound[:, 0])
    high[:, 1] = np.where(high[:, 1] < xbound[:, 1], high[:, 1], xbound[:, 1])
    return a, b, c, low, high


def compiled_rest_to_rest(dyn, path, gridpoints: np.ndarray, xbound: np.ndarray) -> Optional[np.ndarray]:
    """:func:`rest_to_rest`'s path velocities by the compiled kernel (:mod:`robodesign.solvers.topp_kernel`) for
    TOPPRA([velocity constraint, dyn], path, gridpoints, "seidel") with ``xbound`` the velocity constraint's x bounds.
    seidelWrapper's coefficients come from the compiled ``constraint_rows`` when ``dyn`` holds its path terms on
    this grid (the time scaling's DynamicsConstraint), else from ``dyn.compute_constraint_params`` and
    :func:`seidel_rows`. None when the kernel is not compiled yet, the problem is not of that form, or the kernel
    is not sure to follow toppra (then toppra runs: the same numbers either way)."""
    from robodesign.solvers import topp_kernel
    if not topp_kernel.ready():
        return None
    grid = np.asarray(gridpoints, dtype=float)
    deltas = grid[1:] - grid[:-1]
    if not np.all(deltas > 0):
        return None
    tm = getattr(dyn, "terms", None)
    if tm is not None and tm.path is path and np.array_equal(tm.grid, grid):
        rows = _compiled_rows(dyn, tm, deltas, xbound)
    else:
        A, B, C, F, h, ubound, xb2 = dyn.compute_constraint_params(path, grid)
        if ubound is not None or xb2 is not None or A is None:
            return None
        rows = seidel_rows(A, B, C, F, h, xbound)
    if rows is None:
        return None
    a, b, c, low, high = rows
    sd = np.empty(len(grid))
    return sd if topp_kernel.rest_to_rest(a, b, c, low, high, deltas, sd) == topp_kernel.OK else None


def _compiled_rows(dyn, tm, deltas, xbound):
    """seidel_rows(*dyn.compute_constraint_params(...)[:5], xbound) by the compiled kernel (topp_kernel.constraint_rows:
    the same numbers), or None where that gives None (a coefficient not finite)."""
    from robodesign.solvers import topp_kernel
    N1, dof = tm.qs.shape
    use_torque = bool(dyn.use_torque)
    k = 4 * dof if use_torque else 2 * dof
    a, b, c = np.zeros((N1, 2 + 2 * k)), np.zeros((N1, 2 + 2 * k)), np.zeros((N1, 2 + 2 * k))
    low, high = np.empty((N1, 2)), np.empty((N1, 2))
    robot = dyn.robot
    tmax, amax, fv, fc = (_read_only(x, dof) for x in (dyn.tau_max, dyn.amax, robot.friction_viscous,
                                                         robot.friction_coulomb))
    g, ai, bri, bli = (tm.g, tm.a, tm.bR, tm.bL) if use_torque else (tm.qs,) * 4
    x0 = _read_only(dyn.x0, N1) if use_torque else np.ones(N1)
    ok = topp_kernel.constraint_rows(tm.qs, tm.qss_r, tm.qss_l, g, ai, bri, bli, np.ascontiguousarray(x0), amax,
                                     tmax, fv, fc, use_torque, deltas, np.asarray(xbound, np.float64), a, b, c, low,
                                     high)
    return (a, b, c, low, high) if ok else None


def _read_only(x, n: int) -> np.ndarray:
    """``np.broadcast_to(np.asarray(x, np.float64), (n,))``: a read-only float64 vector of length n (the kernel's
    argument types), without broadcast_to's cost where x already is such a vector (a read-only view of it)."""
    a = np.asarray(x, np.float64)
    if a.shape != (n,) or not a.flags.c_contiguous:
        return np.broadcast_to(a, (n,))
    v = a.view()
    v.flags.writeable = False
    return v


def pass_velocities(tp, vel, dyn, path, grid, xbound):
    """One TOPP-RA pass (toppra's TOPPRA([vel, dyn], path, grid, "seidel").compute_parameterization(0, 0)): its path
    velocities (None when it fails) and toppra's return code when toppra's own loop ran. The compiled kernel
    (toppra_loop.compiled_rest_to_rest) first, then the lean loop, then toppra's loop: the same numbers."""
    if grid[0] == path.path_interval[0] and grid[-1] == path.path_interval[1]:   # (else toppra raises)
        sd_vec = compiled_rest_to_rest(dyn, path, grid, xbound)
        if sd_vec is not None:
            return sd_vec, None
    algo = tp.algorithm.TOPPRA([vel, dyn], path, gridpoints=grid, solver_wrapper="seidel")
    sd_vec = rest_to_rest(algo)
    if sd_vec is not None:
        return sd_vec, None
    algo.compute_parameterization(0.0, 0.0)   # a branch of toppra's own loop (numerical trouble, uncontrollable)
    pd = algo.problem_data
    ok = pd.return_code == tp.algorithm.ParameterizationReturnCode.Ok and pd.sd_vec is not None
    return (pd.sd_vec if ok else None), pd.return_code


def velocity_xbound(vel, qs: np.ndarray) -> np.ndarray:
    """``vel.compute_constraint_params(path, grid)``'s x bounds (toppra's JointVelocityConstraint) from the path's
    q'(s) on the grid, ``qs`` = ``path(grid, 1)``, which that call would compute again: its own routine on the same
    numbers."""
    from toppra._CythonUtils import _create_velocity_constraint
    _, _, xb = _create_velocity_constraint(qs, vel.vlim)
    out = np.array(xb)
    out[:, 0] = xb[:, 1]
    out[:, 1] = -xb[:, 0]
    return out
