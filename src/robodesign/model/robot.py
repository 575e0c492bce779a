"""Exact robot models: a pinocchio ``Model`` plus coal collision geometry, built from an assembly.

``Robot`` keeps what the robot *is* (pinocchio model, geometry model, limits, drivetrain
parameters, base pose) apart from scratch space (``pin.Data``/``pin.GeometryData``), as in
Pinocchio. It is built once per assembly (~1 ms) and is not meant to be pickled: ship the
(module set, assembly) specs to other processes and rebuild there. Its collision geometry and
queries are :class:`robodesign.model.robot_geometry.RobotGeometry`'s.

Conventions (docs/formats.md):
* The base frame is the base connector flipped about x; ``base_pose`` is its world pose.
* Revolute joints rotate about the joint frame's z axis, prismatic ones translate along it. A
  module mounted "backwards" (entered through its child body) gets the same joint about −z so q
  keeps its meaning.
* The TCP is the free ``eef`` connector (or the last free connector in breadth-first order).
* Drivetrain torque (:meth:`Robot.drivetrain_torques`, the one formula)
  τ = RNEA(q, q̇, q̈) + k²·I_m·q̈ + f_v·q̇ + f_c·σ(q̇), with σ(x) = sin(atan(100x))
  (the smooth sign of the reference, so costs are comparable); k²·I_m is pinocchio's ``armature``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import chain
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np
import pinocchio as pin

from robodesign.core.errors import AssemblyError, InputError
from robodesign.formats.assembly import Assembly
from robodesign.formats.module_spec import ModuleSet
from robodesign.model import robot_build as _rb
from robodesign.model.batch_fk import batch_kinematics as _batch_kinematics
from robodesign.model.batch_fk import fk_batch
from robodesign.model.pair_scratch import fresh_guesses
from robodesign.model.rnea_batch import rnea_rows
from robodesign.model.robot_build import (
    add_bodies,
    add_body_frames,
    chain_to,
    finish,
    vector_norm,  # noqa: F401 - where solve and solvers.ik import it from
    walk,
)
from robodesign.model.robot_geometry import Obstacle, RobotGeometry

COULOMB_SMOOTHING = 100.0
# the build's memo helpers, where they were before robot_build had them
_memo, _coal_shapes, _inertia, _zero_inertias = _rb._memo, _rb._coal_shapes, _rb._inertia, _rb._zero_inertias


def smooth_sign(x: np.ndarray) -> np.ndarray:
    """sin(atan(k·x)) = k·x / √(1 + (k·x)²), the reference's smooth sign (k = 100)."""
    s = COULOMB_SMOOTHING * np.asarray(x, dtype=float)
    return s / np.sqrt(1.0 + s * s)


_UNIFORMS: Dict[int, np.ndarray] = {}   # n → the first n standard uniforms of np.random.default_rng(0)


def _rank_samples(lo: np.ndarray, hi: np.ndarray, samples: int) -> np.ndarray:
    """The ``samples`` configurations (rows) that ``np.random.default_rng(0).uniform(lo, hi)`` gives one call after
    the other: each is ``lo + (hi − lo)·u`` with ``u`` the generator's next standard uniforms, the same numbers."""
    n = samples * lo.size
    u = _UNIFORMS.get(n)
    if u is None:
        u = _UNIFORMS[n] = np.random.default_rng(0).random(n)
    return lo + (hi - lo) * u.reshape(samples, lo.size)


try:  # the gufunc behind np.linalg.svd(compute_uv=False) without its ~15 µs of Python-level checks
    from numpy.linalg import _umath_linalg as _ul

    def _svd_values(J: np.ndarray) -> np.ndarray:
        """``np.linalg.svd(J, compute_uv=False)`` of a float64 matrix or stack: the same LAPACK call. A vector, a
        non-finite input, or an output with a non-finite value (no convergence) goes through numpy's own call,
        which then raises or answers (and warns) as it does."""
        if J.ndim < 2 or not np.isfinite(J).all():
            return np.linalg.svd(J, compute_uv=False)
        s = _ul.svd(J, signature="d->d")
        return s if np.isfinite(s).all() else np.linalg.svd(J, compute_uv=False)
    _svd_values(np.eye(2))
except Exception:  # pragma: no cover - other numpy layouts
    def _svd_values(J: np.ndarray) -> np.ndarray:
        """``np.linalg.svd(J, compute_uv=False)``."""
        return np.linalg.svd(J, compute_uv=False)


def _rank(s: np.ndarray, rtol: float) -> int:
    """The rank of a matrix with singular values ``s`` (descending): how many exceed ``rtol`` times the largest
    (0 for none or a zero matrix); the comparisons of ``np.sum(s > rtol * s[0])``, in Python floats."""
    v = s.tolist()
    if not v or not v[0] > 0:
        return 0
    t = rtol * v[0]
    return sum(x > t for x in v)


#: the smallest eigenvalue of a Gram matrix that :func:`_certainly_full_rank` certifies, as a fraction of its trace, is
#: the square of the larger of this and 1000·rtol
_CERTIFIED_RATIO = 1e-5


def _certainly_full_rank(J: np.ndarray, rtol: float) -> bool:
    """Whether the rank that :func:`_rank` gives of ``_svd_values(J)`` is certainly ``min(J.shape)``, shown without an
    SVD (False: not shown, the SVD decides; ~25 µs against the SVD's ~70 µs in an evaluation, where LAPACK's code is
    cold). J's smaller Gram matrix G (J·Jᵀ or Jᵀ·J, eigenvalues σᵢ²) minus t·I, t = tr(G)·max(1000·rtol, 1e-5)², has a
    Cholesky factor (computed in Python floats). A factor computed in floating point is the exact one of a matrix off
    by δ < (n + 8)·1e-15·tr(G) (the rounding of G and of the factorization; n: J's longer side, at most 1000 here),
    far below t ≥ 1e-10·tr(G): so σ_min² ≥ t − δ, and with tr(G) ≥ σ₁², σ_min/σ₁ > 0.99·max(1000·rtol, 1e-5).
    LAPACK's singular values are off by less than 1e-12·σ₁ (backward stable): all of them exceed rtol·σ₁. Only for
    rtol ≤ 1e-6 (larger tolerances: the SVD) and a finite matrix J with a Gram trace below 1e300."""
    if J.ndim != 2 or not J.size or max(J.shape) > 1000 or rtol > 1e-6:
        return False
    G = J @ J.T if J.shape[0] <= J.shape[1] else J.T @ J
    g = G.tolist()
    tr = 0.0
    for i, gi in enumerate(g):
        tr += gi[i]
    if not 0.0 < tr < 1e300:   # (also a J with a non-finite value)
        return False
    t = tr * max(1e3 * rtol, _CERTIFIED_RATIO) ** 2
    L: List[List[float]] = []
    for i, gi in enumerate(g):
        row: List[float] = []
        for j, lj in enumerate(L):
            s = gi[j]
            for m in range(j):
                s -= row[m] * lj[m]
            row.append(s / lj[j])
        s = gi[i] - t
        for x in row:
            s -= x * x
        if not s > 0.0:
            return False
        row.append(math.sqrt(s))
        L.append(row)
    return True


_G = (0.0, 0.0, -9.81)   # the default gravity
_GRAVITIES: Dict[int, Tuple[tuple, "pin.Motion"]] = {}   # id(a tuple of floats) → (it, pinocchio's motion of it)


def _gravity_motion(g: Sequence[float]) -> "pin.Motion":
    """pinocchio's motion of the gravity ``g`` (a model it is set on keeps a copy), made once per tuple of floats
    object (immutable: the robots of a cell are given their task's)."""
    hit = _GRAVITIES.get(id(g))
    if hit is not None and hit[0] is g:
        return hit[1]
    motion = pin.Motion(np.array([*g, 0.0, 0.0, 0.0], dtype=float))
    if type(g) is tuple and all(type(x) is float for x in g):
        if len(_GRAVITIES) >= 256:
            _GRAVITIES.clear()
        _GRAVITIES[id(g)] = (g, motion)   # (g held: its id is not reused while the entry lives)
    return motion


@dataclass(frozen=True)
class JointInfo:
    name: str
    module_index: int
    module_id: str
    joint_id: str
    type: str
    reversed: bool


_INFOS: Dict[tuple, JointInfo] = {}   # its fields → a JointInfo (immutable: robots share them)


def _joint_info(fields: tuple) -> JointInfo:
    if len(_INFOS) >= 65536:
        _INFOS.clear()
    info = _INFOS[fields] = JointInfo(*fields)
    return info


class Robot(RobotGeometry):
    def __init__(self, module_set: ModuleSet, assembly: Assembly, base_pose: Optional[np.ndarray] = None,
                 convex_meshes: bool = False, gravity: Sequence[float] = _G):
        self.module_set = module_set
        self.assembly = assembly
        self._build(convex_meshes)
        self.kinematic_model.gravity = _gravity_motion(gravity)
        self.data: "pin.Data"
        if base_pose is None:   # (else set_base_pose below makes them)
            self.base_pose = np.eye(4)
            self.data = pin.Data(self.kinematic_model)
        self._sync_link_model()
        self._geom_data = None  # built on first use (many candidates never reach a collision query)
        self._geometry_changed()
        self._base_probe: Optional[tuple] = None  # base_collisions' own pairs before there is a geom_data
        self._root_spheres: Optional[tuple] = None   # base_collisions' bounds of the objects fixed to the world
        self._obstacle_bounds = None                 # and of the obstacles (collision_cull.ObstacleBounds)
        self._reach: Optional[Tuple[np.ndarray, float]] = None
        self._generic_rank: Optional[int] = None
        self._batch_chain: Optional[Any] = None  # batch_fk._BatchKinematics, built on first use
        self.obstacles: List[Obstacle] = []
        self._obstacle_ids: List[int] = []
        self.safety_margin = 0.0  # of robot–obstacle pairs (set_obstacles)
        if base_pose is not None:
            self.set_base_pose(base_pose)

    # ------------------------------------------------------------------------------------------
    @classmethod
    def from_order(cls, module_set: ModuleSet, order: Sequence, **kw) -> "Robot":
        return cls(module_set, Assembly.from_order(module_set, order), **kw)

    def _build(self, convex_meshes: bool) -> None:
        """The model (its joints, bodies and TCP frame; the other frames are added by :meth:`add_frames`), the
        joints' limits and the collision geometry's specs, by a breadth-first walk over the assembly's bodies from
        the base connector (:func:`robodesign.model.robot_build.walk`)."""
        w = walk(self.module_set, self.assembly, convex_meshes)
        model = w.model
        self.instance_labels = w.labels
        self._root_items = w.root_items   # (kind, index, base-frame placement)
        self.joint_infos = [_INFOS.get(j) or _joint_info(j) for j in w.joints]
        nq = model.nq
        if nq != len(self.joint_infos):
            raise AssemblyError("only 1-DoF joints are supported")
        self.dof = nq
        self.mass = w.mass
        rows = w.rows   # (per joint: its nine numbers, read as np.array(rows, dtype=float) would)
        columns = np.fromiter(chain.from_iterable(rows), float, 9 * len(rows)).reshape(-1, 9).T.copy()
        self._set_joint_limits(model, columns)
        self.tcp_frame, tcp_joint, Mc = finish(w)
        self._chain = chain_to(w, tcp_joint)   # (tcp_chain's)
        self._joint_norms, self._tcp_norm = w.joint_norms, w.tcp_norm   # (reach_bound's terms)
        if Mc is not None:
            self._root_items.append(("frame", self.tcp_frame, Mc))
        # the pinocchio model for kinematics (joints, frames, limits): model's object, its bodies perhaps not added
        self.kinematic_model = model
        self._bodies_of: Optional[_rb.Walk] = w
        self._frames: Optional[list] = w.bodies   # (the bodies' frames; None once add_frames has added them)
        self._geom_model: Optional[pin.GeometryModel] = None
        self._geoms, self._n_geoms, self._root_geoms, self._placed = w.geoms, w.n_geoms, w.root_geoms, False
        self._root_key = tuple(w.root_key)
        self._specs: Optional[list] = None   # (_geom_specs, _geom_body: made of _geoms on first use)
        self._bodies_of_geoms: Optional[list] = None
        self._direct_joint_pairs, self._self_map = w.direct_joint_pairs, None   # (the map: on first use)

    @property
    def model(self) -> "pin.Model":
        """The pinocchio model. A new robot's has its joints, their limits and its frames; its bodies' inertias are
        added at the first ask for it (:func:`~robodesign.model.robot_build.add_bodies`): the robot's own
        kinematics (forward kinematics, Jacobians, reach bound, collision placements) reads its joints and frames
        without asking, so a design that fails before any other use never adds them."""
        w = self._bodies_of
        if w is not None:
            self._bodies_of = None
            add_bodies(w, self.tcp_frame)
        return self.kinematic_model

    def _set_joint_limits(self, model: "pin.Model", columns: np.ndarray) -> None:
        """The joints' limits and drivetrains (rows of ``columns`` in joint order: lower, upper, velocity,
        acceleration, torque, gear ratio, motor inertia, Coulomb and viscous friction) on the robot and its model
        (armature)."""
        lower, upper, vel, acc, eff, gear, im, fc, fv = columns
        self.q_lower, self.q_upper, self.dq_max, self.ddq_max, self.tau_max = lower, upper, vel, acc, eff
        self.gear_ratio, self.motor_inertia, self.friction_coulomb, self.friction_viscous = gear, im, fc, fv
        # (pinocchio keeps copies)
        model.lowerPositionLimit, model.upperPositionLimit, model.velocityLimit, model.effortLimit = lower, upper, vel, eff
        model.armature = gear ** 2 * im

    # ------------------------------------------------------------------------------------------
    # configuration of the robot in its cell
    def set_base_pose(self, T: np.ndarray) -> None:
        T = np.asarray(T, dtype=float)
        if T.shape != (4, 4) or not all(map(math.isfinite, T.ravel().tolist())):
            raise InputError("base pose must be a finite 4x4 matrix")
        self.base_pose = T.copy()
        model, geom, SE3 = self.kinematic_model, self._geom_model, pin.SE3
        for kind, idx, M in self._root_items:
            if kind == "joint":
                model.jointPlacements[idx] = SE3(T @ M)
            elif kind == "frame":
                model.frames[idx].placement = SE3(T @ M)
            elif geom is not None:   # (else the geometry, when it is made, places them: _geometry_object)
                geom.geometryObjects[idx].placement = SE3(T @ M)
        self._placed = True
        self.data = pin.Data(model)   # (createData's Data, made in place: createData returns a copy)
        self._sync_link_model()
        if self._geom_data is not None:  # the scratch space stays (it holds no placement between queries), but as
            fresh_guesses(self._geom_data)  # a new one: each pair's GJK starts from where a new one starts
        self._base_probe = self._reach = self._batch_chain = None
        self._geometry_changed()

    def set_gravity(self, g: Sequence[float]) -> None:
        self.kinematic_model.gravity = _gravity_motion(g)
        self._sync_link_model()

    def _sync_link_model(self) -> None:
        """Invalidate the armature-free model copy (rebuilt lazily by :meth:`rnea`)."""
        self._link_model: Optional[pin.Model] = None

    # ------------------------------------------------------------------------------------------
    # kinematics
    def _q(self, q) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        if q.shape[0] != self.dof or q.ndim != 1:
            raise InputError(f"expected {self.dof} joint values, got shape {q.shape}")
        return q

    def tcp_chain(self) -> List[int]:
        """The pinocchio joint ids from the world to the TCP's joint, in order (empty: TCP on the base)."""
        return list(self._chain)

    def fk(self, q, frame: Optional[int] = None) -> np.ndarray:
        """World pose (4x4) of a frame (default: TCP)."""
        pin.framesForwardKinematics(self.kinematic_model, self.data, self._q(q))
        return self.data.oMf[self.tcp_frame if frame is None else frame].homogeneous

    def fk_batch(self, Q, frame: Optional[int] = None) -> np.ndarray:
        """World poses (N×4×4) of a frame (default: TCP) at every configuration of ``Q`` (N×dof): the
        same numbers as :meth:`fk` per row (to ~1e-15), computed in one vectorised pass over the samples
        (:func:`fk_batch`)."""
        return fk_batch(self, Q, frame)

    def joint_poses_batch(self, Q) -> np.ndarray:
        """World poses (N×njoints×4×4) of every pinocchio joint frame (index 0: the world) at every
        configuration of ``Q``, as ``data.oMi`` after ``pin.forwardKinematics`` per row."""
        return _batch_kinematics(self).joint_poses(self._Q(Q))

    def _Q(self, Q) -> np.ndarray:
        Q = np.asarray(Q, dtype=float)
        if Q.ndim == 1:
            Q = Q.reshape(1, -1)
        if Q.ndim != 2 or Q.shape[1] != self.dof:
            raise InputError(f"expected N×{self.dof} joint values, got shape {Q.shape}")
        return Q

    def add_frames(self) -> "pin.Model":
        """The model with every frame: a new robot's model has its joints' frames and the TCP; the frames of its
        bodies (``<instance>.<body>``) and connectors (``<instance>.<body>.<connector>``) are added by the first
        call of this (which :meth:`frame_id`, :meth:`fk_all` and the URDF export and viewer make), with a new
        :attr:`data` (a ``Data`` made before has no room for them). Most designs of a search never need them."""
        frames, self._frames = self._frames, None
        if frames:
            model = self.model
            add_body_frames(model, frames, self.base_pose if self._placed else None, self._root_items)
            self.data = pin.Data(model)
        return self.model

    def fk_all(self, q) -> Dict[str, np.ndarray]:
        model = self.add_frames()
        pin.framesForwardKinematics(model, self.data, self._q(q))
        return {f.name: self.data.oMf[i].homogeneous for i, f in enumerate(model.frames)}

    def frame_id(self, name: str) -> int:
        self.add_frames()
        if not self.model.existFrame(name):
            raise KeyError(name)
        return self.model.getFrameId(name)

    def jacobian(self, q, frame: Optional[int] = None, reference=pin.LOCAL_WORLD_ALIGNED) -> np.ndarray:
        """6×dof frame Jacobian (linear rows first), world-aligned at the frame origin by default."""
        f = self.tcp_frame if frame is None else frame
        return pin.computeFrameJacobian(self.kinematic_model, self.data, self._q(q), f, reference)

    def generic_rank(self, samples: int = 4, rtol: float = 1e-8) -> int:
        """How many independent directions (of the 6 of a pose) the TCP can move in at a generic configuration:
        the largest rank of the TCP Jacobian over ``samples`` configurations drawn (seeded) within the joint
        limits, the angular rows scaled by the reach radius so both halves have units of length. A structural
        rank below 6 (parallel or coaxial axes where a wrist needs three independent ones, fewer than six
        joints, ...) holds at every configuration except a set of measure zero: such an arm reaches only a
        lower-dimensional set of poses. Cached (independent of the base pose).

        The configurations are ``np.random.default_rng(0).uniform(lo, hi)`` drawn ``samples`` times
        (:func:`_rank_samples`); the first one's rank decides when :func:`_certainly_full_rank` shows it full, else the
        structure when it bounds the rank by what the first one certainly has (:meth:`_deficient_rank`), else
        all Jacobians go through one SVD call (numpy's SVD of a stack is each matrix's own LAPACK call: the same
        singular values), and the scratch space is left as the one-by-one loop that stops at the first full rank
        leaves it."""
        if self._generic_rank is None:
            lo = np.maximum(np.asarray(self.q_lower, float), -math.pi)
            hi = np.minimum(np.asarray(self.q_upper, float), math.pi)
            scale = max(self.reach_bound()[1], 1e-3)
            Q = _rank_samples(lo, hi, max(1, samples))
            J = self._scaled_jacobian(Q[0], scale)
            full = min(J.shape)
            if _certainly_full_rank(J, rtol):
                self._generic_rank = full
            elif J.ndim < 2 or not J.size or len(Q) == 1:   # (a vector: numpy's SVD raises, as the loop's did)
                self._generic_rank = _rank(_svd_values(J) if J.size else np.zeros(0), rtol)
            else:
                self._generic_rank = self._deficient_rank(J, Q, scale, rtol)
        return self._generic_rank

    def _deficient_rank(self, J: np.ndarray, Q: np.ndarray, scale: float, rtol: float) -> int:
        """The largest rank of the scaled Jacobians at the rows of ``Q`` (``J``: the first one's, not shown full): the
        structural rank when it decides (:func:`robodesign.model.rank_bound.structural_rank`: then no sample counts
        more, and none counts full), with the scratch space left at the last row as the loop left it; else
        :meth:`_stacked_rank`."""
        from robodesign.model.rank_bound import structural_rank
        r = structural_rank(self, J, scale, rtol)
        if r is None:
            return self._stacked_rank(J, Q, scale, rtol)
        self.jacobian(Q[-1])
        return r

    def _stacked_rank(self, J: np.ndarray, Q: np.ndarray, scale: float, rtol: float) -> int:
        """The largest rank of the scaled Jacobians at the rows of ``Q`` (``J``: the first one's), from one SVD call;
        the scratch space left at the first row of full rank (the last row without one), as the loop left it."""
        Js = np.stack([J] + [self._scaled_jacobian(q, scale) for q in Q[1:]])
        ranks = [_rank(s, rtol) for s in _svd_values(Js)]
        full = min(J.shape)
        first_full = next((k for k, r in enumerate(ranks) if r >= full), len(Q) - 1)
        if first_full < len(Q) - 1:   # (where the loop stopped: its Jacobian was the last one made)
            self.jacobian(Q[first_full])
        return max(ranks)

    def _scaled_jacobian(self, q: np.ndarray, scale: float) -> np.ndarray:
        """The TCP Jacobian at ``q`` with its angular rows times ``scale`` (:meth:`generic_rank`'s)."""
        J = np.array(self.jacobian(q), dtype=float)
        J[3:] *= scale
        return J

    def reach_bound(self) -> Tuple[np.ndarray, float]:
        """(world point o, radius R): every reachable TCP position lies within R of o.

        o is the origin of the first joint on the TCP's chain (fixed in the world); R sums the distances
        between consecutive joint origins on the chain (constant for revolute joints, plus the stroke for
        prismatic ones) and the TCP offset from its joint. Cached until the base pose changes.
        """
        if self._reach is None:
            m, chain = self.kinematic_model, self._chain
            if not chain:
                d = self.data   # (scratch space: the frame's pose at the neutral configuration)
                pin.forwardKinematics(m, d, pin.neutral(m))
                o, R = pin.updateFramePlacement(m, d, self.tcp_frame).translation.copy(), 0.0
            else:
                o = self._first_joint_origin()
                norms = self._joint_norms   # (vector_norm of each model.jointPlacements[b].translation: the walk's)
                R = sum(norms[b - 1] for b in chain[1:])
                R += self._tcp_norm          # (of model.frames[self.tcp_frame].placement.translation)
                infos = self.joint_infos
                for j in chain:
                    if infos[j - 1].type == "prismatic":   # (pinocchio's PZ or PrismaticUnaligned)
                        idx = m.joints[j].idx_q
                        lo, hi = m.lowerPositionLimit[idx], m.upperPositionLimit[idx]
                        R += max(abs(lo), abs(hi)) if np.isfinite(lo) and np.isfinite(hi) else math.inf
            self._reach = (o, R)
        return self._reach[0].copy(), self._reach[1]

    def _first_joint_origin(self) -> np.ndarray:
        """The world origin of the TCP chain's first joint at the neutral configuration: ``data.oMi`` of it after
        ``pin.forwardKinematics(model, data, pin.neutral(model))``. On the world, that is its placement times the
        joint's transform at q = 0 (rotation, translation 0): translation t + R·0, which is t wherever t is finite
        and not zero (R·0 sums zeros; only a zero's sign could differ). There the placement's translation is taken;
        else pinocchio's forward kinematics is run."""
        m, j = self.kinematic_model, self._chain[0]
        t = m.jointPlacements[j].translation.copy()   # (the bindings' array views the model)
        if all(x != 0.0 and math.isfinite(x) for x in t.tolist()):
            return t
        d = self.data   # (scratch space)
        pin.forwardKinematics(m, d, pin.neutral(m))
        return d.oMi[j].translation.copy()

    # ------------------------------------------------------------------------------------------
    # dynamics
    def rnea(self, q, dq, ddq, f_ext=None) -> np.ndarray:
        """Link-side inverse dynamics of one sample (no motor inertia, no friction); ``f_ext``: pinocchio
        joint-frame forces (see :meth:`tcp_wrench_forces`)."""
        if self._link_model is None:  # a copy without armature: link-side RNEA in one pinocchio call
            self._link_model = pin.Model(self.model)
            self._link_model.armature = np.zeros(self.model.nv)
            self._link_data = pin.Data(self._link_model)
        m, d = self._link_model, self._link_data
        if f_ext is None:
            return pin.rnea(m, d, self._q(q), np.asarray(dq, dtype=float), np.asarray(ddq, dtype=float))
        return pin.rnea(m, d, self._q(q), np.asarray(dq, dtype=float), np.asarray(ddq, dtype=float), f_ext)

    def gravity_torque(self, q) -> np.ndarray:
        return pin.computeGeneralizedGravity(self.model, self.data, self._q(q)).copy()

    def tcp_wrench_forces(self, q, wrench) -> "pin.StdVec_Force":
        """A world wrench ``[f; τ]`` acting at the TCP as pinocchio joint-frame external forces for RNEA
        (which subtracts them: the joints resist the push, τ gains −Jᵀw)."""
        m, d = self.model, self.data
        pin.framesForwardKinematics(m, d, self._q(q))
        jid = m.frames[self.tcp_frame].parentJoint
        oMi = d.oMi[jid]
        w = np.asarray(wrench, dtype=float)
        f = w[:3]
        # the force acts at the TCP point: about the joint origin it adds the moment (p_tcp − p_joint) × f;
        # both are then expressed in the joint frame, as pinocchio's external forces are
        moment = w[3:] + np.cross(d.oMf[self.tcp_frame].translation - oMi.translation, f)
        fext = pin.StdVec_Force()
        for _ in range(m.njoints):
            fext.append(pin.Force.Zero())
        fext[jid] = pin.Force(oMi.rotation.T @ f, oMi.rotation.T @ moment)
        return fext

    def link_torques(self, Q, DQ, DDQ, fext=None) -> np.ndarray:
        """Link-side torques (RNEA without motor inertia and friction) at every sample: arrays (N, dof) →
        (N, dof). ``fext``: None or (N, 6) world wrenches ``[f; τ]`` applied at the TCP (zero rows: none)."""
        Q, DQ, DDQ = (np.asarray(x, dtype=float).reshape(-1, self.dof) for x in (Q, DQ, DDQ))
        if fext is None:   # pinocchio's RNEA of every row in one call (model.rnea_batch: the numbers of rnea per row)
            return rnea_rows(self.model, Q, DQ, DDQ, link_side=True)
        out = np.empty_like(Q)
        for k in range(len(Q)):
            f = None if fext is None or not np.any(fext[k]) else self.tcp_wrench_forces(Q[k], fext[k])
            out[k] = self.rnea(Q[k], DQ[k], DDQ[k], f)
        return out

    def friction_torques(self, DQ) -> np.ndarray:
        """f_v·q̇ + f_c·σ(q̇) (σ: :func:`smooth_sign`), per sample."""
        DQ = np.asarray(DQ, dtype=float)
        return self.friction_viscous * DQ + self.friction_coulomb * smooth_sign(DQ)

    def drivetrain_torques(self, Q, DQ, DDQ, fext=None, link_torques: Optional[np.ndarray] = None) -> np.ndarray:
        """Drivetrain (motor-side) torques, what peakTorque limits: τ = RNEA + k²·I_m·q̈ + f_v·q̇ + f_c·σ(q̇)
        at every sample, arrays (N, dof) → (N, dof). ``fext`` as in :meth:`link_torques`; pass
        ``link_torques`` when they are already computed for the same samples and wrenches."""
        tau_link = self.link_torques(Q, DQ, DDQ, fext) if link_torques is None else link_torques
        DDQ = np.asarray(DDQ, dtype=float).reshape(tau_link.shape)
        return tau_link + self.model.armature * DDQ + self.friction_torques(np.reshape(DQ, tau_link.shape))

    def mass_matrix(self, q) -> np.ndarray:
        """Joint-space inertia incl. reflected motor inertia (armature)."""
        M = pin.crba(self.model, self.data, self._q(q))
        return np.triu(M) + np.triu(M, 1).T

    def forward_dynamics(self, q, dq, tau) -> np.ndarray:
        """q̈ from drivetrain torque (inverse of :meth:`drivetrain_torques`)."""
        dq = np.asarray(dq, float)
        tau_link = np.asarray(tau, float) - self.friction_torques(dq)
        return pin.aba(self.model, self.data, self._q(q), dq, tau_link).copy()

    # ------------------------------------------------------------------------------------------
    def joint_limits(self) -> Dict[str, list]:
        return {"lower": self.q_lower.tolist(), "upper": self.q_upper.tolist(), "velocity": self.dq_max.tolist(),
                "acceleration": self.ddq_max.tolist(), "torque": self.tau_max.tolist()}

    def nearest_equivalent(self, q, near=None) -> np.ndarray:
        """The configuration of the same robot pose as ``q`` whose revolute joints are turned by whole turns
        (2π·k, within the joint limits) to lie nearest ``near`` (default: 0 clipped into the limits).

        Joints whose limits span more than a turn reach every pose in several sheets that differ by 2π, and a
        path between two sheets of a joint that folds the arm onto itself must pass through the fold: free
        space falls apart into pieces that hold the same poses. Keeping every IK solution in the sheet nearest
        one reference keeps them in one piece (docs/diagnosis.md, "Whole turns")."""
        q = np.array(q, dtype=float)
        rev = self._revolute_mask()
        if not rev.any():
            return q
        lo, hi = self.q_lower, self.q_upper
        ref = np.clip(0.0, lo, hi) if near is None else np.asarray(near, dtype=float)
        two_pi = 2.0 * math.pi
        k = np.round((ref - q) / two_pi)
        cand = q + two_pi * k
        # the shift nearest the reference may leave the limits: step one turn back towards q
        cand = np.where(cand > hi + 1e-12, cand - two_pi, cand)
        cand = np.where(cand < lo - 1e-12, cand + two_pi, cand)
        ok = rev & (cand >= lo - 1e-12) & (cand <= hi + 1e-12)
        return np.where(ok, cand, q)

    def turn_variants(self, q) -> List[np.ndarray]:
        """The configurations of the same pose as ``q`` with one revolute joint turned by ±2π (those within the
        joint limits): the other sheets a path may need, e.g. a base joint that must turn the long way round
        an obstacle."""
        q = np.asarray(q, dtype=float)
        out = []
        for j in np.flatnonzero(self._revolute_mask()):
            for s in (2.0 * math.pi, -2.0 * math.pi):
                v = q.copy()
                v[j] += s
                if self.q_lower[j] - 1e-12 <= v[j] <= self.q_upper[j] + 1e-12:
                    out.append(v)
        return out

    def _revolute_mask(self) -> np.ndarray:
        m = getattr(self, "_rev_mask", None)
        if m is None:
            m = self._rev_mask = np.array([ji.type == "revolute" for ji in self.joint_infos], dtype=bool)
        return m

    def random_configuration(self, rng: np.random.Generator) -> np.ndarray:
        lo = np.where(np.isfinite(self.q_lower), self.q_lower, -math.pi)
        hi = np.where(np.isfinite(self.q_upper), self.q_upper, math.pi)
        return rng.uniform(lo, hi)

    def summary(self, q=None) -> dict:
        q = np.zeros(self.dof) if q is None else self._q(q)
        return {
            "modules": list(self.assembly.module_ids),
            "dof": self.dof,
            "mass": self.mass,
            "q": q.tolist(),
            "tcp_pose": self.fk(q).tolist(),
            "base_pose": self.base_pose.tolist(),
            "gravity_torque": self.gravity_torque(q).tolist(),
            "joint_limits": self.joint_limits(),
            "joint_names": [j.name for j in self.joint_infos],
            "n_collision_geometries": self.n_collision_geometries,
            "n_self_collision_pairs": self.n_self_collision_pairs,
            "self_collision": self.in_self_collision(q),
        }
