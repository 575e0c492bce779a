"""Numerical inverse kinematics onto a *tolerated* pose.

:func:`solve_ik` runs Levenberg–Marquardt (damped least squares) from seeded random restarts and
returns every distinct, collision-free joint configuration it finds whose TCP pose satisfies
``goal.valid`` (up to ``n_solutions``).

How the tolerance is used (robodesign's decisions; see docs of :mod:`robodesign.tolerance`):

* The error is not the full 6-D ``log6(nominal⁻¹·T)`` but one row per *active* tolerance constraint,
  computed analytically from ``Δ = nominal⁻¹·T`` = (p, R) — exactly the quantities the projections are
  defined on: ``x, y, z`` → p_i; ``r_sph`` → ‖p‖; ``r_cyl`` → √(x²+y²); ``phi_cyl``/``phi_sph``/``theta`` →
  the angle times its lever arm (metres); ``N_x, N_y, N_z`` → components of ``log3(R)``; ``Theta_R`` →
  the rotation angle. Frames other than ``nominal`` rotate p and log3(R) by the constant Q of the frame.
  A direction no constraint bounds (e.g. the yaw about the tool z when only ``N_x``/``N_y`` are given)
  therefore has no row at all, which is the "weight 0" of a weighted 6-D error, derived per constraint.
* Each row is a *dead-zone* residual: the value minus its clamp into a target interval, which is the
  tolerance interval shrunk by a quarter of its width on every side not at the projection's natural
  limit (``r ≥ 0``, ``θ ≥ 0``; one-sided infinite intervals by 1e-4). Inside the target a row is zero and
  drops out. For a symmetric tolerance about the nominal this converges towards the nominal; when the
  nominal lies outside the tolerance (allowed by the format) it still converges to a valid pose.
* A solution is accepted as soon as ``goal.valid(fk(q))`` (checked only once the model's own exact check
  passes, so ``valid`` is called rarely). Projections without an analytic row (``R/P/Y``, Euler angles,
  quaternions) fall back to a full rotation error towards a fixed valid orientation
  (``goal.project_nominal()``), active while any of them is violated.
* A goal position farther from the first joint than an upper bound of the arm's reach (sum of the
  distances between consecutive joint origins, prismatic strokes and the TCP offset) fails at once.

Inner loop: ``pin.computeJointJacobians`` + ``updateFramePlacement`` + ``getFrameJacobian(LOCAL)`` (the same
Jacobian as ``robot.jacobian(q, reference=pin.LOCAL)`` without the per-call input checks), damping
``λ = ½‖e‖² + 1e-6`` (Sugihara's LM: well damped far from the goal, Gauss–Newton close to it), a step
capped at 1 rad, clamping to the joint limits. A restart ends on acceptance, after ``max_iter`` iterations,
or when the error has not dropped by 1 % within 8 iterations.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np
import pinocchio as pin

from ..errors import InputError
from ..tolerance import PROJECTIONS, ToleratedPose

__all__ = ["IKResult", "solve_ik", "reach_bound", "DISTINCT_TOL"]

DISTINCT_TOL = 0.1          # rad: solutions closer than this (Euclidean, joint space) count as one
_SHRINK = 0.25              # dead-zone: shrink each bounded side by this fraction of the interval width
_OPEN_MARGIN = 1e-4         # dead-zone margin on a one-sided infinite interval (m or rad)
_EPS = 1e-12                # the tolerance's own comparison slack
_LAMBDA_FACTOR = 0.1
_LAMBDA_BIAS = 1e-6
_MAX_STEP = 1.0             # rad (or m for prismatic joints), infinity norm of one LM step
_STALL_WINDOW = 8
_STALL_RATIO = 0.99
_DEGENERATE = 1e-12


@dataclass
class IKResult:
    """``solutions``: distinct valid configurations (first = first found); ``stats``: counters and timing."""
    solutions: List[np.ndarray]
    stats: Dict[str, object] = field(default_factory=dict)

    @property
    def success(self) -> bool:
        return bool(self.solutions)

    @property
    def q(self) -> Optional[np.ndarray]:
        return self.solutions[0] if self.solutions else None

    def __bool__(self) -> bool:
        return self.success


# ---------------------------------------------------------------------------------------------------------
# The goal as analytic residual rows
# ---------------------------------------------------------------------------------------------------------
def _shrunk(lo: float, hi: float, nat_lo: float, nat_hi: float) -> Tuple[float, float]:
    """Dead-zone interval inside [lo, hi] (sides at the natural limits of the projection stay)."""
    if math.isfinite(lo) and math.isfinite(hi):
        m = _SHRINK * (hi - lo)
    else:
        m = _OPEN_MARGIN
    a = lo + m if lo > nat_lo and math.isfinite(lo) else lo
    b = hi - m if hi < nat_hi and math.isfinite(hi) else hi
    if a > b:  # only for one-sided margins on very narrow intervals
        a = b = 0.5 * (lo + hi)
    return a, b


def _lin_dist(v: float, pieces) -> float:
    best = math.inf
    for a, b in pieces:
        if v > b:
            d = v - b
        elif v < a:
            d = v - a
        else:
            return 0.0
        if abs(d) < abs(best):
            best = d
    return best


def _arc_dist(v: float, pieces) -> float:
    best = math.inf
    for a, b in pieces:
        w = b - a
        if w >= 2 * math.pi:
            return 0.0
        d = (v - a) % (2 * math.pi)
        if d <= w:
            return 0.0
        above, below = d - w, 2 * math.pi - d
        d = above if above <= below else -below
        if abs(d) < abs(best):
            best = d
    return best


class _Term:
    __slots__ = ("name", "Q", "pieces", "target", "periodic", "translational")

    def __init__(self, name, Q, pieces, target, periodic, translational):
        self.name, self.Q, self.pieces, self.target = name, Q, pieces, target
        self.periodic, self.translational = periodic, translational


class GoalModel:
    """A :class:`ToleratedPose` compiled into analytic residual rows (one per active constraint)."""

    def __init__(self, goal: ToleratedPose):
        self.goal = goal
        N = np.asarray(goal.nominal, dtype=float)
        self.RnT = np.ascontiguousarray(N[:3, :3].T)
        self.pn = N[:3, 3].copy()
        self.unconstrained = bool(goal.is_unconstrained)
        self.terms: List[_Term] = []
        self.fallback: List = []          # constraints without an analytic row (rpy, euler, quat)
        Rn = N[:3, :3]
        Qs: Dict[str, Optional[np.ndarray]] = {}
        for c in goal.constraints:
            if c.covers_allowed_range():
                continue
            info = PROJECTIONS[c.projection]
            if info.system in ("rpy", "euler", "quat"):
                self.fallback.append(c)
                continue
            if c.frame not in Qs:
                Qs[c.frame] = self._frame_Q(goal, c.frame, Rn)
            pieces = [(float(a), float(b)) for a, b in c.pieces]
            if info.periodic:
                target = []
                for a, b in pieces:
                    m = _SHRINK * (b - a)
                    target.append((a + m, b - m))
            else:
                target = [_shrunk(a, b, info.lo, info.hi) for a, b in pieces]
            self.terms.append(_Term(c.projection, Qs[c.frame], pieces, target, info.periodic,
                                    info.translational))
        self.need_p = any(t.translational for t in self.terms)
        self.need_rv = any((not t.translational) for t in self.terms)
        self.R_anchor_T = None
        if self.fallback:
            T = goal.project_nominal()
            if T is None:
                T = goal.sample(np.random.default_rng(0))
            D = goal.delta(T)
            self.R_anchor_T = np.ascontiguousarray(D[:3, :3].T)
        rows = {"r_sph": 3, "Theta_R": 3, "r_cyl": 2}
        self.n_rows_max = sum(rows.get(t.name, 1) for t in self.terms) + (3 if self.fallback else 0)

    @staticmethod
    def _frame_Q(goal, frame: str, Rn) -> Optional[np.ndarray]:
        if frame == "nominal":
            return None
        Qd = getattr(goal, "_Q", None)
        if isinstance(Qd, dict) and frame in Qd:
            Q = np.asarray(Qd[frame], dtype=float)
        elif frame == "world":
            Q = Rn.copy()
        else:
            Q = np.asarray(goal.frame_resolver(frame), dtype=float)[:3, :3].T @ Rn
        return None if np.allclose(Q, np.eye(3), atol=1e-15) else np.ascontiguousarray(Q)

    # -- per iteration -------------------------------------------------------------------------------------
    def rows(self, R, p, J, E, JJ):
        """Fill residual rows of the current TCP pose (R, p world) and LOCAL Jacobian J (6×n).

        Writes the active rows into E / JJ and returns (k, exact_ok): k rows used; exact_ok is True when
        the model's own evaluation says the pose is inside every analytic constraint (without fallback).
        """
        RnT = self.RnT
        Rd = RnT @ R
        k = 0
        ok = True
        if self.need_p:
            pd = RnT @ (p - self.pn)
            Jp = Rd @ J[:3]            # d p_Δ / dq
        if self.need_rv:
            rv = pin.log3(Rd)
            Jr = pin.Jlog3(Rd) @ J[3:]
        for t in self.terms:
            Q = t.Q
            name = t.name
            if t.translational:
                v3 = pd if Q is None else Q @ pd
                J3 = Jp if Q is None else Q @ Jp
                if name == "x" or name == "y" or name == "z":
                    i = 0 if name == "x" else (1 if name == "y" else 2)
                    v = v3[i]
                    d = _lin_dist(v, t.pieces)
                    if abs(d) > _EPS:
                        ok = False
                    e = _lin_dist(v, t.target)
                    if e != 0.0:
                        E[k] = e
                        JJ[k] = J3[i]
                        k += 1
                elif name == "r_sph":
                    # vector residual p·(1 − c/‖p‖): Gauss–Newton towards the nearest target point
                    # (a scalar ‖p‖ row converges several times slower)
                    r = math.sqrt(pd[0] * pd[0] + pd[1] * pd[1] + pd[2] * pd[2])
                    if abs(_lin_dist(r, t.pieces)) > _EPS:
                        ok = False
                    e = _lin_dist(r, t.target)
                    if e != 0.0:
                        if r > _DEGENERATE:
                            E[k:k + 3] = pd * (e / r)
                        else:
                            E[k:k + 3] = (e, 0.0, 0.0)
                        JJ[k:k + 3] = Jp
                        k += 3
                elif name == "r_cyl":
                    x, y = v3[0], v3[1]
                    rho = math.hypot(x, y)
                    if abs(_lin_dist(rho, t.pieces)) > _EPS:
                        ok = False
                    e = _lin_dist(rho, t.target)
                    if e != 0.0:
                        if rho > _DEGENERATE:
                            E[k] = x * (e / rho)
                            E[k + 1] = y * (e / rho)
                        else:
                            E[k] = e
                            E[k + 1] = 0.0
                        JJ[k:k + 2] = J3[:2]
                        k += 2
                elif name == "phi_cyl" or name == "phi_sph":
                    x, y = v3[0], v3[1]
                    rho = math.hypot(x, y)
                    if rho < _DEGENERATE:
                        continue        # on the axis: every azimuth counts as satisfied
                    phi = math.atan2(y, x)
                    if abs(_arc_dist(phi, t.pieces)) > _EPS:
                        ok = False
                    e = _arc_dist(phi, t.target)
                    if e != 0.0:        # residual in metres: arc length at radius rho
                        E[k] = rho * e
                        JJ[k] = (x * J3[1] - y * J3[0]) / rho
                        k += 1
                else:  # theta
                    x, y, z = v3[0], v3[1], v3[2]
                    rho = math.hypot(x, y)
                    r = math.hypot(rho, z)
                    if r < _DEGENERATE:
                        continue
                    th = math.atan2(rho, z)
                    if abs(_lin_dist(th, t.pieces)) > _EPS:
                        ok = False
                    e = _lin_dist(th, t.target)
                    if e != 0.0:
                        E[k] = r * e
                        if rho > _DEGENERATE:
                            g = np.array([z * x / rho, z * y / rho, -rho]) / r
                        else:
                            g = np.array([1.0, 0.0, 0.0])
                        JJ[k] = g @ J3
                        k += 1
            else:
                if name == "Theta_R":
                    th = math.sqrt(rv[0] * rv[0] + rv[1] * rv[1] + rv[2] * rv[2])
                    if abs(_lin_dist(th, t.pieces)) > _EPS:
                        ok = False
                    e = _lin_dist(th, t.target)
                    if e != 0.0:   # vector residual, as for r_sph
                        if th > _DEGENERATE:
                            E[k:k + 3] = rv * (e / th)
                        else:
                            E[k:k + 3] = (e, 0.0, 0.0)
                        JJ[k:k + 3] = Jr
                        k += 3
                else:
                    i = 0 if name == "N_x" else (1 if name == "N_y" else 2)
                    if Q is None:
                        v = rv[i]
                        row = Jr[i]
                    else:
                        v = Q[i] @ rv
                        row = Q[i] @ Jr
                    if abs(_lin_dist(v, t.pieces)) > _EPS:
                        ok = False
                    e = _lin_dist(v, t.target)
                    if e != 0.0:
                        E[k] = e
                        JJ[k] = row
                        k += 1
        if self.fallback:
            if not self._fallback_ok(R, p):
                Ra = self.R_anchor_T @ Rd
                w = pin.log3(Ra)
                Jf = pin.Jlog3(Ra) @ J[3:]
                E[k:k + 3] = w
                JJ[k:k + 3] = Jf
                k += 3
        return k, ok

    def _fallback_ok(self, R, p) -> bool:
        T = np.eye(4)
        T[:3, :3] = R
        T[:3, 3] = p
        vals = self.goal.values(T)
        for c in self.fallback:
            v = vals[c.key]
            d = _arc_dist(v, c.pieces) if PROJECTIONS[c.projection].periodic else _lin_dist(v, c.pieces)
            if abs(d) > _EPS:
                return False
        return True

    def position_lower_bound(self, point: np.ndarray) -> float:
        """A lower bound on the distance from ``point`` (world) to any valid TCP position (0 if unknown)."""
        pd = self.RnT @ (np.asarray(point, float) - self.pn)
        best = 0.0
        boxes: Dict[int, Dict[str, Tuple[float, float]]] = {}
        for t in self.terms:
            if t.name == "r_sph":
                hi = max(b for _, b in t.pieces)
                best = max(best, float(np.linalg.norm(pd)) - hi)
            elif t.name in ("x", "y", "z"):
                key = id(t.Q) if t.Q is not None else 0
                boxes.setdefault(key, {"Q": t.Q})[t.name] = (min(a for a, _ in t.pieces), max(b for _, b in t.pieces))
        for d in boxes.values():
            if all(n in d for n in "xyz"):
                Q = d["Q"]
                v = pd if Q is None else Q @ pd
                lo = np.array([d[n][0] for n in "xyz"])
                hi = np.array([d[n][1] for n in "xyz"])
                best = max(best, float(np.linalg.norm(v - np.clip(v, lo, hi))))
        return best


def reach_bound(robot) -> Tuple[np.ndarray, float]:
    """(world point o, radius R): every reachable TCP position lies within R of o.

    o is the origin of the first joint on the TCP's chain (fixed in the world); R sums the distances
    between consecutive joint origins on the chain (constant for revolute joints, plus the stroke for
    prismatic ones) and the TCP offset from its joint.
    """
    m = robot.model
    fr = m.frames[robot.tcp_frame]
    chain = []
    j = fr.parentJoint
    while j > 0:
        chain.append(j)
        j = m.parents[j]
    chain.reverse()
    d = robot.model.createData()
    pin.framesForwardKinematics(m, d, pin.neutral(m))
    if not chain:
        return d.oMf[robot.tcp_frame].translation.copy(), 0.0
    o = d.oMi[chain[0]].translation.copy()
    R = 0.0
    for a, b in zip(chain, chain[1:]):
        R += float(np.linalg.norm(m.jointPlacements[b].translation))
    R += float(np.linalg.norm(fr.placement.translation))
    for j in chain:
        idx = m.joints[j].idx_q
        if m.joints[j].shortname().startswith("JointModelP"):  # PX/PY/PZ, PrismaticUnaligned
            lo, hi = m.lowerPositionLimit[idx], m.upperPositionLimit[idx]
            R += max(abs(lo), abs(hi)) if np.isfinite(lo) and np.isfinite(hi) else math.inf
    return o, R


# ---------------------------------------------------------------------------------------------------------
# The solver
# ---------------------------------------------------------------------------------------------------------
def _as_rng(rng) -> np.random.Generator:
    if isinstance(rng, np.random.Generator):
        return rng
    return np.random.default_rng(rng)


def solve_ik(robot, goal: ToleratedPose, rng=None, q_seed=None, max_restarts: int = 300,
             max_iter: int = 60, check_collision: bool = True, n_solutions: int = 1,
             time_limit: Optional[float] = None, distinct_tol: float = DISTINCT_TOL) -> IKResult:
    """Joint configurations whose TCP pose lies inside the tolerated ``goal``.

    ``rng``: a ``np.random.Generator`` or a seed (the result is deterministic for a given seed unless
    ``time_limit`` cuts the search). ``q_seed`` is the start of the first attempt; the others start at
    ``robot.random_configuration(rng)``. ``max_restarts`` counts attempts (including the seeded one).
    With ``check_collision`` a solution must be free of self-collision and of contact with the obstacles
    set on the robot (``robot.in_collision``). Up to ``n_solutions`` solutions are collected that are
    pairwise more than ``distinct_tol`` apart (Euclidean joint distance).
    ``stats``: attempts, iterations, converged, rejected_collision, rejected_duplicate, time, reason
    ("found" | "max_restarts" | "time_limit" | "out_of_reach").
    """
    t0 = time.perf_counter()
    if not isinstance(goal, ToleratedPose):
        raise InputError(f"goal must be a ToleratedPose, got {type(goal).__name__}")
    if n_solutions < 1:
        raise InputError("n_solutions must be at least 1")
    if max_restarts < 1 or max_iter < 1:
        raise InputError("max_restarts and max_iter must be at least 1")
    rng = _as_rng(rng)
    model, data, fid = robot.model, robot.data, robot.tcp_frame
    n = robot.dof
    lo = np.asarray(robot.q_lower, dtype=float)
    hi = np.asarray(robot.q_upper, dtype=float)
    gm = GoalModel(goal)
    stats: Dict[str, object] = {"attempts": 0, "iterations": 0, "converged": 0, "rejected_collision": 0,
                                "rejected_duplicate": 0, "time": 0.0, "reason": "max_restarts"}
    sols: List[np.ndarray] = []
    total_iter = 0

    def finish(reason: str) -> IKResult:
        stats["iterations"] = total_iter
        stats["reason"] = reason
        stats["time"] = time.perf_counter() - t0
        return IKResult(sols, stats)

    if q_seed is not None:
        q_seed = np.asarray(q_seed, dtype=float)
        if q_seed.shape != (n,):
            raise InputError(f"q_seed must have {n} values, got shape {q_seed.shape}")

    if not gm.unconstrained:
        o, R = reach_bound(robot)
        if gm.position_lower_bound(o) > R + 1e-9:
            return finish("out_of_reach")

    E = np.zeros(max(gm.n_rows_max, 1))
    JJ = np.zeros((max(gm.n_rows_max, 1), n))
    valid = goal.valid
    in_collision = robot.in_collision
    cjj, ufp, gfj = pin.computeJointJacobians, pin.updateFramePlacement, pin.getFrameJacobian
    LOCAL = pin.LOCAL
    deadline = None if time_limit is None else t0 + float(time_limit)

    for attempt in range(max_restarts):
        if deadline is not None and attempt > 0 and time.perf_counter() > deadline:
            return finish("time_limit")
        stats["attempts"] = attempt + 1
        if attempt == 0 and q_seed is not None:
            q = np.clip(q_seed, lo, hi)
        else:
            q = robot.random_configuration(rng)
        found = None
        if gm.unconstrained:
            found = q
        else:
            best = math.inf
            since = 0
            for it in range(max_iter):
                cjj(model, data, q)
                M = ufp(model, data, fid)
                J = gfj(model, data, fid, LOCAL)
                k, ok = gm.rows(M.rotation, M.translation, J, E, JJ)
                total_iter += 1
                if ok:
                    T = M.homogeneous
                    if valid(T):
                        found = q
                        break
                if k == 0:
                    break  # inside every target interval but not valid (cannot happen for analytic rows)
                e = E[:k]
                err = float(e @ e)
                if err < best * _STALL_RATIO:
                    best = err
                    since = 0
                else:
                    since += 1
                    if since >= _STALL_WINDOW:
                        break
                Jk = JJ[:k]
                lam = _LAMBDA_FACTOR * err + _LAMBDA_BIAS
                if k <= n:
                    A = Jk @ Jk.T
                    A.flat[::k + 1] += lam
                    dq = Jk.T @ np.linalg.solve(A, e)
                else:
                    A = Jk.T @ Jk
                    A.flat[::n + 1] += lam
                    dq = np.linalg.solve(A, Jk.T @ e)
                s = float(np.max(np.abs(dq)))
                if s > _MAX_STEP:
                    dq *= _MAX_STEP / s
                q = q - dq
                np.minimum(q, hi, out=q)
                np.maximum(q, lo, out=q)
        if found is None:
            continue
        stats["converged"] += 1
        if check_collision and in_collision(found):
            stats["rejected_collision"] += 1
            continue
        if any(float(np.linalg.norm(found - s)) <= distinct_tol for s in sols):
            stats["rejected_duplicate"] += 1
            continue
        sols.append(found.copy())
        if len(sols) >= n_solutions:
            return finish("found")
    return finish("max_restarts")
