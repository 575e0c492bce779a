"""Numerical inverse kinematics onto a *tolerated* pose.

:func:`solve_ik` runs Levenberg–Marquardt (damped least squares) from seeded random restarts and
returns distinct, collision-free joint configurations whose TCP pose satisfies ``goal.valid`` (up to
``n_solutions``).

How the tolerance is used (robodesign's decisions; projections as in :mod:`robodesign.formats.tolerance`):

* The error is computed from ``Δ = nominal⁻¹·T = (p, R)`` with the decoupled pair (p, log3 R) rather
  than ``log6(Δ)``: the tolerance projections are defined on exactly these quantities (x, y, z = p_i;
  r_sph = ‖p‖; N_x, N_y, N_z = log3(R)_i; Theta_R = ‖log3 R‖; …), so each constraint maps to its own rows
  and its exact residual. The Jacobian is ``blockdiag(R_Δ, Jlog3(R_Δ)) · J_LOCAL``.
* One residual block per *active* constraint: ``x/y/z/N_*`` → 1 row; ``r_sph``/``Theta_R`` → 3 rows
  (the vector p·(1 − c/‖p‖): a scalar ‖p‖ row converged ~5× slower); ``r_cyl`` → 2 rows;
  ``phi_cyl``/``phi_sph``/``theta`` → 1 row (the angle times its lever arm, in metres). Frames other than
  ``nominal`` rotate p and log3(R) by the constant Q of the frame. A direction that no constraint bounds
  (e.g. the yaw about the tool z when only N_x/N_y are given) has no row at all: the per-axis weight 0,
  derived from the tolerance; a fully bounded pose gets the full 6-D error.
* Each row is a *dead-zone* residual: the value minus its clamp into a target interval = the tolerance
  interval shrunk by a quarter of its width on every side that is not at the projection's natural limit
  (r ≥ 0, θ ≥ 0; a one-sided infinite interval by 1e-4). Inside the target a row is zero (a zero row
  does not change the LM step). For a tolerance centred on the nominal this converges towards the
  nominal; when the nominal lies outside the tolerance (the format allows it) it still lands inside.
* A solution is accepted as soon as ``goal.valid(fk(q))``; ``valid`` is only called once the model's own
  exact check of the analytic constraints passes (tested to agree with ``valid``). Projections without an
  analytic row (R/P/Y, Euler angles, quaternions) fall back to a full rotation error towards a fixed valid
  orientation (``goal.project_nominal()``), active while any of them is violated.
* A goal that provably no configuration reaches fails at once, before any restart (:class:`ChainBounds`):
  its position set farther from the first joint than an upper bound of the arm's reach (distances between
  consecutive joint origins + prismatic strokes + TCP offset), or farther than the rest of that bound from
  the circle the second joint's origin describes about a revolute first joint (``reason="out_of_reach"``);
  or, when the goal bounds the orientation (``Theta_R`` or N_x/N_y/N_z), the last joint's origin, which then
  lies within ``r + 2·sin(θ/2)·|c|`` of ``p_nominal − R_nominal·c`` (c: that origin seen from the TCP),
  farther from that circle than the chain between them reaches (``"out_of_orientation_reach"``). Only
  ``r_sph``, complete x/y/z boxes, ``Theta_R`` and complete N_x/N_y/N_z boxes are used; joint limits and
  collisions are ignored, so the bounds never reject a reachable goal (tests/test_ik_bounds.py).

Inner loop: damping ``λ = 0.02·‖e‖² + 1e-6`` (Sugihara's LM: damped far from the goal, Gauss–Newton close
to it), the step capped at 1 (Euclidean, rad), clamping to the joint limits. An attempt ends on acceptance,
after ``max_iter`` iterations or when the squared error has not dropped below 0.9× its best for 3
iterations (tuned on PTP_3: fewest iterations per success). The compiled goal model and the reach bound are
cached per goal / robot (weak references). The starts of all attempts are drawn at once (uniform within
the joint limits, ±π where a limit is infinite).

Two implementations of the loop do the same arithmetic: the compiled one of :mod:`.ik_kernel` (numba,
about 1 µs per iteration; it runs the descents of consecutive attempts in one call until one lands in the
goal) for robots whose TCP chain has revolute/prismatic joints about ±z (every robodesign robot) and goals
whose constraints have one interval each among x/y/z/N_x/N_y/N_z/r_sph/Theta_R/r_cyl; and the Python one
(about 15 µs per iteration: ``pin.computeJointJacobians`` + ``updateFramePlacement`` +
``getFrameJacobian(LOCAL)``) for everything else, for ``ROBODESIGN_JIT=0``, under the ``_trace`` hook and
while the kernels are still being compiled in the background on a cold cache (``ik_kernel.ready``).
Same seed, same solutions (tests/test_ik_kernel.py).

Collision repair: once more than 2 converged configurations were rejected for collision (collisions are
then the bottleneck, e.g. a branch whose collision-free part is a sliver of the tolerated set), each
further colliding solution gets 4 re-solves from Gaussian perturbations (σ = 0.05 rad) of at most 10
iterations, which explore the valid set around that IK branch before the next random restart. On the
hardest PTP_3 pair found (a collision-free solution 5e-5 m from a self-collision) this raised the
success within 300 restarts from 55 % to 85 %; it does not change the common case.
"""
from __future__ import annotations

import math
import time
import weakref
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Optional, Tuple, cast

import numpy as np
import pinocchio as pin

from robodesign.core.errors import InputError
from robodesign.formats.tolerance import PROJECTIONS, ToleratedPose
from robodesign.solvers.ik_accept import Acceptance
from robodesign.solvers.ik_bounds import _BOUNDS_CACHE as _BOUNDS_CACHE  # (the bounds' names, kept here too)
from robodesign.solvers.ik_bounds import _REVOLUTE_AXES as _REVOLUTE_AXES
from robodesign.solvers.ik_bounds import ChainBounds, chain_bounds
from robodesign.solvers.ik_bounds import _circle_distance as _circle_distance
from robodesign.solvers.ik_proof import valid_provable
from robodesign.solvers.lazy_rng import LazyGenerator

__all__ = ["IKResult", "solve_ik", "goal_model", "GoalModel", "DISTINCT_TOL", "ChainBounds", "chain_bounds",
           "provably_unreachable"]

DISTINCT_TOL = 0.1          # rad: solutions closer than this (Euclidean, joint space) count as one
_SHRINK = 0.25              # dead-zone: shrink each bounded side by this fraction of the interval width
_OPEN_MARGIN = 1e-4         # dead-zone margin on a one-sided infinite interval (m or rad)
_EPS = 1e-12                # the tolerance's own comparison slack
_LAMBDA_FACTOR = 0.02         # LM damping λ = factor·‖e‖² + bias (Sugihara 2011)
_LAMBDA_BIAS = 1e-6
_MAX_STEP = 1.0             # rad (or m for prismatic joints), Euclidean norm of one LM step
_STALL_WINDOW = 3
_STALL_RATIO = 0.9
_DEGENERATE = 1e-12
_REPAIR_AFTER = 2           # collision repair starts after this many collision-rejected solutions …
_REPAIR_TRIES = 4           # … with this many perturbed re-solves per rejected solution,
_REPAIR_SIGMA = 0.05        # rad, std. dev. of the perturbation,
_REPAIR_ITER = 10           # LM iterations per re-solve


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


def _single(pieces):
    """(a, b) if ``pieces`` is one interval, else None."""
    return pieces[0] if len(pieces) == 1 else None


def _make_term(name: str, Q: Optional[np.ndarray], pieces, target, periodic: bool):
    """A factory ``bind(Es, Js) -> f(P, R, Jp, Jr) -> ok`` for one active constraint.

    The term owns fixed rows of the residual: ``Es``/``Js`` are views of them in the solver's buffers.
    ``f`` writes the dead-zone residual (value minus its clamp into ``target``) and its Jacobian there,
    or zeros when the value is inside the target (a zero row with a zero residual does not change the
    LM step, so inactive rows need no bookkeeping). ``P = (p list, p array)`` and ``R = (log3 list, log3
    array)`` describe Δ in nominal axes; ``Jp``/``Jr`` are their Jacobians. ``ok`` is the exact check of
    the tolerance interval (slack 1e-12). Scalars are handled as Python floats: a numpy call on a
    3-vector costs about 1 µs.
    """
    one, tone = _single(pieces), _single(target)
    if one is not None and tone is not None and not periodic:
        a, b = one
        ta, tb = tone
        a -= _EPS
        b += _EPS

        def inside(v):
            return a <= v <= b

        def dz(v):
            return v - tb if v > tb else (v - ta if v < ta else 0.0)
    else:
        dist = _arc_dist if periodic else _lin_dist

        def inside(v):
            return abs(dist(v, pieces)) <= _EPS

        def dz(v):
            return dist(v, target)

    if name in ("x", "y", "z", "N_x", "N_y", "N_z"):
        i = {"x": 0, "y": 1, "z": 2, "N_x": 0, "N_y": 1, "N_z": 2}[name]
        rot = name.startswith("N")
        row_q = None if Q is None else np.ascontiguousarray(Q[i])

        def bind(Es, Js):
            Jrow = Js[0]
            state = [True]          # rows currently zero?

            def f(P, R, Jp, Jr):
                X = R if rot else P
                v = X[0][i] if row_q is None else float(row_q.dot(X[1]))
                e = dz(v)
                if e != 0.0:
                    Jx = Jr if rot else Jp
                    Es[0] = e
                    Jrow[:] = Jx[i] if row_q is None else row_q.dot(Jx)
                    state[0] = False
                elif not state[0]:
                    Es[0] = 0.0
                    Jrow[:] = 0.0
                    state[0] = True
                return inside(v)
            return f
        return bind, 1

    if name in ("r_sph", "Theta_R"):
        rot = name == "Theta_R"   # both are frame-invariant

        def bind(Es, Js):
            state = [True]

            def f(P, R, Jp, Jr):
                # vector residual x·(1 − c/‖x‖): Gauss–Newton towards the nearest target point
                # (a scalar ‖x‖ row converges several times slower)
                X = R if rot else P
                x0, x1, x2 = X[0]
                r = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
                e = dz(r)
                if e != 0.0:
                    if r > _DEGENERATE:
                        np.multiply(X[1], e / r, out=Es)
                    else:
                        Es[:] = (e, 0.0, 0.0)
                    np.copyto(Js, Jr if rot else Jp)
                    state[0] = False
                elif not state[0]:
                    Es[:] = 0.0
                    Js[:] = 0.0
                    state[0] = True
                return inside(r)
            return f
        return bind, 3

    if name == "r_cyl":
        Q2 = None if Q is None else np.ascontiguousarray(Q[:2])

        def bind(Es, Js):
            state = [True]

            def f(P, R, Jp, Jr):
                x, y = P[0][:2] if Q2 is None else Q2.dot(P[1]).tolist()
                rho = math.sqrt(x * x + y * y)
                e = dz(rho)
                if e != 0.0:
                    if rho > _DEGENERATE:
                        Es[0] = x * (e / rho)
                        Es[1] = y * (e / rho)
                    else:
                        Es[0] = e
                        Es[1] = 0.0
                    np.copyto(Js, Jp[:2] if Q2 is None else Q2.dot(Jp))
                    state[0] = False
                elif not state[0]:
                    Es[:] = 0.0
                    Js[:] = 0.0
                    state[0] = True
                return inside(rho)
            return f
        return bind, 2

    if name in ("phi_cyl", "phi_sph", "theta"):
        azimuth = name != "theta"

        def bind(Es, Js):
            Jrow = Js[0]

            def f(P, R, Jp, Jr):
                x, y, z = P[0] if Q is None else Q.dot(P[1]).tolist()
                rho = math.sqrt(x * x + y * y)
                if azimuth:
                    if rho < _DEGENERATE:     # on the axis every azimuth counts as satisfied
                        Es[0] = 0.0
                        Jrow[:] = 0.0
                        return True
                    v = math.atan2(y, x)
                    e = dz(v)
                    if e != 0.0:              # residual in metres: arc length at radius rho
                        J3 = Jp if Q is None else Q.dot(Jp)
                        Es[0] = rho * e
                        Jrow[:] = (x * J3[1] - y * J3[0]) / rho
                    else:
                        Es[0] = 0.0
                        Jrow[:] = 0.0
                    return inside(v)
                r = math.sqrt(rho * rho + z * z)
                if r < _DEGENERATE:           # the polar angle of the origin counts as satisfied
                    Es[0] = 0.0
                    Jrow[:] = 0.0
                    return True
                v = math.atan2(rho, z)
                e = dz(v)
                if e != 0.0:                  # residual in metres: arc length at radius r
                    J3 = Jp if Q is None else Q.dot(Jp)
                    g = [z * x / (rho * r), z * y / (rho * r), -rho / r] if rho > _DEGENERATE else [1.0, 0.0, 0.0]
                    Es[0] = r * e
                    Jrow[:] = np.dot(g, J3)
                else:
                    Es[0] = 0.0
                    Jrow[:] = 0.0
                return inside(v)
            return f
        return bind, 1
    raise AssertionError(name)


class GoalModel:
    """A :class:`ToleratedPose` compiled into analytic residual rows (one term per active constraint)."""

    def __init__(self, goal: ToleratedPose):
        self.goal = goal
        N = np.asarray(goal.nominal, dtype=float)
        self.N_inv = np.ascontiguousarray(np.linalg.inv(N))
        self.unconstrained = bool(goal.is_unconstrained)
        self.factories: List[Tuple[Callable, int]] = []
        self.names: List[str] = []
        self.fallback: List = []          # constraints without an analytic row (rpy, euler, quat)
        self.boxes: Dict[str, Dict[str, Tuple[float, float]]] = {}
        self.sphere_hi = math.inf
        self.theta_hi = math.inf           # upper bound of Theta_R (rad)
        self.rot_boxes: Dict[str, Dict[str, Tuple[float, float]]] = {}   # N_x/N_y/N_z per frame
        self.term_specs: List[tuple] = []  # (projection, Q, pieces, target, periodic): the compiled kernel's input
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
                target = [(a + _SHRINK * (b - a), b - _SHRINK * (b - a)) for a, b in pieces]
            else:
                target = [_shrunk(a, b, info.lo, info.hi) for a, b in pieces]
            self.factories.append(_make_term(c.projection, Qs[c.frame], pieces, target, info.periodic))
            self.term_specs.append((c.projection, Qs[c.frame], pieces, target, info.periodic))
            self.names.append(c.projection)
            if c.projection == "r_sph":
                self.sphere_hi = min(self.sphere_hi, max(b for _, b in pieces))
            elif c.projection in ("x", "y", "z"):
                d = self.boxes.setdefault(c.frame, {})
                d[c.projection] = (min(a for a, _ in pieces), max(b for _, b in pieces))
            elif c.projection == "Theta_R":
                self.theta_hi = min(self.theta_hi, max(b for _, b in pieces))
            elif c.projection in ("N_x", "N_y", "N_z"):
                d = self.rot_boxes.setdefault(c.frame, {})
                d[c.projection[-1]] = (min(a for a, _ in pieces), max(b for _, b in pieces))
        self._Qs = Qs
        # (frame's Q or None, lower corner, upper corner) of every complete x/y/z box: position_lower_bound's
        self._position_boxes = [(Qs.get(frame), np.array([d[n][0] for n in "xyz"]), np.array([d[n][1] for n in "xyz"]))
                                for frame, d in self.boxes.items() if all(n in d for n in "xyz")]
        self.need_p = any(nm in ("x", "y", "z", "r_sph", "r_cyl", "phi_cyl", "phi_sph", "theta")
                          for nm in self.names)
        self.need_rv = any(nm in ("N_x", "N_y", "N_z", "Theta_R") for nm in self.names)
        self.R_anchor_T = None
        if self.fallback:
            T = goal.project_nominal()
            if T is None:
                T = goal.sample(np.random.default_rng(0))
            self.R_anchor_T = np.ascontiguousarray(goal.delta(T)[:3, :3].T)
        self.n_rows = sum(k for _, k in self.factories) + (3 if self.fallback else 0)
        self._program = None          # the goal as compiled-kernel arrays (built on first use)

    def program(self):
        """``(tkind, tvec)`` for :mod:`.ik_kernel`, or None when a constraint has no kernel row."""
        if self._program is None:
            prog = None
            if not self.fallback and not self.unconstrained:
                from robodesign.solvers import ik_kernel
                prog = ik_kernel.compile_goal(self.term_specs, valid_provable(self.goal, self.N_inv))
            self._program = prog if prog is not None else False
        return self._program or None

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

    def evaluator(self, n: int):
        """``(f, E, JJ)``: ``ok = f(T, J)`` fills the residual ``E`` (n_rows) and its Jacobian ``JJ``
        (n_rows × n) for the TCP pose ``T`` (4×4 world) and LOCAL frame Jacobian ``J`` (6×n); ``ok`` is
        True when every analytic constraint holds exactly (fallback constraints are left to ``valid``).
        Each call of :meth:`evaluator` owns fresh buffers (safe for concurrent solves).
        """
        m = max(self.n_rows, 1)
        E = np.zeros(m)
        JJ = np.zeros((m, n))
        if not self.fallback and sorted(self.names) == ["Theta_R", "r_sph"]:
            fast = self._ball_pair_evaluator(E, JJ)
            if fast is not None:
                return fast, E, JJ
        terms = []
        k = 0
        for bind, rows in self.factories:
            terms.append(bind(E[k:k + rows], JJ[k:k + rows]))
            k += rows
        Ninv = self.N_inv
        need_p, need_rv = self.need_p, self.need_rv
        B = np.zeros((6, 6))            # blockdiag(R_Δ, Jlog3(R_Δ))
        Bp, Br = B[:3, :3], B[3:, 3:]
        JB = np.zeros((6, n))
        Jp, Jr = JB[:3], JB[3:]
        log3, Jlog3, dot, copyto = pin.log3, pin.Jlog3, np.dot, np.copyto
        fallback = self._fallback_rows(E[k:k + 3], JJ[k:k + 3]) if self.fallback else None

        def f(T, J):
            D = Ninv.dot(T)
            Rd = D[:3, :3]
            P = Rv = None
            if need_p:
                pd = D[:3, 3]
                P = (pd.tolist(), pd)
                copyto(Bp, Rd)
            if need_rv:
                rv = log3(Rd)
                Rv = (rv.tolist(), rv)
                copyto(Br, Jlog3(Rd))
            dot(B, J, out=JB)           # [d p_Δ/dq ; d log3(R_Δ)/dq]  (J is LOCAL: v_world = R v_local)
            ok = True
            for t in terms:
                if not t(P, Rv, Jp, Jr):
                    ok = False
            if fallback is not None:
                fallback(T, Rd, J)
            return ok
        return f, E, JJ

    def _ball_pair_evaluator(self, E: np.ndarray, JJ: np.ndarray):
        """Fast path for the common ``r_sph`` + ``Theta_R`` goal: the rows are [p_Δ·s_p; log3(R_Δ)·s_r]
        and their Jacobian is blockdiag(R_Δ, Jlog3(R_Δ))·J, written straight into ``JJ``."""
        p_first = self.names[0] == "r_sph"
        ip, ir = (0, 3) if p_first else (3, 0)
        specs = []
        for name in ("r_sph", "Theta_R"):
            c = next(c for c in self.goal.constraints if c.projection == name and not c.covers_allowed_range())
            info = PROJECTIONS[name]
            pieces = [(float(a), float(b)) for a, b in c.pieces]
            target = [_shrunk(a, b, info.lo, info.hi) for a, b in pieces]
            specs.append((pieces, target))
        (pp, pt), (rp, rt) = specs
        if len(pp) != 1 or len(rp) != 1:
            return None
        pa, pb_ = pp[0][0] - _EPS, pp[0][1] + _EPS
        pta, ptb = pt[0]
        ra, rb = rp[0][0] - _EPS, rp[0][1] + _EPS
        rta, rtb = rt[0]
        Ninv = self.N_inv
        B = np.zeros((6, 6))
        Bp, Br = B[ip:ip + 3, :3], B[ir:ir + 3, 3:]
        Ep, Er = E[ip:ip + 3], E[ir:ir + 3]
        Jp_rows, Jr_rows = JJ[ip:ip + 3], JJ[ir:ir + 3]
        log3, Jlog3, dot, copyto, multiply = pin.log3, pin.Jlog3, np.dot, np.copyto, np.multiply
        sqrt = math.sqrt

        def f(T, J):
            D = Ninv.dot(T)
            Rd = D[:3, :3]
            pd = D[:3, 3]
            rv = log3(Rd)
            x0, x1, x2 = pd.tolist()
            y0, y1, y2 = rv.tolist()
            r = sqrt(x0 * x0 + x1 * x1 + x2 * x2)
            th = sqrt(y0 * y0 + y1 * y1 + y2 * y2)
            ep = r - ptb if r > ptb else (r - pta if r < pta else 0.0)
            er = th - rtb if th > rtb else (th - rta if th < rta else 0.0)
            if ep != 0.0 or er != 0.0:
                copyto(Bp, Rd)
                copyto(Br, Jlog3(Rd))
                dot(B, J, out=JJ)
                if ep == 0.0:
                    Ep[:] = 0.0
                    Jp_rows[:] = 0.0
                elif r > _DEGENERATE:
                    multiply(pd, ep / r, out=Ep)
                else:
                    Ep[:] = (ep, 0.0, 0.0)
                if er == 0.0:
                    Er[:] = 0.0
                    Jr_rows[:] = 0.0
                elif th > _DEGENERATE:
                    multiply(rv, er / th, out=Er)
                else:
                    Er[:] = (er, 0.0, 0.0)
            else:
                E[:] = 0.0
            return pa <= r <= pb_ and ra <= th <= rb
        return f

    def _fallback_rows(self, Es, Js):
        """Rows for rpy/euler/quat constraints: full rotation error towards a fixed valid orientation,
        active while any of them is violated."""
        RaT = self.R_anchor_T
        goal = self.goal

        def f(T, Rd, J):
            vals = goal.values(T)
            bad = False
            for c in self.fallback:
                v = vals[c.key]
                d = _arc_dist(v, c.pieces) if PROJECTIONS[c.projection].periodic else _lin_dist(v, c.pieces)
                if abs(d) > _EPS:
                    bad = True
                    break
            if bad:
                Ra = RaT.dot(Rd)
                Es[:] = pin.log3(Ra)
                Js[:] = pin.Jlog3(Ra).dot(J[3:])
            else:
                Es[:] = 0.0
                Js[:] = 0.0
        return f

    def position_radius(self) -> float:
        """An upper bound on ‖p − p_nominal‖ over every valid TCP position p (inf if unbounded): from
        ``r_sph`` and complete x/y/z boxes (their farthest corner)."""
        r = self.sphere_hi
        for d in self.boxes.values():
            if all(n in d for n in "xyz"):
                r = min(r, math.sqrt(sum(max(abs(d[n][0]), abs(d[n][1])) ** 2 for n in "xyz")))
        return max(r, 0.0)

    def rotation_radius(self) -> float:
        """An upper bound on the angle between a valid TCP orientation and the nominal one (inf if
        unbounded): from ``Theta_R`` and complete N_x/N_y/N_z boxes (‖log3(R_Δ)‖ ≤ the farthest corner)."""
        r = self.theta_hi
        for d in self.rot_boxes.values():
            if all(n in d for n in "xyz"):
                r = min(r, math.sqrt(sum(max(abs(d[n][0]), abs(d[n][1])) ** 2 for n in "xyz")))
        return max(r, 0.0)

    def rotation_slack(self, c: np.ndarray) -> float:
        """An upper bound on |R_Δ·c − c| over every valid orientation R_Δ = R_nominalᵀ·R (c in TCP axes; inf if
        unbounded): 2·sin(θ/2)·|c| from :meth:`rotation_radius`, and, for N_* rows bounding two components of
        the rotation vector ω in a frame (the third free, e.g. a tool axis within ±0.1 rad and any turn about
        it), |c_a|·|ω_⊥| + 2·|c_⊥| with a the free axis (|R·e_a − e_a| = 2·sin(φ/2)·|n_⊥| ≤ |ω_⊥|)."""
        c = np.asarray(c, dtype=float)
        nc = float(np.linalg.norm(c))
        best = 2.0 * math.sin(min(self.rotation_radius(), math.pi) / 2.0) * nc \
            if math.isfinite(self.rotation_radius()) else math.inf
        for frame, d in self.rot_boxes.items():
            Q = self._Qs.get(frame)
            cf = c if Q is None else Q @ c
            for a, axis in enumerate("xyz"):
                others = [n for n in "xyz" if n != axis]
                if not all(n in d for n in others):
                    continue
                w = math.sqrt(sum(max(abs(d[n][0]), abs(d[n][1])) ** 2 for n in others))
                c_perp = math.sqrt(max(nc * nc - cf[a] * cf[a], 0.0))
                best = min(best, abs(float(cf[a])) * min(w, 2.0) + 2.0 * c_perp)
        return best

    def position_lower_bound(self, point: np.ndarray) -> float:
        """A lower bound on the distance from ``point`` (world) to any valid TCP position (0 if unknown)."""
        pd = self.N_inv[:3, :3].dot(np.asarray(point, float)) + self.N_inv[:3, 3]
        best = 0.0
        if math.isfinite(self.sphere_hi):
            best = float(np.linalg.norm(pd)) - self.sphere_hi
        for Q, lo, hi in self._position_boxes:
            v = pd if Q is None else Q @ pd
            best = max(best, float(np.linalg.norm(v - np.clip(v, lo, hi))))
        return best


_GOAL_CACHE: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


# ---------------------------------------------------------------------------------------------------------
# Provable reachability bounds (decided before any restart; the bounds themselves: .ik_bounds)
# ---------------------------------------------------------------------------------------------------------
def provably_unreachable(robot, goal: ToleratedPose) -> str:
    """'' or the reason ("out_of_reach", "out_of_orientation_reach") why no configuration of ``robot`` puts
    its TCP into ``goal``: the bounds of :class:`ChainBounds`, which hold for every q (joint limits and
    collisions ignored), so a goal they reject is unreachable, and :func:`solve_ik` returns at once."""
    return chain_bounds(robot).unreachable(goal_model(goal))


#: a goal "fixes the full pose" when its position is bounded within this half-width [m] in x, y and z (or this
#: radius) and its orientation within this angle [rad] (Theta_R, or N_x, N_y and N_z in one frame)
FULL_POSE_POSITION = 0.01
FULL_POSE_ANGLE = math.radians(2.0)


def fixes_full_pose(goal: ToleratedPose) -> bool:
    """Whether ``goal`` bounds all six pose directions tightly (:data:`FULL_POSE_POSITION`,
    :data:`FULL_POSE_ANGLE`; the published Whitman2020, BPO24 and Liu2020 goals: ±1 mm, 0.5°). An arm whose
    :meth:`~robodesign.model.robot.Robot.generic_rank` is below 6 reaches only a lower-dimensional set of poses,
    which passes through such a small tolerance set only by coincidence: the IK stage does not search for it."""
    gm = goal_model(goal)
    box = 2 * FULL_POSE_POSITION
    pos = gm.sphere_hi <= FULL_POSE_POSITION or any(
        all(k in b and b[k][1] - b[k][0] <= box for k in "xyz") for b in gm.boxes.values())
    ang = 2 * FULL_POSE_ANGLE
    ori = gm.theta_hi <= FULL_POSE_ANGLE or any(
        len(b) == 3 and all(hi - lo <= ang for lo, hi in b.values()) for b in gm.rot_boxes.values())
    return bool(pos and ori)


def goal_model(goal: ToleratedPose) -> GoalModel:
    """The compiled :class:`GoalModel` of a goal (cached per goal object)."""
    gm = _GOAL_CACHE.get(goal)
    if gm is None:
        gm = GoalModel(goal)
        try:
            _GOAL_CACHE[goal] = gm
        except TypeError:
            pass
    return gm


try:  # the gufunc behind np.linalg.solve without its ~4 µs of Python-level checks
    from numpy.linalg import _umath_linalg as _ul

    def _solve(A, b):
        return _ul.solve1(A, b, signature="dd->d")
    _solve(np.eye(2), np.ones(2))
except Exception:  # pragma: no cover - other numpy layouts
    _solve = np.linalg.solve

try:  # the ufunc np.clip ends in (numpy._core._methods._clip), without its ~3 µs of Python-level dispatch
    from numpy._core.umath import clip as _clip  # type: ignore[attr-defined]
except ImportError:  # pragma: no cover - other numpy layouts
    _clip = np.clip


# ---------------------------------------------------------------------------------------------------------
# The solver
# ---------------------------------------------------------------------------------------------------------
class _Kernel:
    """The compiled LM descent (:mod:`.ik_kernel`) bound to one robot, goal and buffers."""

    def __init__(self, ck, prog, n, lo, hi, valid, max_iter, kmod, Ninv):
        tkind, tvec = prog
        m = kmod.rows_of(tkind)
        self.E, self.JJ, self.T = np.zeros(m), np.zeros((m, n)), np.zeros((4, 4))
        self.q = np.zeros(n)
        self.params = np.array([_LAMBDA_FACTOR, _LAMBDA_BIAS, _MAX_STEP, _STALL_RATIO, _STALL_WINDOW], dtype=float)
        self.lo = np.ascontiguousarray(lo, dtype=float)
        self.hi = np.ascontiguousarray(hi, dtype=float)
        self.valid, self.max_iter = valid, int(max_iter)
        self._repair, self._batch = kmod.lm_repair, kmod.lm_batch
        # the kernels' arguments after the start(s), in their order, put together once
        tail = (ck.chain, ck.kind, ck.sign, ck.iq, ck.tcp, Ninv, tkind, tvec, self.E, self.JJ, self.T, self.params)
        self._descend_args = (self.lo, self.hi) + tail
        self._batch_args = (self.max_iter, self.lo, self.hi) + tail + (self.q,)

    def repair(self, found: np.ndarray, noise: np.ndarray, iters: int):
        """(q or None, iterations) of one descent from ``clip(found + noise, lo, hi)`` (numpy's, made in the kernel);
        ``valid`` stays the judge of the result (asked unless the kernel proves it true)."""
        q = np.empty(len(found))
        status, its = self._repair(found, noise, iters, *self._descend_args, q)
        return (q if status == 2 or (status == 1 and self.valid(self.T)) else None), its

    def batch(self, starts: np.ndarray, a: int, stop: int):
        """(index, q or None, iterations): descents from starts[a:stop] until one lands in the goal."""
        idx, its, proven = self._batch(starts, a, stop, *self._batch_args)
        if idx < stop and (proven or self.valid(self.T)):
            return idx, self.q.copy(), its
        return idx, None, its


def _kernel_descend(robot, gm: GoalModel, n: int, lo: np.ndarray, hi: np.ndarray, valid, max_iter: int):
    """The compiled descent for this robot and goal (:class:`_Kernel`), or None when :mod:`.ik_kernel`
    does not cover them (the Python loop then runs)."""
    if gm.unconstrained:
        return None
    from robodesign.solvers import ik_kernel
    if not ik_kernel.ready():   # not compiled yet: the Python loop runs meanwhile (no cold-start stall)
        return None
    prog = gm.program()
    if prog is None:
        return None
    ck = ik_kernel.chain_kernel(robot)
    if ck is None:
        return None
    return _Kernel(ck, prog, n, lo, hi, valid, max_iter, ik_kernel, gm.N_inv)


def _as_rng(rng) -> np.random.Generator:
    if isinstance(rng, np.random.Generator):
        return rng
    return rng.generator if isinstance(rng, LazyGenerator) else np.random.default_rng(rng)


_trace: Optional[list] = None   # development hook: a list receives (converged, iterations, [err²…]) per attempt


def solve_ik(robot, goal: ToleratedPose, rng=None, q_seed=None, max_restarts: int = 300,
             max_iter: int = 40, check_collision: bool = True, n_solutions: int = 1,
             time_limit: Optional[float] = None, distinct_tol: float = DISTINCT_TOL,
             reach_bounds: bool = True, canonical: bool = True, saturate: int = 0,
             max_step: Optional[np.ndarray] = None) -> IKResult:
    """Joint configurations whose TCP pose lies inside the tolerated ``goal``.

    ``rng``: a ``np.random.Generator`` or a seed (the result is deterministic for a given seed unless
    ``time_limit`` cuts the search). ``q_seed`` is the start of the first attempt; the others start at
    ``robot.random_configuration(rng)``. ``max_restarts`` counts attempts (including the seeded one);
    ``max_iter`` bounds the LM iterations of one attempt. With ``check_collision`` a solution must be
    free of self-collision and of contact with the obstacles set on the robot (``robot.in_collision``).
    With ``reach_bounds`` (default) a goal that :class:`ChainBounds` proves out of reach fails at once
    (no restart; reason "out_of_reach" or "out_of_orientation_reach"); False runs the restarts anyway.
    Up to ``n_solutions`` solutions are collected that are pairwise more than ``distinct_tol`` apart
    (Euclidean joint distance). With ``canonical`` (default) each solution's revolute joints are turned by
    whole turns to the sheet nearest ``q_seed`` (else nearest 0; :meth:`Robot.nearest_equivalent`), so the
    solutions of one goal and of consecutive goals lie in one piece of free space.
    With ``saturate`` > 0 the collecting stops (reason "saturated") once that many converged attempts since the
    last new solution were duplicates of the solutions found (collision and limit rejections do not count):
    the goal's solutions have stopped growing. The solutions are then the first ones the full search finds.
    With ``max_step`` (rad or m per joint, or one number for all) a solution must lie within that of ``q_seed`` in
    every joint (a path's next pose, reached in a given time: :meth:`GoalPlanner.follow_chain
    <robodesign.design.goal_planner.GoalPlanner.follow_chain>`); farther ones count as rejected_far.
    ``time_limit`` (s) stops the search after the current attempt.
    ``stats``: attempts, iterations, converged, rejected_limits, rejected_collision, rejected_duplicate,
    (rejected_far,) time, reason ("found" | "saturated" | "max_restarts" | "time_limit" | "out_of_reach" |
    "out_of_orientation_reach").
    """
    if n_solutions < 1:
        raise InputError("n_solutions must be at least 1")
    return IKSearch(robot, goal, rng, q_seed=q_seed, max_restarts=max_restarts, max_iter=max_iter,
                    check_collision=check_collision, time_limit=time_limit, distinct_tol=distinct_tol,
                    reach_bounds=reach_bounds, canonical=canonical, saturate=saturate,
                    max_step=max_step).run(n_solutions)


class IKSearch:
    """:func:`solve_ik` as a search that can stop and go on: ``run(n)`` collects solutions until there are ``n``
    (reason "found") or the search ends, and a later ``run(m)`` goes on from where it stopped. The attempts,
    random draws and solutions are those of one ``solve_ik(..., n_solutions=m)`` call, so a caller can first
    ask every goal for one solution (is each reachable?) and collect the rest afterwards, at no extra cost
    (:meth:`robodesign.design.goal_planner.GoalPlanner.solve_ik`). ``solutions``: the distinct solutions so
    far (first = first found); ``finished``: the search has ended (``stats["reason"]`` says why)."""

    def __init__(self, robot, goal: ToleratedPose, rng=None, q_seed=None, max_restarts: int = 300,
                 max_iter: int = 40, check_collision: bool = True, time_limit: Optional[float] = None,
                 distinct_tol: float = DISTINCT_TOL, reach_bounds: bool = True, canonical: bool = True,
                 saturate: int = 0, max_step: Optional[np.ndarray] = None) -> None:
        if not isinstance(goal, ToleratedPose):
            raise InputError(f"goal must be a ToleratedPose, got {type(goal).__name__}")
        if max_restarts < 1 or max_iter < 1:
            raise InputError("max_restarts and max_iter must be at least 1")
        if saturate < 0:
            raise InputError(f"saturate must be 0 (off) or more, got {saturate}")
        if q_seed is not None:
            q_seed = np.asarray(q_seed, dtype=float)
            if q_seed.shape != (robot.dof,):
                raise InputError(f"q_seed must have {robot.dof} values, got shape {q_seed.shape}")
        if max_step is not None:
            max_step = np.broadcast_to(np.asarray(max_step, dtype=float), (robot.dof,))
            if q_seed is None:
                raise InputError("max_step needs q_seed (the configuration a solution must lie near)")
        self.solutions: List[np.ndarray] = []
        self.stats: Dict[str, Any] = {"attempts": 0, "iterations": 0, "converged": 0, "rejected_limits": 0,
                                      "rejected_collision": 0, "rejected_duplicate": 0, "repairs": 0,
                                      "time": 0.0, "reason": "max_restarts"}
        self.finished = False
        self._steps = _search(robot, goal, rng, q_seed, max_restarts, max_iter, check_collision, time_limit,
                              distinct_tol, reach_bounds, canonical, saturate, self.solutions, self.stats,
                              max_step)

    def run(self, n_solutions: int) -> IKResult:
        """Go on until there are ``n_solutions`` solutions or the search ends; the result so far (copies)."""
        t0 = time.perf_counter()
        while not self.finished and len(self.solutions) < n_solutions:
            try:
                next(self._steps)
            except StopIteration:
                self.finished = True
        if not self.finished:
            self.stats["reason"] = "found"
        self.stats["time"] += time.perf_counter() - t0
        return IKResult(list(self.solutions), dict(self.stats))


def _search(robot, goal: ToleratedPose, rng, q_seed: Optional[np.ndarray], max_restarts: int, max_iter: int,
            check_collision: bool, time_limit: Optional[float], distinct_tol: float, reach_bounds: bool,
            canonical: bool, saturate: int, sols: List[np.ndarray], stats: Dict[str, Any],
            max_step: Optional[np.ndarray] = None):
    """The body of :class:`IKSearch`: appends each new solution to ``sols`` and yields; sets
    ``stats["reason"]`` and returns when the search ends."""
    t0 = time.perf_counter()
    rng = _as_rng(rng)
    model, data, fid = robot.kinematic_model, robot.data, robot.tcp_frame
    n = robot.dof
    lo = np.asarray(robot.q_lower, dtype=float)
    hi = np.asarray(robot.q_upper, dtype=float)
    gm = goal_model(goal)
    total_iter = 0

    why = chain_bounds(robot).unreachable(gm) if reach_bounds else ""
    if why:
        stats["reason"] = why
        return

    valid = goal.valid
    trace = _trace
    kernel = _kernel_descend(robot, gm, n, lo, hi, valid, max_iter) if trace is None else None
    evaluate, E, JJ = gm.evaluator(n) if kernel is None else cast(Any, (None, np.zeros(0), None))  # (Python loop)
    m_rows = len(E)
    cjj, ufp, gfj = pin.computeJointJacobians, pin.updateFramePlacement, pin.getFrameJacobian
    LOCAL = pin.LOCAL
    deadline = None if time_limit is None else t0 + float(time_limit)
    max_step2 = _MAX_STEP * _MAX_STEP
    solve = _solve
    eye = np.eye(min(m_rows, n))
    small = m_rows <= n
    # restarts draw exactly what robot.random_configuration(rng) draws, without its per-call set-up
    r_lo = np.where(np.isfinite(lo), lo, -math.pi)
    r_hi = np.where(np.isfinite(hi), hi, math.pi)
    normal = rng.normal

    def py_descend(q: np.ndarray, iters: int):
        """LM from q; the accepted configuration or None. Counts iterations in ``total_iter``."""
        nonlocal total_iter
        best = math.inf
        since = 0
        hist: Optional[List[float]] = [] if trace is not None else None
        found = None
        it = 0
        for it in range(iters):
            cjj(model, data, q)
            T = ufp(model, data, fid).homogeneous
            ok = evaluate(T, gfj(model, data, fid, LOCAL))
            total_iter += 1
            if ok and valid(T):
                found = q
                break
            err = float(E.dot(E))
            if err == 0.0:
                break  # inside every target interval but not valid (only possible with fallback rows)
            if hist is not None:
                hist.append(err)
            if err < best * _STALL_RATIO:
                best = err
                since = 0
            else:
                since += 1
                if since >= _STALL_WINDOW:
                    break
            lam = _LAMBDA_FACTOR * err + _LAMBDA_BIAS
            if small:             # dq = Jᵀ (J Jᵀ + λI)⁻¹ e
                A = JJ.dot(JJ.T)
                A += eye * lam
                dq = JJ.T.dot(solve(A, E))
            else:                 # dq = (JᵀJ + λI)⁻¹ Jᵀ e
                A = JJ.T.dot(JJ)
                A += eye * lam
                dq = solve(A, JJ.T.dot(E))
            s2 = float(dq.dot(dq))
            if not s2 <= max_step2:       # also catches NaN
                if not math.isfinite(s2):
                    break
                dq *= _MAX_STEP / math.sqrt(s2)
            q = q - dq
            np.minimum(q, hi, out=q)
            np.maximum(q, lo, out=q)
        if trace is not None:
            trace.append((found is not None, it + 1, hist))
        return found

    def repair(found: np.ndarray, noise: np.ndarray):
        """A re-solve from ``clip(found + noise, lo, hi)`` (in the compiled loop: the same start, made there)."""
        nonlocal total_iter
        if kernel is None:
            return py_descend(_clip(found + noise, lo, hi), _REPAIR_ITER)
        q2, its = kernel.repair(found, noise, _REPAIR_ITER)
        total_iter += its
        return q2

    accept = Acceptance(robot, valid, lo, hi, q_seed, check_collision, canonical, distinct_tol, stats, sols,
                        max_step)
    repeats = 0   # duplicates found since the last new solution (saturate)

    # every attempt's start at once: the same numbers as one uniform draw (random_configuration) per attempt
    starts = r_lo + (r_hi - r_lo) * rng.random((max_restarts, n))
    if q_seed is not None:
        starts[0] = np.clip(q_seed, lo, hi)
    attempt = 0
    while attempt < max_restarts:
        if deadline is not None and attempt > 0 and time.perf_counter() > deadline:
            stats["iterations"], stats["reason"] = total_iter, "time_limit"
            return
        if gm.unconstrained:
            found = starts[attempt].copy()
            attempt += 1
        elif kernel is not None:
            # descents in the compiled loop until one lands in the goal (one at a time under a time limit)
            stop = max_restarts if deadline is None else attempt + 1
            idx, found, its = kernel.batch(starts, attempt, stop)
            total_iter += its
            attempt = min(idx + 1, stop)
        else:
            found = py_descend(starts[attempt].copy(), max_iter)
            attempt += 1
        stats["attempts"] = attempt
        if found is None:
            continue
        stats["converged"] += 1
        verdict = accept(found)
        if verdict == "collision" and not gm.unconstrained and stats["rejected_collision"] > _REPAIR_AFTER:
            # collisions are the bottleneck: the valid set around this IK branch may hold
            # collision-free configurations (a few 0.01 rad away), so look there before restarting
            for _ in range(_REPAIR_TRIES):
                q2 = repair(found, normal(0.0, _REPAIR_SIGMA, n))
                if q2 is None:
                    continue
                stats["repairs"] += 1
                verdict = accept(q2)
                if verdict != "collision":
                    break
        if verdict == "added":
            stats["iterations"] = total_iter
            repeats = 0
            yield
        elif verdict == "duplicate":
            repeats += 1
            if repeats == saturate:
                stats["iterations"], stats["reason"] = total_iter, "saturated"
                return
    stats["iterations"], stats["reason"] = total_iter, "max_restarts"
