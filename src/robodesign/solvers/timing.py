"""Time parameterization of joint-space paths into :class:`~robodesign.core.trajectory.Trajectory`
samples (the project's one trajectory type; ``JointTrajectory`` is its old name here).

Integration rule (guaranteed by every trajectory this module and :mod:`.trajopt` produce)
-----------------------------------------------------------------------------------------
Piecewise-constant acceleration ("zero-order hold" on ``ddq``): ``ddq[k]`` is the acceleration on
``[t_k, t_{k+1})`` and, for every ``k < N-1`` with ``h = t_{k+1} - t_k``::

    q[k+1]  = q[k] + dq[k]·h + ½·ddq[k]·h²
    dq[k+1] = dq[k] + ddq[k]·h

both up to floating-point rounding (measured ≤ 1e-12; :meth:`Trajectory.consistency_residual`).
The sampled trajectory therefore *is* a continuous, exactly integrated C¹ trajectory, and
:meth:`Trajectory.interpolate` evaluates it between samples. ``ddq`` of the last sample is the
acceleration after the motion: 0 for every trajectory that ends at rest.

Rest samples: every rest-to-rest motion starts with one step of zero acceleration (a "pre-roll" of one
``dt``: samples 0 and 1 both have q = q_start, dq = 0, and sample 0 has ddq = 0), so that the first and
the last sample of every motion have dq = ddq = 0 *exactly* while the rule above still holds exactly.
CoBRA needs this: ``returnTo`` compares ddq with the sample at t = 0, and a ``pause`` window that ends
where the next motion starts requires ddq = 0 at that sample. The price is one dt per motion.

How the samples are made from a continuous time-optimal profile ``v(t)`` of duration ``T = n·dt``
(:func:`resample_velocity_profile`): ``dq[k] = v(t_k)`` exactly (so velocity limits of the profile
carry over; the first and last samples are exactly 0), ``ddq[k] = (dq[k+1] − dq[k])/dt`` (the *mean*
acceleration over the step, never larger than the profile's largest acceleration on that step),
``q`` from the rule above. The trapezoid-integrated end point misses the goal by O(dt²·∫|jerk|)
(~1e-5 rad); that residual r is removed by adding ``r·w(t)`` to the velocity with a bump
``w ∝ ‖v(t)‖`` of unit integral (zero at rest), so ``q[-1]`` is the goal exactly. The reported
``info["max_path_error"]`` is the largest distance between the samples and the continuous profile.
Finally every sample is checked against |dq| ≤ dq_max (to 1e-9 relative), |ddq| ≤ ddq_max and the
drivetrain torque |τ(q, dq, ddq)| ≤ τ_max (to 1e-12 relative, ``Robot.drivetrain_torques``) with both
accelerations the judge's motion model has at the sample, ddq[k] after it and ddq[k−1] before it
(:func:`sample_torques`; the checker's ``joint.tau`` rule); if
anything is exceeded, the profile is slowed down uniformly (t → λ·t: v/λ, a/λ²; λ chosen from the
violation ratios, at least one more sample) and resampled. Position limits are not enforced here: the
path is assumed to lie within them (blends stay in the convex hull of the waypoints).

toppra path: parabolic blends (decision)
----------------------------------------
A cubic spline through the planner's waypoints can bulge out of the collision-checked corridor.
:class:`BlendedPolyline` keeps the piecewise-linear path and replaces each corner by a parabolic
blend (a quadratic Bézier from ``W − r·u_in`` via the corner ``W`` to ``W + r·u_out``), so the path
is C¹ with unit speed in joint-space arc length on the straight parts. The blend lies in the triangle
(W − r·u_in, W, W + r·u_out). For a corner of turning angle θ:

* largest distance from the piecewise-linear path: ``r·sin θ / 4`` (≤ r/4),
* distance from the waypoint itself: ``r·sin(θ/2) / 2`` (≤ r/2),

with ``r = min(blend_radius, ½·adjacent segment lengths)``; default ``blend_radius = 0.05`` rad, i.e.
at most 0.0125 rad (≈ 0.7°) away from the checked polyline and 0.025 rad from a waypoint.
``blend_radius = 0`` stops exactly at every waypoint. Corners turning by more than 175° (reversals)
are always stops. Stopping waypoints (``stop_at``) are passed exactly, at rest, at a sample.

toppra torque constraint (decision)
-----------------------------------
τ = a(s)·s̈ + b(s)·ṡ² + c(s) + f_v·q'(s)·ṡ + f_c·σ(q'(s)·ṡ), with a, b, c from pinocchio RNEA
(armature included). Friction is not linear in (s̈, ṡ²); it is bounded *conservatively*, one side at a
time, using that ṡ ≥ 0 fixes the sign of each joint's velocity:

* Coulomb: |σ| < 1 and sign(σ) = sign(q'_j), so it only tightens the bound on that side, by f_c
  (also at ṡ ≈ 0, where the true term vanishes: a path that starts with gravity within f_c of the limit
  is rejected by toppra and falls back to ruckig).
* viscous: ṡ = √x ≤ √x₀/2 + x/(2√x₀) for any x₀ > 0 (tangent of the concave √), which is linear
  in x = ṡ² and exact at x = x₀. Pass 1 uses x₀ = ¼ of the velocity-limit curve (divided by 16 while
  toppra finds it infeasible); every further pass uses x₀ = the previous solution, which keeps that
  solution feasible, so passes never get slower (``torque_passes``, default 3; measured on a
  6-DoF IMPROV move with halved torque limits: 2.70 s → 2.20 s → 2.16 s; without friction 1.62 s). A pass
  whose x₀ would equal the previous pass's bit for bit is not run: it would solve the same problem again
  (a move the torque limits do not slow down gives the same profile in pass 2 as in pass 1).

Constraints are enforced at both ends of every grid interval ("interpolation" discretization, with
the left/right limits of q''(s) at blend boundaries); what remains between grid points is caught by the
sample check above.

ruckig
------
Each segment between consecutive waypoints is a straight line q = q_a + d·s, timed by a 1-DoF ruckig
profile on s with the tightest limits along d (jerk = ``jerk_factor``·acceleration, default 10×), with
``DurationDiscretization.Discrete`` so the duration is a multiple of dt; the robot stops at every
waypoint. (ruckig's ``intermediate_positions`` needs the cloud API, so it is not used.) Torques are
then checked on the samples as above.

Non-finite velocity/acceleration limits (e.g. geometric_primitive_modules) are replaced by
:data:`UNBOUNDED_LIMIT`; non-finite torque limits are simply not constrained.
"""
from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass
from typing import Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

from robodesign.core.errors import InfeasibleError
from robodesign.core.trajectory import Trajectory
from robodesign.model.rnea_batch import rnea_rows
from robodesign.solvers.blended_path import BlendedPolyline
from robodesign.solvers.toppra_loop import pass_velocities, velocity_xbound

UNBOUNDED_LIMIT = 1e3  # stands in for an infinite velocity (rad/s, m/s) or acceleration limit
REVERSAL_ANGLE = math.radians(175.0)  # corners turning more than this are always stops
JointTrajectory = Trajectory  # the old name, kept for code written against it


class TimingError(InfeasibleError):
    """No time parameterization was found (e.g. the path is statically infeasible for the torques)."""


# ==============================================================================================
# limits, bounds, checks
# ==============================================================================================
def _finite(x, fallback: float = UNBOUNDED_LIMIT) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    return np.where(np.isfinite(x) & (x > 0), x, fallback)


def sample_torques(robot, traj: Trajectory) -> np.ndarray:
    """(N, dof) the largest |drivetrain torque| at every sample over the accelerations the judge's motion model
    has there (robodesign.judge.motion): the step's own ddq[k] just after the sample and the previous step's
    ddq[k−1] just before it (the samples are a piecewise-constant acceleration, so these are the motion's
    one-sided accelerations; the checker's ``joint.tau`` rule tests both)."""
    n = len(traj.t)
    before_acc = np.concatenate((traj.ddq[:1], traj.ddq[:-1])) if n >= 2 else traj.ddq[:0]
    # torque is affine in q̈ at fixed (q, q̇): τ_before = τ_after + M(q)·(q̈_before − q̈_after), computed directly;
    # the link-side RNEA and the drivetrain terms of both in one batched call each (row by row the same operations),
    # 'before' only at the samples where q̈ changes: elsewhere the same inputs (equal up to the sign of a zero, which
    # changes no torque beyond the sign of a zero: |τ| is taken)
    differ = np.any(before_acc != traj.ddq[:len(before_acc)], axis=1)
    Q = np.concatenate((traj.q, traj.q[:len(before_acc)][differ]))
    DQ = np.concatenate((traj.dq, traj.dq[:len(before_acc)][differ]))
    DDQ = np.concatenate((traj.ddq, before_acc[differ]))
    tau = robot.drivetrain_torques(Q, DQ, DDQ, link_torques=robot.link_torques(Q, DQ, DDQ))
    after = tau[:n]
    if n < 2:
        return np.abs(after)
    before = after.copy()
    before[differ] = tau[n:]
    return np.maximum(np.abs(after), np.abs(before))


def trapezoid_time(distance: float, v_max: float, a_max: float) -> float:
    """Minimum rest-to-rest time over ``distance`` with |v| ≤ v_max, |a| ≤ a_max (trapezoid or bang-bang)."""
    d = abs(float(distance))
    if d == 0.0:
        return 0.0
    v_inf, a_inf = not math.isfinite(v_max), not math.isfinite(a_max)
    if a_inf:
        return 0.0 if v_inf else d / v_max
    if v_inf or d <= v_max ** 2 / a_max:
        return 2.0 * math.sqrt(d / a_max)
    return d / v_max + v_max / a_max


def time_optimal_bound(robot, q_a, q_b) -> float:
    """Lower bound on the duration of a rest-to-rest move q_a → q_b: the slowest joint's optimal
    trapezoid/bang-bang time under its own velocity and acceleration limits (torques, jerk, paths and
    coordination ignored)."""
    return float(time_optimal_bounds(robot, np.asarray(q_b, float) - np.asarray(q_a, float)))


def time_optimal_bounds(robot, D: np.ndarray) -> np.ndarray:
    """``time_optimal_bound`` for many moves at once: ``D`` holds joint distances |q_b - q_a| on its last
    axis; returns the bound of each move (the slowest joint's trapezoid/bang-bang time)."""
    D = np.abs(np.asarray(D, dtype=float))
    v, a = np.asarray(robot.dq_max, dtype=float), np.asarray(robot.ddq_max, dtype=float)
    if v.shape == a.shape == D.shape[-1:] and D.shape[-1] and bool(np.all((v > 0) & (a > 0) & (v < np.inf)
                                                                         & (a < np.inf))):
        # positive finite limits: the same elementwise numbers (v/a and v·v/a per joint, as on every broadcast
        # element), without the infinite cases and with no division to warn about
        t = np.where(D <= v * v / a, 2.0 * np.sqrt(D / a), D / v + v / a)
        return np.where(D == 0.0, 0.0, t).max(axis=-1)
    v = np.broadcast_to(v, D.shape)
    a = np.broadcast_to(a, D.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        bang = 2.0 * np.sqrt(D / a)                      # never reaches v (a finite)
        trap = D / v + v / a                             # reaches v
        t = np.where(np.isinf(v) | (D <= v * v / a), bang, trap)
        t = np.where(np.isinf(a), np.where(np.isinf(v), 0.0, D / v), t)
    t = np.where(D == 0.0, 0.0, t)
    return t.max(axis=-1) if t.shape[-1] else np.zeros(t.shape[:-1])


def jerk_limited_time(distance: float, v_max: float, a_max: float, j_max: float) -> float:
    """Minimum rest-to-rest time of a 1-DoF move with velocity, acceleration and jerk limits (the
    7-segment profile ruckig computes; used by tests and to report bounds)."""
    d = abs(float(distance))
    if d == 0.0:
        return 0.0
    v, a, j = float(v_max), float(a_max), float(j_max)
    # acceleration phase to speed w: duration and distance
    def acc_phase(w):
        if w >= a * a / j:  # reaches a
            ta = w / a + a / j
        else:
            ta = 2.0 * math.sqrt(w / j)
        return ta, 0.5 * w * ta
    ta, da = acc_phase(v)
    if 2 * da <= d:
        return 2 * ta + (d - 2 * da) / v
    lo, hi = 0.0, v  # peak speed w < v: solve 2·dist(w) = d by bisection
    for _ in range(200):
        w = 0.5 * (lo + hi)
        if 2 * acc_phase(w)[1] < d:
            lo = w
        else:
            hi = w
    return 2 * acc_phase(0.5 * (lo + hi))[0]


# ==============================================================================================
# sampling a continuous profile
# ==============================================================================================
def _zoh_from_velocity(q0: np.ndarray, q1: np.ndarray, V: np.ndarray, h: float):
    """Samples (q, dq, ddq) obeying the integration rule with dq ≈ V, q[0]=q0 and q[-1]=q1 exactly (by the compiled
    topp_kernel.zoh_rows once it is ready: the same numbers as the numpy calls here)."""
    from robodesign.solvers import topp_kernel
    V = np.array(V, dtype=float)
    n = len(V) - 1
    dof = len(q0)
    if n <= 0:
        return q0.reshape(1, dof).copy(), np.zeros((1, dof)), np.zeros((1, dof))
    if dof > 0 and topp_kernel.ready():
        Q, A = np.empty_like(V), np.empty_like(V)
        topp_kernel.zoh_rows(np.array(q0, dtype=float), np.array(q1, dtype=float), V, float(h), Q, A)
        return Q, V, A
    V[0] = 0.0
    V[-1] = 0.0
    inc = 0.5 * h * (V[:-1] + V[1:])
    r = (q1 - q0) - inc.sum(axis=0)
    w = np.linalg.norm(V, axis=1)
    W = float(np.sum(0.5 * h * (w[:-1] + w[1:])))
    if W > 0:
        V += np.outer(w / W, r)
    A = np.zeros_like(V)
    A[:-1] = np.diff(V, axis=0) / h
    steps = V[:-1] * h + 0.5 * A[:-1] * h * h
    Q = np.empty_like(V)
    Q[0] = q0
    Q[1:] = q0 + np.cumsum(steps, axis=0)
    Q[-1] = q1
    return Q, V, A


@dataclass
class _Profile:
    """A continuous rest-to-rest profile: velocity(t) for t in [0, duration], from q_start to q_goal."""
    duration: float
    velocity: Callable[[np.ndarray], np.ndarray]  # (n,) times → (n, dof)
    q_start: np.ndarray
    q_goal: np.ndarray
    position: Optional[Callable[[np.ndarray], np.ndarray]] = None  # optional, for the path-error report


def resample_velocity_profile(robot, velocity: Callable[[np.ndarray], np.ndarray], duration: float,
                              q_start, q_goal, dt: float, torque_limits: bool = True,
                              position: Optional[Callable] = None, max_iter: int = 60) -> Trajectory:
    """Sample a continuous rest-to-rest velocity profile at ``dt`` (duration rounded up to a multiple
    of dt) obeying the integration rule, and slow it down uniformly until every sample satisfies the
    velocity, acceleration and (optionally) drivetrain-torque limits."""
    prof = _Profile(float(duration), velocity, np.asarray(q_start, float), np.asarray(q_goal, float), position)
    return _fit_limits(robot, prof, dt, torque_limits, max_iter)


def _sample(prof: _Profile, n: int, h: float) -> Tuple[Trajectory, float]:
    """n steps of the (stretched) profile after one step of rest (the pre-roll; module docstring)."""
    T_new = n * h
    lam = T_new / prof.duration
    tp = h * np.arange(n + 1)
    V = np.zeros((n + 2, len(prof.q_start)))
    V[1:] = prof.velocity(np.minimum(tp / lam, prof.duration)) / lam
    Q, V, A = _zoh_from_velocity(prof.q_start, prof.q_goal, V, h)
    return Trajectory(h * np.arange(n + 2), Q, V, A), lam


#: :func:`_fit_limits` gives up when STALL_WINDOW slow-downs in a row took less than STALL_GAIN (relative) off the
#: torque ratio
STALL_WINDOW = 5
STALL_GAIN = 0.01
STALL_DOUBLINGS = 2
#: nor slows a motion down more than this factor (a motion 100× slower than its time-optimal profile is no
#: candidate for a cycle time; unbounded, a joint whose friction exceeds its limit made 10⁷-sample motions)
MAX_STRETCH = 100.0


def _limit_ratio(X: np.ndarray, limit: np.ndarray) -> float:
    """The largest X/limit over the columns (joints) whose limit is finite, 0 without any. With every limit finite
    the whole of X is divided (the same elements, so the same maximum, without the column copy)."""
    m = np.isfinite(limit)
    if not m.any():
        return 0.0
    return float(np.max(X / limit if m.all() else X[:, m] / limit[m]))


def _fit_limits(robot, prof: _Profile, h: float, torque_limits: bool, max_iter: int = 60) -> Trajectory:
    if prof.duration <= 0 or np.max(np.abs(prof.q_goal - prof.q_start), initial=0.0) == 0.0:
        tr = Trajectory.at_rest(prof.q_goal)
        tr.info.update(stretch=1.0, max_path_error=0.0)
        return tr
    vmax = np.asarray(robot.dq_max, float)
    amax = np.asarray(robot.ddq_max, float)
    tmax = np.asarray(robot.tau_max, float)
    n = max(1, int(math.ceil(prof.duration / h - 1e-9)))
    torque_history: List[float] = []
    doublings = 0
    for it in range(max_iter):
        tr, lam = _sample(prof, n, h)
        rv = _limit_ratio(np.abs(tr.dq), vmax)
        ra = _limit_ratio(np.abs(tr.ddq), amax)
        rt = _limit_ratio(sample_torques(robot, tr), tmax) if torque_limits and np.isfinite(tmax).any() else 0.0
        if rv <= 1.0 + 1e-9 and ra <= 1.0 + 1e-12 and rt <= 1.0 + 1e-12:
            err = 0.0
            if prof.position is not None:
                tq = np.maximum(tr.t[1:] - h, 0.0) / lam
                err = float(np.max(np.abs(prof.position(np.minimum(tq, prof.duration)) - tr.q[1:])))
            tr.info.update(stretch=lam, max_path_error=err, limit_ratios={"dq": rv, "ddq": ra, "tau": rt},
                           stretch_iterations=it)
            return tr
        if torque_limits and rt > 1.0 and it == 0:
            # statically infeasible? then no slow-down helps
            g = robot.drivetrain_torques(tr.q, np.zeros_like(tr.q), np.zeros_like(tr.q))
            m = np.isfinite(tmax)
            if np.any(np.abs(g[:, m]) > tmax[m]):
                raise TimingError("the path passes configurations where gravity alone exceeds the torque limit")
        if torque_limits and rt > 1.0:
            torque_history.append(rt)
            # slowing down shrinks the inertial and velocity terms; what stays is gravity and Coulomb friction
            # while moving. When STALL_WINDOW slow-downs took less than STALL_GAIN off the torque ratio, the
            # duration is doubled (at most STALL_DOUBLINGS times); a ratio still over the limit after that is
            # gravity and friction alone: give up instead of stretching the motion sixty times
            if len(torque_history) > STALL_WINDOW and rt > torque_history[-1 - STALL_WINDOW] * (1 - STALL_GAIN):
                if doublings >= STALL_DOUBLINGS:
                    raise TimingError(f"slowing down does not bring the torque within the limit (|τ|/τ_max = "
                                      f"{rt:.4f} after {it} slow-downs, stretch {lam:.3f}: gravity and friction)")
                doublings += 1
                torque_history.clear()
                n *= 2
                continue
        grow = max(1.0, rv, math.sqrt(max(ra, 0.0)), math.sqrt(max(rt, 0.0)) if rt > 1 else 1.0) * (1.0 + 1e-4)
        n = max(n + 1, int(math.ceil(n * grow - 1e-9)))
        if n * h > MAX_STRETCH * max(prof.duration, h):
            raise TimingError(f"the limits need the motion slowed down more than {MAX_STRETCH:g} times "
                              f"(|dq|/limit {rv:.3g}, |ddq|/limit {ra:.3g}, |τ|/limit {rt:.3g})")
    raise TimingError(f"could not satisfy the limits after {max_iter} slow-downs (stretch {lam:.3f})")


# ==============================================================================================
# toppra: blended polyline path and dynamics constraint
# ==============================================================================================
_TOPPRA = None


def _toppra():
    global _TOPPRA
    if _TOPPRA is None:
        import toppra  # noqa: F401  (slow import: 1.3 s, only when needed)
        import toppra.algorithm  # noqa: F401
        import toppra.constraint  # noqa: F401
        import toppra.solverwrapper as sw
        # toppra asks the file system for its optional solvers (qpoases, cvxpy) at every TOPPRA set-up
        # (importlib.util.find_spec, ~2 ms); the answer cannot change within a process, so ask once
        found = sw.available_solvers(False)
        sw.available_solvers = lambda output_msg=True: found
        _TOPPRA = toppra
    return _TOPPRA


_VEL_CONSTRAINTS: Dict[bytes, object] = {}


def _velocity_constraint(vmax: np.ndarray):
    """toppra's JointVelocityConstraint for ±vmax, built once per limit vector (its set-up formats the limits
    into a description string, several ms per call; the object keeps no state of a path)."""
    key = np.asarray(vmax, float).tobytes()
    c = _VEL_CONSTRAINTS.get(key)
    if c is None:
        if len(_VEL_CONSTRAINTS) > 256:
            _VEL_CONSTRAINTS.clear()
        c = _VEL_CONSTRAINTS[key] = _toppra().constraint.JointVelocityConstraint(np.column_stack([-vmax, vmax]))
    return c


def preload() -> None:
    """Import toppra now (its import is slow) and load the compiled TOPP-RA kernel (or start its background
    compilation: topp_kernel.ready) instead of at the first time scaling."""
    _toppra()
    from robodesign.solvers import topp_kernel
    topp_kernel.ready()


class _PathTerms:
    """What the dynamics constraint needs of a path on a grid and does not depend on the viscous tangent
    points: q'(s), q''(s) (right and left limits) and the RNEA terms g(q), a = M(q)·q' and
    b = M(q)·q'' + C(q, q')·q' per grid point. Built once per path and shared by every torque pass."""

    def __init__(self, robot, path, grid: np.ndarray, use_torque: bool):
        self.path, self.grid = path, np.array(grid, dtype=float)
        if isinstance(path, BlendedPolyline):  # (the grid located once: the same numbers as a call per order)
            q, self.qs, self.qss_r = path.eval_orders(grid, (0, 1, 2))
            # without blends q'' is 0 everywhere, from either side: the left limits are the same numbers
            self.qss_l = path.eval_orders(grid, (2,), left=True)[0] if path.is_blend.any() else self.qss_r
        else:
            q, self.qs, self.qss_r = path(grid, 0), path(grid, 1), path(grid, 2)
            self.qss_l = path.eval_left(grid, 2) if hasattr(path, "eval_left") else self.qss_r
        self.g = self.a = self.bR = self.bL = None
        if not use_torque:
            return
        qs, qss_r, qss_l = self.qs, self.qss_r, self.qss_l
        N1 = len(q)
        left = ~np.all(qss_l == qss_r, axis=1) if qss_l is not qss_r else np.zeros(N1, bool)  # own left limits
        zero = np.zeros_like(q)
        # per grid point rnea(q, 0, 0), rnea(q, 0, q'), rnea(q, q', q''⁺) and where it differs rnea(q, q', q''⁻):
        # one batched call (rnea_batch: the same numbers as a call each)
        T = rnea_rows(robot.model, np.concatenate((q, q, q, q[left])), np.concatenate((zero, zero, qs, qs[left])),
                      np.concatenate((zero, qs, qss_r, qss_l[left])))
        G = T[:N1]
        BR = T[2 * N1:3 * N1] - G
        BL = BR
        if qss_l is not qss_r:
            BL = BR.copy()
            BL[left] = T[3 * N1:] - G[left]
        self.g, self.a, self.bR, self.bL = G, T[N1:2 * N1] - G, BR, BL


def _dynamics_constraint_class():
    _toppra()
    from toppra.constraint import LinearConstraint

    class DynamicsConstraint(LinearConstraint):
        """Joint acceleration + (conservative) drivetrain torque limits, interpolation discretization."""

        def __init__(self, robot, amax, tau_max, x0: Optional[np.ndarray], use_torque: bool,
                     terms: Optional["_PathTerms"] = None):
            super().__init__()
            self.robot, self.amax, self.tau_max, self.x0, self.use_torque = robot, amax, tau_max, x0, use_torque
            self.terms = terms
            self.identical = True

        def compute_constraint_params(self, path, gridpoints, *args, **kwargs):
            tm = self.terms
            if tm is None or tm.path is not path or not np.array_equal(tm.grid, gridpoints):
                tm = _PathTerms(self.robot, path, gridpoints, self.use_torque)
            N1 = len(gridpoints)
            dof = path.dof
            qs, qss_r, qss_l = tm.qs, tm.qss_r, tm.qss_l
            nb = 3 if self.use_torque else 1
            a = np.zeros((N1, nb * dof))
            bR = np.zeros((N1, nb * dof))
            bL = np.zeros((N1, nb * dof))
            cc = np.zeros((N1, nb * dof))
            a[:, :dof] = qs
            bR[:, :dof] = qss_r
            bL[:, :dof] = qss_l
            g_lim = [self.amax, self.amax]
            if self.use_torque:
                robot = self.robot
                tmax = self.tau_max
                finite = np.isfinite(tmax)
                fv, fc = robot.friction_viscous, robot.friction_coulomb
                x0 = np.maximum(self.x0, 1e-8)
                # the same arithmetic as one grid point at a time, on every grid point at once
                sq = np.sqrt(x0)[:, None]
                g, ai, bri, bli = tm.g, tm.a, tm.bR, tm.bL
                pos, neg = qs > 0, qs < 0
                beta_up = np.where(pos, fv * qs / (2 * sq), 0.0)
                gam_up = np.where(pos, fc + fv * qs * sq / 2, 0.0)
                beta_lo = np.where(neg, fv * -qs / (2 * sq), 0.0)
                gam_lo = np.where(neg, fc + fv * -qs * sq / 2, 0.0)
                sl_up, sl_lo = slice(dof, 2 * dof), slice(2 * dof, 3 * dof)
                a[:, sl_up] = np.where(finite, ai, 0.0)
                a[:, sl_lo] = np.where(finite, ai, 0.0)
                bR[:, sl_up] = np.where(finite, bri + beta_up, 0.0)
                bR[:, sl_lo] = np.where(finite, bri - beta_lo, 0.0)
                bL[:, sl_up] = np.where(finite, bli + beta_up, 0.0)
                bL[:, sl_lo] = np.where(finite, bli - beta_lo, 0.0)
                cc[:, sl_up] = np.where(finite, g + gam_up, 0.0)
                cc[:, sl_lo] = np.where(finite, g - gam_lo, 0.0)
                tl = np.where(finite, tmax, 1.0)
                g_lim += [tl, tl]
            m = nb * dof
            # F v ≤ g with v = [acc; τ_up; τ_lo]: acc ≤ amax, −acc ≤ amax, τ_up ≤ τmax, −τ_lo ≤ τmax
            F = np.zeros((2 * dof + (2 * dof if self.use_torque else 0), m))
            I = np.eye(dof)
            F[:dof, :dof] = I
            F[dof:2 * dof, :dof] = -I
            if self.use_torque:
                F[2 * dof:3 * dof, dof:2 * dof] = I
                F[3 * dof:, 2 * dof:] = -I
            g = np.concatenate(g_lim)
            # interpolation scheme: stage i constrains (u_i, x_i) at s_i⁺ and (u_i, x_i + 2Δ_i u_i) at s_{i+1}⁻
            deltas = np.diff(gridpoints)
            A2 = np.zeros((N1, 2 * m))
            B2 = np.zeros((N1, 2 * m))
            C2 = np.zeros((N1, 2 * m))
            A2[:, :m], B2[:, :m], C2[:, :m] = a, bR, cc
            A2[:-1, m:] = a[1:] + 2 * deltas[:, None] * bL[1:]
            B2[:-1, m:] = bL[1:]
            C2[:-1, m:] = cc[1:]
            A2[-1, m:], B2[-1, m:], C2[-1, m:] = a[-1], bL[-1], cc[-1]
            k = F.shape[0]
            F2 = np.zeros((2 * k, 2 * m))
            F2[:k, :m] = F
            F2[k:, m:] = F
            return A2, B2, C2, F2, np.concatenate([g, g]), None, None

    return DynamicsConstraint


_DYN_CLS = None


def _same_tangents(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two passes' viscous tangent points are the same bit for bit (then so are their profiles)."""
    return bool(np.array_equal(a, b))


class _ToppraMotion:
    """The motion of a TOPP-RA profile along its path: on grid interval i (from time T_grid[i], dt_i[i] long) the
    path parameter s moves from grid[i] at speed sd[i] with the constant acceleration u[i]; its joint velocity
    and position at given times (1-d arrays)."""

    def __init__(self, path, grid, sd, dt_i, u, T_grid):
        self.path, self.grid, self.sd, self.dt_i, self.u, self.T_grid = path, grid, sd, dt_i, u, T_grid

    def s_of_t(self, t: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """(s(t), ṡ(t))."""
        grid, sd, dt_i, u, T_grid = self.grid, self.sd, self.dt_i, self.u, self.T_grid
        i = np.clip(np.searchsorted(T_grid, t, side="right") - 1, 0, len(dt_i) - 1)
        tau_ = np.clip(t - T_grid[i], 0.0, dt_i[i])
        sdot = np.maximum(sd[i] + u[i] * tau_, 0.0)
        s = np.minimum(grid[i] + sd[i] * tau_ + 0.5 * u[i] * tau_ ** 2, grid[i + 1])
        return s, sdot

    def _at(self, t, order: int) -> np.ndarray:
        """q'(s(t))·ṡ(t) (``order`` 1) or q(s(t)) (0): on a BlendedPolyline by the compiled
        topp_kernel.profile_rows once it is ready (the same numbers as these numpy calls)."""
        from robodesign.solvers import topp_kernel
        t = np.asarray(t, float)
        path = self.path
        if isinstance(path, BlendedPolyline) and t.ndim == 1 and topp_kernel.ready():
            out = np.empty((len(t), path.dof))
            topp_kernel.profile_rows(self.T_grid, self.dt_i, self.sd, self.u, self.grid, path.breaks, path.p0,
                                     path.d0, path.c, float(path.length), path.points[-1], np.array(t, dtype=float),
                                     order, out)
            return out
        s, sdot = self.s_of_t(t)
        return path(s, 1) * sdot[:, None] if order == 1 else path(s, 0)

    def velocity(self, t) -> np.ndarray:
        """(len(t), dof) the joint velocities q'(s(t))·ṡ(t) (the _Profile's ``velocity``)."""
        return self._at(t, 1)

    def position(self, t) -> np.ndarray:
        """(len(t), dof) the joint positions q(s(t)) (the _Profile's ``position``, for the path-error report)."""
        return self._at(t, 0)


def _toppra_profile(robot, path: BlendedPolyline, vmax, amax, torque_limits: bool, grid_step: float,
                    torque_passes: int) -> Tuple[_Profile, dict]:
    global _DYN_CLS
    tp = _toppra()
    if _DYN_CLS is None:
        _DYN_CLS = _dynamics_constraint_class()
    grid = path.gridpoints(grid_step)
    vel = _velocity_constraint(vmax)
    tau = np.asarray(robot.tau_max, float)
    use_torque = bool(torque_limits and np.any(np.isfinite(tau)))
    terms = _PathTerms(robot, path, grid, use_torque)   # RNEA along the path once, not once per pass
    qs = np.abs(terms.qs)
    with np.errstate(divide="ignore", over="ignore"):  # tiny path derivatives: the bound is +inf anyway
        x_vel = np.min(np.where(qs > 1e-12, (vmax / np.maximum(qs, 1e-300)) ** 2, np.inf), axis=1)
    x_vel = np.minimum(x_vel, 1e6)
    sd = None
    passes = max(1, torque_passes) if use_torque else 1
    # viscous tangent points: pass 1 at a quarter of the velocity-limit curve (halving it on failure),
    # later passes at the previous solution (which stays feasible, so they never get slower)
    x0 = x_vel / 4.0
    p = 0
    xbound = velocity_xbound(vel, terms.qs)   # the velocity constraint's x bounds, once per path
    while p < passes:
        sd_vec, code = pass_velocities(tp, vel, _DYN_CLS(robot, amax, tau, x0, use_torque, terms), path, grid,
                                        xbound)
        if sd_vec is None:
            if sd is not None:
                break  # keep the previous (feasible) pass
            if use_torque and np.max(x0 / x_vel) > 1e-4:
                x0 = x0 / 16.0
                continue
            raise TimingError(f"toppra failed: {code}")
        sd = np.maximum(np.asarray(sd_vec, float), 0.0)
        x_next = np.maximum(sd ** 2, 1e-4 * x_vel)
        p += 1
        if _same_tangents(x_next, x0):
            break  # the next pass would solve the same problem again: the same profile (converged)
        x0 = x_next
    assert sd is not None  # the loop ends after a feasible pass (or raises)
    sd[0] = sd[-1] = 0.0
    ds = grid[1:] - grid[:-1]
    denom = sd[:-1] + sd[1:]
    if np.any(denom <= 0):
        raise TimingError("toppra returned a zero-velocity interval")
    dt_i = 2 * ds / denom
    u = (sd[1:] ** 2 - sd[:-1] ** 2) / (2 * ds)
    T_grid = np.concatenate([[0.0], np.cumsum(dt_i)])
    motion = _ToppraMotion(path, grid, sd, dt_i, u, T_grid)
    prof = _Profile(float(T_grid[-1]), motion.velocity, path.points[0].copy(), path.points[-1].copy(),
                    motion.position)
    return prof, {"gridpoints": len(grid), "toppra_duration": float(T_grid[-1]), "torque_passes": p}


# ==============================================================================================
# ruckig
# ==============================================================================================
def _ruckig_profile(q_a, q_b, vmax, amax, jmax, dt) -> _Profile:
    import ruckig
    d = np.asarray(q_b, float) - np.asarray(q_a, float)
    L = float(np.linalg.norm(d))
    if L == 0.0:
        return _Profile(0.0, lambda t: np.zeros((len(np.atleast_1d(t)), len(d))), q_a, q_b)
    u = d / L
    au = np.abs(u)
    m = au > 1e-15
    v_s = float(np.min(vmax[m] / au[m]))
    a_s = float(np.min(amax[m] / au[m]))
    j_s = float(np.min(jmax[m] / au[m]))
    otg = ruckig.Ruckig(1, dt)
    inp = ruckig.InputParameter(1)
    inp.current_position, inp.current_velocity, inp.current_acceleration = [0.0], [0.0], [0.0]
    inp.target_position, inp.target_velocity, inp.target_acceleration = [L], [0.0], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [v_s], [a_s], [j_s]
    inp.duration_discretization = ruckig.DurationDiscretization.Discrete
    tr = ruckig.Trajectory(1)
    res = otg.calculate(inp, tr)
    if res not in (ruckig.Result.Working, ruckig.Result.Finished):
        raise TimingError(f"ruckig failed: {res}")
    T = float(tr.duration)

    def sdot(t):
        return np.array([tr.at_time(float(x))[1][0] for x in np.atleast_1d(t)])

    def velocity(t):
        return np.outer(sdot(t), u)

    def position(t):
        return np.asarray(q_a, float) + np.outer([tr.at_time(float(x))[0][0] for x in np.atleast_1d(t)], u)

    return _Profile(T, velocity, np.asarray(q_a, float), np.asarray(q_b, float), position)


# ==============================================================================================
# public entry point
# ==============================================================================================
def _split(K: int, stops: Sequence[int]) -> List[Tuple[int, int]]:
    idx = sorted({0, K - 1, *[int(i) for i in stops]})
    return [(a, b) for a, b in zip(idx[:-1], idx[1:])]


def time_parameterize(robot, path, dt: float = 0.01, method: str = "toppra", torque_limits: bool = True,
                      stop_at: Optional[Sequence[int]] = None, *, blend_radius: float = 0.05,
                      jerk_factor: float = 10.0, grid_step: float = 0.02, torque_passes: int = 3,
                      fallback: bool = True) -> Trajectory:
    """Time-parameterize a joint-space path (K×dof waypoints) from rest to rest, sampled every ``dt``.

    * ``method="toppra"``: time-optimal along a blended polyline (``blend_radius``; 0 = stop at every
      waypoint), velocity, acceleration and (``torque_limits``) drivetrain-torque limits. If toppra
      fails and ``fallback`` is set, the ruckig method is used (``info["method"]`` says which).
    * ``method="ruckig"``: straight segments, stopping at every waypoint, jerk-limited
      (``jerk_factor`` × acceleration limit).
    * ``stop_at``: waypoint indices where the robot must be at rest (dq = ddq = 0 exactly at one
      sample, q = the waypoint exactly); the first and last waypoints always are.

    Returns a :class:`Trajectory` starting at t = 0 (each rest-to-rest part begins with one rest step,
    see the module docstring) with ``info`` keys: ``method`` ("toppra", "ruckig" or "toppra+ruckig"
    after a fallback), ``stop_samples`` ({waypoint index: index of the sample where the robot arrives
    there at rest} for every waypoint passed at rest — use ``t[k]`` as the CoBRA goal time),
    ``solve_time`` (s, whole call), ``toppra_time``, ``gridpoints``, ``max_path_deviation`` (bound on
    the distance from the polyline, from the blends), ``max_path_error`` (samples vs. continuous
    profile), ``stretch`` (largest uniform slow-down the sample check needed; 1 = none).
    Raises :class:`TimingError` if no parameterization satisfies the limits (e.g. gravity alone
    exceeds a torque limit on the path).
    """
    t_start = _time.perf_counter()
    P = np.asarray(path, dtype=float)
    if P.ndim == 1:
        P = P.reshape(-1, robot.dof)
    if P.ndim != 2 or P.shape[1] != robot.dof or len(P) == 0:
        raise ValueError(f"path must be K×{robot.dof}, got shape {np.shape(path)}")
    if not np.all(np.isfinite(P)):
        raise ValueError("path contains non-finite values")
    if dt <= 0:
        raise ValueError("dt must be positive")
    if method not in ("toppra", "ruckig"):
        raise ValueError(f"unknown method {method!r} (toppra, ruckig)")
    K = len(P)
    stops = list(stop_at or [])
    for i in stops:
        if not -K <= int(i) < K:
            raise ValueError(f"stop_at index {i} out of range for {K} waypoints")
    stops = [int(i) % K for i in stops]
    vmax = _finite(robot.dq_max)
    amax = _finite(robot.ddq_max)
    jmax = jerk_factor * amax
    if method == "ruckig" or blend_radius <= 0:
        stops = list(range(K))
    else:  # reversals are stops
        for i in range(1, K - 1):
            a, b = P[i] - P[i - 1], P[i + 1] - P[i]
            na, nb = np.linalg.norm(a), np.linalg.norm(b)
            if na > 1e-12 and nb > 1e-12 and a @ b < math.cos(REVERSAL_ANGLE) * na * nb:
                stops.append(i)
    used = method
    traj: Optional[Trajectory] = None
    stop_samples: Dict[int, int] = {0: 0}
    max_dev, max_err, stretch, n_grid, tp_time = 0.0, 0.0, 1.0, 0, 0.0

    def append(part: Trajectory, waypoint: int) -> None:
        nonlocal traj, max_err, stretch
        max_err = max(max_err, part.info.get("max_path_error", 0.0))
        stretch = max(stretch, part.info.get("stretch", 1.0))
        traj = part if traj is None else traj.concatenate(part)
        stop_samples[waypoint] = len(traj) - 1

    for a, b in _split(K, stops):
        seg = P[a:b + 1]
        if np.max(np.abs(seg - seg[0])) == 0.0:
            append(Trajectory.at_rest(seg[0]), b)
            continue
        if method == "toppra":
            try:
                bp = BlendedPolyline(seg, blend_radius)
                t0 = _time.perf_counter()
                prof, meta = _toppra_profile(robot, bp, vmax, amax, torque_limits, grid_step, torque_passes)
                tp_time += _time.perf_counter() - t0
                part = _fit_limits(robot, prof, dt, torque_limits)
                max_dev = max(max_dev, bp.max_deviation)
                n_grid += meta["gridpoints"]
                append(part, b)
                continue
            except TimingError:
                if not fallback:
                    raise
                used = "toppra+ruckig"
        # ruckig: straight lines, stopping at every waypoint of the segment
        for i in range(len(seg) - 1):
            prof = _ruckig_profile(seg[i], seg[i + 1], vmax, amax, jmax, dt)
            append(_fit_limits(robot, prof, dt, torque_limits), a + i + 1)
    if traj is None:  # a single waypoint
        traj = Trajectory.at_rest(P[0])
    traj.ddq[-1] = 0.0
    traj.dq[-1] = 0.0
    traj.info.update(method=used, stop_samples=dict(sorted(stop_samples.items())),
                     solve_time=_time.perf_counter() - t_start, toppra_time=tp_time, max_path_deviation=max_dev,
                     max_path_error=max_err, stretch=stretch, gridpoints=n_grid)
    return traj
