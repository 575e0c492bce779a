"""Trajectory optimization with CasADi ``Opti`` + ipopt, warm-started from a planned, timed path.

Transcription (multiple shooting, exact for the project's integration rule)
---------------------------------------------------------------------------
N intervals of equal length h = T/N; states q_k, q̇_k (k = 0..N), controls q̈_k (k < N), piecewise
constant::

    q_{k+1} = q_k + q̇_k·h + ½·q̈_k·h²,   q̇_{k+1} = q̇_k + q̈_k·h

— the same rule :class:`~robodesign.core.trajectory.Trajectory` samples obey, so the optimized
trajectory is an exactly integrated C¹ curve. Constraints:

* q_lower + m ≤ q_k ≤ q_upper − m at the interior nodes (m = ``limit_margin``; the fixed end nodes may
  lie closer), and the output samples are checked against the limits (TrajoptError otherwise);
  |q̇_k| ≤ q̇_max (q̇ is piecewise linear, so this holds at all times),
  |q̈_k| ≤ q̈_max (exact: q̈ is constant per interval);
* drivetrain torque (:func:`~.casadi_dynamics.casadi_drivetrain_torque`, RNEA + armature + viscous +
  smooth Coulomb) within ±τ_max·(1 − ``torque_margin``) at *both ends* of every interval with that
  interval's q̈ — i.e. at (q_k, q̇_k, q̈_k) and (q_{k+1}, q̇_{k+1}, q̈_k). τ is affine in q̈, so a state
  at a node with any mix of its two neighbouring q̈ (what an output sample straddling a node sees) is
  covered too; what remains between nodes is caught by the output sample check below;
* rest at both ends: q_0 = q_start, q_N = q_goal (or ‖p_TCP(q_N) − goal_position‖ ≤ goal_tol if a goal
  *position* is given), q̇_0 = q̇_N = 0;
* collision avoidance (decision): a **tube** around the warm start. The warm start is a collision-checked
  path; node k must stay inside the box |q_k − q_warm(k/N·T_warm)|_∞ ≤ ``tube`` (rad or m; max norm,
  which is a cheap simple bound). Between nodes the trajectory is a quadratic interpolation of nodes
  inside the tube. ``tube=None`` drops it (then the result must be collision-checked again). A
  linearised signed-distance constraint would allow larger moves but needs distance gradients
  per iteration (not done).

Objectives (CoBRA names, weights as in the cost strings of FORMAT §4, e.g. ``"cyc_1,mechEnergy_0.05"``):

* ``cyc``: T (free final time; bounded below by the per-joint trapezoid bound);
* ``mechEnergy``: Σ_k |τ_k·q̇_k|·h (τ_k at the interval's left node, like CoBRA's left rectangle rule);
  |·| in epigraph form (slack s_k ≥ ±τ_k·q̇_k, minimise Σ s_k·h), exact and smooth for ipopt;
* ``effort``: Σ_k Σ_j |τ_kj|·h (epigraph form as well).

Without a ``cyc`` term the final time is fixed (``duration``, default: the warm start's), since
mechanical energy alone is minimised by moving infinitely slowly.

Solver: ipopt with the exact Hessian; ``expand=False`` by default. The torque function is one SX
function ``map``-ped over the nodes, so casadi differentiates it once; expanding the whole NLP to SX
was slower here (measured: 3.3 s vs 1.5 s for min-time, 6-DoF, 30 nodes — the expanded Hessian
construction dominates), and a limited-memory Hessian needed 6× more iterations.

Scope: one rest-to-rest motion. For a timed path with intermediate stops (goals), optimize each part
between two ``info["stop_samples"]`` separately (``warm.slice(k0, k1)``) and concatenate the results.

Output: the solution's continuous velocity is resampled at ``dt_out`` with
:func:`~.timing.resample_velocity_profile` (duration rounded up to a multiple of dt_out, the
integration rule exact, q[-1] exactly the goal, every sample re-checked against the velocity,
acceleration and torque limits and slowed down uniformly if needed). Like every motion from
:mod:`.timing` it starts with one rest step (dq = ddq = 0 at the first and last sample exactly).
"""
from __future__ import annotations

import math
import time as _time
from typing import Any, Dict, Optional, Sequence, Union

import casadi as ca
import numpy as np

from robodesign.core.errors import InfeasibleError
from robodesign.core.trajectory import Trajectory
from robodesign.formats.costs import CostFunction, cost_terms
from robodesign.formats.costs import parse_cost as parse_cobra_cost
from robodesign.solvers.casadi_dynamics import casadi_drivetrain_torque, casadi_fk
from robodesign.solvers.timing import resample_velocity_profile, time_optimal_bound


class TrajoptError(InfeasibleError):
    """ipopt did not find a feasible trajectory."""


def trajopt_weights(cost) -> Dict[str, float]:
    """Trajectory-optimization weights {term: weight} from a :class:`CostFunction`, a CoBRA cost (either
    notation, compounds such as ``Liu2`` expand) or a dict; only the trajectory-dependent terms ``cyc``,
    ``mechEnergy``, ``effort`` are supported."""
    if isinstance(cost, dict):
        out = {str(k): float(v) for k, v in cost.items()}
    else:
        cf = cost if isinstance(cost, CostFunction) else parse_cobra_cost(str(cost))
        out = {name: float(w) for name, w in cf.terms}
    known = [n for n, term in cost_terms().items() if term.trajopt]
    bad = [k for k in out if k not in known]
    if bad:
        raise ValueError(f"unsupported cost term(s) {bad} for trajectory optimization (supported: {', '.join(known)})")
    if not out:
        raise ValueError("empty cost")
    return out


def mechanical_energy(robot, traj: Trajectory) -> float:
    """CoBRA ``mechEnergy``: Σ_{k<N} |τ_k·q̇_k|·(t_{k+1} − t_k) with the drivetrain torque."""
    if len(traj) < 2:
        return 0.0
    tau = robot.drivetrain_torques(traj.q, traj.dq, traj.ddq)
    p = np.abs(np.einsum("ij,ij->i", tau, traj.dq))[:-1]
    return float(np.sum(p * np.diff(traj.t)))


def optimize_trajectory(robot, warm: Trajectory, cost="cyc", n_nodes: int = 30, dt_out: float = 0.01,
                        max_iter: int = 500, tube: Optional[float] = 0.05, *, duration: Optional[float] = None,
                        torque_limits: bool = True, torque_margin: float = 1e-3, limit_margin: float = 1e-3,
                        goal_position: Optional[Sequence[float]] = None, goal_tol: float = 1e-3,
                        tol: float = 1e-7, expand: bool = False, ipopt_options: Optional[dict] = None,
                        verbose: bool = False) -> Trajectory:
    """Optimize a rest-to-rest trajectory from ``warm.q[0]`` to ``warm.q[-1]`` (see module docstring).

    Returns a :class:`Trajectory` sampled every ``dt_out`` with ``info``: ``solve_time`` (s, whole
    call), ``ipopt_time``, ``iterations``, ``status``, ``T_opt`` (continuous optimum), ``objective``,
    ``stretch`` (uniform slow-down needed by the sample check, 1 if none). Raises :class:`TrajoptError`
    if ipopt fails.
    """
    t_start = _time.perf_counter()
    weights = trajopt_weights(cost)
    dof, N = robot.dof, int(n_nodes)
    if N < 2:
        raise ValueError("n_nodes must be ≥ 2")
    if warm.dof != dof:
        raise ValueError(f"warm start has {warm.dof} joints, robot {dof}")
    q_start, q_goal = warm.q[0].copy(), warm.q[-1].copy()
    Tw = max(warm.duration, 1e-3)
    free_T = weights.get("cyc", 0.0) != 0.0
    T_fixed = float(duration if duration is not None else Tw)
    T_lb = 0.98 * time_optimal_bound(robot, q_start, q_goal) if goal_position is None else 1e-3
    T_lb = max(T_lb, 1e-3)

    # warm start at the nodes (same phase k/N of the motion)
    tk = np.linspace(0.0, 1.0, N + 1) * Tw + warm.t[0]
    Wq, Wdq, _ = warm.interpolate(tk)
    T0 = Tw if free_T else T_fixed
    scale = Tw / T0
    Wdq = Wdq * scale
    h0 = T0 / N
    Wu = np.diff(Wdq, axis=0) / h0

    opti = ca.Opti()
    Q = opti.variable(dof, N + 1)
    DQ = opti.variable(dof, N + 1)
    U = opti.variable(dof, N)
    if free_T:
        T: Union[ca.MX, float] = opti.variable()
        opti.subject_to(opti.bounded(T_lb, T, 20.0 * Tw + 10.0))
        opti.set_initial(T, max(T0, T_lb))
    else:
        T = T_fixed
    h = T / N
    opti.subject_to(Q[:, 1:] == Q[:, :-1] + DQ[:, :-1] * h + 0.5 * U * h ** 2)
    opti.subject_to(DQ[:, 1:] == DQ[:, :-1] + U * h)
    # limits
    lo, hi = np.asarray(robot.q_lower, float), np.asarray(robot.q_upper, float)
    vmax, amax, tmax = (np.asarray(x, float) for x in (robot.dq_max, robot.ddq_max, robot.tau_max))
    for j in range(dof):
        # interior nodes keep ``limit_margin`` from the position limits (ipopt's constraint tolerance, the
        # quadratic pieces between nodes and the resampling may bulge a little); the end nodes, fixed by
        # the boundary conditions, may lie closer (an IK solution at a limit)
        qlo_k = np.full(N + 1, lo[j] + limit_margin if math.isfinite(lo[j]) else -np.inf)
        qhi_k = np.full(N + 1, hi[j] - limit_margin if math.isfinite(hi[j]) else np.inf)
        qlo_k[0], qhi_k[0] = min(qlo_k[0], q_start[j]), max(qhi_k[0], q_start[j])
        if goal_position is None:
            qlo_k[N], qhi_k[N] = min(qlo_k[N], q_goal[j]), max(qhi_k[N], q_goal[j])
        else:
            qlo_k[N], qhi_k[N] = lo[j], hi[j]
        if tube is not None:
            qlo_k = np.maximum(Wq[:, j] - tube, qlo_k)
            qhi_k = np.minimum(Wq[:, j] + tube, qhi_k)
        if np.isfinite(qlo_k).any() or np.isfinite(qhi_k).any():
            opti.subject_to(opti.bounded(qlo_k.reshape(1, -1), Q[j, :], qhi_k.reshape(1, -1)))
        if math.isfinite(vmax[j]):
            opti.subject_to(opti.bounded(-vmax[j], DQ[j, :], vmax[j]))
        if math.isfinite(amax[j]):
            opti.subject_to(opti.bounded(-amax[j], U[j, :], amax[j]))
    # boundary conditions
    opti.subject_to(Q[:, 0] == q_start)
    opti.subject_to(DQ[:, 0] == 0)
    opti.subject_to(DQ[:, N] == 0)
    if goal_position is None:
        opti.subject_to(Q[:, N] == q_goal)
    else:
        fk = casadi_fk(robot)
        p_end = fk(Q[:, N])[0]
        d = p_end - ca.DM(np.asarray(goal_position, float).reshape(3, 1))
        opti.subject_to(ca.sumsqr(d) <= (0.9 * goal_tol) ** 2)  # margin for ipopt's constraint tolerance
    # torques
    need_tau = torque_limits or weights.get("mechEnergy", 0.0) or weights.get("effort", 0.0)
    if need_tau:
        Fmap = casadi_drivetrain_torque(robot).map(N)
        TL = Fmap(Q[:, :-1], DQ[:, :-1], U)
    if torque_limits:
        TR = Fmap(Q[:, 1:], DQ[:, 1:], U)
        lim = tmax * (1.0 - torque_margin)
        for j in range(dof):
            if math.isfinite(tmax[j]):
                opti.subject_to(opti.bounded(-lim[j], TL[j, :], lim[j]))
                opti.subject_to(opti.bounded(-lim[j], TR[j, :], lim[j]))
    # objective
    J: Union[ca.MX, float] = 0
    if free_T:
        J = J + weights["cyc"] * T
    if weights.get("mechEnergy", 0.0):
        # |power| in epigraph form: s_k ≥ ±τ_k·q̇_k, minimise Σ s_k·h (exact |·| at the optimum)
        power = ca.sum1(TL * DQ[:, :-1])  # 1×N
        S = opti.variable(1, N)
        opti.subject_to(S >= power)
        opti.subject_to(S >= -power)
        opti.set_initial(S, 1.0)
        J = J + weights["mechEnergy"] * h * ca.sum2(S)
    if weights.get("effort", 0.0):
        E = opti.variable(dof, N)
        opti.subject_to(ca.vec(E) >= ca.vec(TL))  # vec: element-wise (a square matrix would be an LMI)
        opti.subject_to(ca.vec(E) >= -ca.vec(TL))
        opti.set_initial(E, 1.0)
        J = J + weights["effort"] * h * ca.sum1(ca.sum2(E))
    opti.minimize(J)
    # initial guess
    opti.set_initial(Q, Wq.T)
    opti.set_initial(DQ, Wdq.T)
    opti.set_initial(U, Wu.T)
    opts: Dict[str, Any] = {"expand": bool(expand), "print_time": False,
            "ipopt": {"print_level": 5 if verbose else 0, "sb": "yes", "max_iter": int(max_iter), "tol": tol,
                      "acceptable_tol": 1e-5, "mu_strategy": "adaptive", **(ipopt_options or {})}}
    opti.solver("ipopt", opts)
    t_ipopt = _time.perf_counter()
    try:
        sol = opti.solve()
    except RuntimeError as e:
        stats = opti.stats()
        raise TrajoptError(f"ipopt failed: {stats.get('return_status', e)}") from None
    t_ipopt = _time.perf_counter() - t_ipopt
    stats = sol.stats()
    Qs = np.asarray(sol.value(Q)).reshape(dof, N + 1).T
    DQs = np.asarray(sol.value(DQ)).reshape(dof, N + 1).T
    Us = np.asarray(sol.value(U)).reshape(dof, N).T
    T_opt = float(sol.value(T)) if free_T else T_fixed
    hs = T_opt / N
    DQs[0] = DQs[-1] = 0.0

    def velocity(t):
        t = np.asarray(t, float)
        k = np.clip((t / hs).astype(int), 0, N - 1)
        return DQs[k] + Us[k] * (t - k * hs)[:, None]

    def position(t):
        t = np.asarray(t, float)
        k = np.clip((t / hs).astype(int), 0, N - 1)
        tau = (t - k * hs)[:, None]
        return Qs[k] + DQs[k] * tau + 0.5 * Us[k] * tau ** 2

    q_end = q_goal if goal_position is None else Qs[-1]
    out = resample_velocity_profile(robot, velocity, T_opt, q_start, q_end, dt_out, torque_limits, position)
    bad = (out.q < lo[None, :]) | (out.q > hi[None, :])
    if bad.any():
        k, j = map(int, np.argwhere(bad)[0])
        raise TrajoptError(f"the optimized trajectory leaves the position limits (joint {j}, sample {k}: "
                           f"q = {out.q[k, j]:.6g} outside [{lo[j]:.6g}, {hi[j]:.6g}])")
    out.info.update(solve_time=_time.perf_counter() - t_start, ipopt_time=t_ipopt,
                    iterations=int(stats.get("iter_count", -1)), status=stats.get("return_status"),
                    T_opt=T_opt, objective=float(sol.value(J)), cost=weights, n_nodes=N, tube=tube,
                    method="trajopt")
    return out
