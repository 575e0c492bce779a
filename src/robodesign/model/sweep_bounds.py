"""Bounds of the certified sweep (:mod:`robodesign.model.sweep`) from the motion's own poses: the lever arms of
the poses at the samples (:class:`PosedArms`), with their kernels (:mod:`robodesign.model.sweep_kernel`) and the
numpy path those replace (the same numbers bit for bit)."""
from __future__ import annotations

import copy
import math
import sys
from typing import Any, List, Optional, Tuple

import numpy as np

from robodesign.model.robot import Robot, vector_norm


class StaticSteps:
    """dQ @ W (n−1, P), the static bound per step and pair, computed on first use (most checks never advance
    inside a step)."""

    def __init__(self, dQ: np.ndarray, W: np.ndarray):
        self.dQ, self.W = dQ, W
        self._a: Optional[np.ndarray] = None

    def array(self) -> np.ndarray:
        if self._a is None:
            self._a = self.dQ @ self.W
        return self._a

    def __getitem__(self, kc):
        return self.array()[kc]


class PosedArms:
    """Lever arms of the motion's own poses, per step: a revolute joint j moves a point p of geometry g at most
    dist(p, axis_j)·|q̇_j|, and dist(p, axis_j) ≤ ρ_jg + r_g, with ρ_jg the distance of g's frame origin from the
    axis and r_g the radius of g about that origin. ρ_jg does not change with joint j or the joints above it
    (a rigid motion of both, or a turn about the axis itself); the joints between j and g move g's origin by at
    most their point lever arms. So over step k, ρ_jg ≤ min(ρ_jg(k), ρ_jg(k + 1)) + Σ_i R⁰[i, g]·|Δq_i| (i
    strictly below j), computed at the samples by batched forward kinematics. The arm of a step is the smaller
    of this and the static one (prismatic joints keep theirs)."""

    SLACK = 1e-9  # relative, against rounding of the forward kinematics

    def __init__(self, robot: Optional[Robot], tree: Any, R: np.ndarray):
        self.robot, self.R = robot, R
        dof, G = R.shape
        self.plain = tree.lever_arms(False, dof)
        self.geom_joint = np.array(tree.geom_joint)
        self.t_g = np.array([np.asarray(p.translation, dtype=float) for p in tree.geom_placement]).reshape(G, 3)
        self.rad = np.array(tree.radii)
        # for the displacement bounds (extend): placements, and the centre and half diagonal of each local AABB
        self.R_g = np.array([np.asarray(p.rotation, dtype=float) for p in tree.geom_placement]).reshape(G, 3, 3)
        boxes = [(np.asarray(b.min_, dtype=float), np.asarray(b.max_, dtype=float))
                 for b in (geo.aabb_local for geo in tree.geom_geometry)]  # (set by tree.radii)
        self.box_centre = np.array([(lo + hi) / 2 for lo, hi in boxes]).reshape(G, 3)
        # how far a point of g can be from the box centre once g turns (the half diagonal, or the shape's own
        # bound where tighter: 0 for a sphere centred there, whose occupied space turns into itself)
        self.box_half_diagonal = np.array([vector_norm(hi - lo) / 2 for lo, hi in boxes])
        self.box_radius = np.array([min(d, _kept_reach(geo, c)) for d, geo, c in
                                    zip(self.box_half_diagonal, tree.geom_geometry, self.box_centre)])
        joint_of_v = {tree.idx_v[j]: j for j in range(1, tree.nj)}
        self.joints = [joint_of_v[v] for v in range(dof)]  # pinocchio joint id per velocity index
        self.revolute = np.array([tree.axes[j] is not None for j in self.joints])
        self.axes = np.array([tree.axes[j] if tree.axes[j] is not None else np.zeros(3) for j in self.joints])
        below = np.zeros((dof, dof), dtype=bool)  # below[i, j]: joint i strictly below joint j
        for i, ji in enumerate(self.joints):
            a = tree.parents[ji]
            while a > 0:
                below[i, tree.idx_v[a]] = True
                a = tree.parents[a]
        # down[i, (j, g)] = R⁰[i, g] for i strictly below j: the motion of g's origin relative to joint j
        self.down = (below[:, :, None] * self.plain[:, None, :]).reshape(dof, dof * G)
        # the (revolute joint, geometry) pairs with an arm to tighten
        self.jv, self.g = np.nonzero((R > 0) & self.revolute[:, None])
        self.jid = np.array(self.joints)[self.jv]
        self.flat = self.jv * G + self.g
        # the drift's non-zero terms per joint i (columns of down[:, flat]): summed in the order of i, the same
        # numbers as the full sum over i (the terms left out are +0.0 for finite |Δq|)
        D = self.down[:, self.flat]
        self._drift_terms = [(i, nz, D[i, nz]) for i in range(dof) for nz in [np.nonzero(D[i])[0]] if len(nz)]
        # the same terms flat (the kernel's): joint, columns and values per joint in the order of the joints
        cols = [nz for _, nz, _ in self._drift_terms]
        self._k_drift = (np.array([i for i, _, _ in self._drift_terms], dtype=np.int64),
                         np.cumsum([0] + [len(c) for c in cols]).astype(np.int64),
                         np.concatenate(cols).astype(np.int64) if cols else np.zeros(0, np.int64),
                         np.concatenate([d for _, _, d in self._drift_terms]) if cols else np.zeros(0))
        self._k_tree = (self.geom_joint.astype(np.int64), np.array(self.joints, dtype=np.int64),
                        np.ascontiguousarray(self.t_g), np.ascontiguousarray(self.axes, dtype=float),
                        self.jv.astype(np.int64), self.g.astype(np.int64), self.jid.astype(np.int64),
                        np.ascontiguousarray(self.R, dtype=float), np.ascontiguousarray(self.rad, dtype=float))
        self._gathers: dict = {}  # (W > 0, owner) → the distinct gather columns and where each pair's is
        self._last: Optional[tuple] = None  # (Q, dQ, arms, joint poses) of the last motion
        self._poses: Optional[np.ndarray] = None  # the geometries' poses of the last motion (poses())

    def bound_to(self, robot: Optional[Robot]) -> "PosedArms":
        """These arms for ``robot`` (one built alike: model.sweep._setup_key), without the last motion's."""
        out = copy.copy(self)
        out.robot, out._last, out._poses = robot, None, None
        return out

    def segments(self, Q: np.ndarray, dQ: np.ndarray, W: np.ndarray, owner: np.ndarray,
                 J: Optional[np.ndarray] = None) -> np.ndarray:
        """(n−1, P) displacement bounds per step and pair (≤ dQ @ W); ``J``: the joint poses of Q if known
        (``robot.joint_poses_batch(Q)``)."""
        dof, G = self.R.shape
        last = self._last
        if last is not None and np.array_equal(last[0], Q) and np.array_equal(last[1], dQ):
            X = last[2]  # the same motion (the checker's self and obstacle pairs): the same arms
        else:
            X, J = self._arms(Q, dQ, J)
            self._last, self._poses = (Q.copy(), dQ.copy(), X, J), None
        # pair c: the sum over joints j of X[:, j, owner[j, c]] where W[j, c] > 0 (a gather, not a matrix product:
        # numpy hands products this size to a multithreaded BLAS, which on a busy machine costs more than it saves)
        # pairs with the same owners on the same joints (a robot geometry against each obstacle, …) have the same
        # sum: each distinct column is gathered and summed once
        idx = np.where(W > 0, owner, G)
        key = idx.tobytes()
        if key not in self._gathers:
            self._gathers[key] = _distinct_columns(idx)
        uniq, inverse = self._gathers[key]
        kernel = _kernel(count=False) if len(X) else None
        if kernel is not None:
            return kernel.gather(X, dof, G, uniq, inverse)
        return self._gather_numpy(X, uniq, inverse)

    def schedule(self, Q: np.ndarray, dQ: np.ndarray, W: np.ndarray, owner: np.ndarray,
                 J: Optional[np.ndarray] = None) -> Tuple[np.ndarray, np.ndarray]:
        """(:meth:`segments`, their running sums per pair (P, n): row c is 0 then the cumulative sum of column c,
        as numpy.cumsum adds)."""
        sched = self.segments(Q, dQ, W, owner, J)
        kernel = _kernel(count=False) if len(sched) else None
        if kernel is not None:
            return sched, kernel.running_sums(sched)
        return sched, np.ascontiguousarray(np.concatenate([np.zeros((1, sched.shape[1])),
                                                           np.cumsum(sched, axis=0)]).T)

    def _gather_numpy(self, X: np.ndarray, uniq: np.ndarray, inverse: np.ndarray) -> np.ndarray:
        """The gather of :meth:`segments`, its terms summed from the first joint on (as the kernel)."""
        dof, G = self.R.shape
        X3 = np.concatenate([X.reshape(len(X), dof, G), np.zeros((len(X), dof, 1))], axis=2)
        S = X3[:, 0, uniq[0]]
        for j in range(1, dof):
            S = S + X3[:, j, uniq[j]]
        return S[:, inverse]

    def _drift(self, dQ: np.ndarray) -> np.ndarray:
        """(n−1, K): Σ_i R⁰[i, g]·|Δq_i| over the joints i strictly below j, per step and arm (j, g)."""
        if not np.isfinite(dQ).all():  # inf·0 is no number: the full sum, as written
            return (dQ[:, :, None] * self.down[None, :, self.flat]).sum(axis=1)
        out = np.zeros((len(dQ), len(self.flat)))
        for i, nz, d in self._drift_terms:
            out[:, nz] += dQ[:, i, None] * d
        return out

    def _arms(self, Q: np.ndarray, dQ: np.ndarray, J: Optional[np.ndarray] = None) \
            -> Tuple[np.ndarray, Optional[np.ndarray]]:
        """((n−1, dof·G): |Δq_j| times the arm of joint j for geometry g per step, the joint poses or None): the
        kernel's when it runs and every |Δq| is finite (the same numbers)."""
        if not len(self.flat):
            J = None  # no arm to tighten: the static arms
        elif J is None:
            assert self.robot is not None  # (a template's arms are bound to a robot before use: bound_to)
            try:
                J = self.robot.joint_poses_batch(Q)  # (n, njoints, 4, 4)
            except NotImplementedError:  # a joint type batched FK does not model: the static arms
                pass
        kernel = _kernel() if J is not None and len(dQ) and np.isfinite(dQ).all() else None
        if kernel is not None:
            return kernel.posed_arms(J, *self._k_tree, np.ascontiguousarray(dQ),
                                     *self._k_drift, 1 + self.SLACK), J
        return self._arms_numpy(J, dQ), J

    def _arms_numpy(self, J: Optional[np.ndarray], dQ: np.ndarray) -> np.ndarray:
        """:meth:`_arms` in numpy (J: the joint poses, None: the static arms)."""
        dof, G = self.R.shape
        X = (dQ[:, :, None] * self.R[None]).reshape(len(dQ), dof * G)  # the static arms
        if J is not None:
            Tg, Tj = J[:, self.geom_joint, :3], J[:, self.joints, :3]  # (n, G, 3, 4), (n, dof, 3, 4)
            centre = Tg[..., 3] + sum(Tg[..., b] * self.t_g[:, b, None] for b in range(3))  # (n, G, 3)
            axis = sum(Tj[..., b] * self.axes[:, b, None] for b in range(3))  # (n, dof, 3)
            rel = centre[:, self.g] - Tj[..., 3][:, self.jv]  # (n, K, 3)
            u = axis[:, self.jv]
            rx, ry, rz, ux, uy, uz = rel[..., 0], rel[..., 1], rel[..., 2], u[..., 0], u[..., 1], u[..., 2]
            rho = np.sqrt((ry * uz - rz * uy) ** 2 + (rz * ux - rx * uz) ** 2 + (rx * uy - ry * ux) ** 2).T  # (K, n)
            drift = self._drift(dQ)  # (n−1, K)
            arm = (np.minimum(rho[:, :-1], rho[:, 1:]).T + drift + self.rad[self.g]) * (1 + self.SLACK) + 1e-12
            arm = np.where(np.isfinite(arm), arm, np.inf)  # no number (huge q): the static arm
            X[:, self.flat] = dQ[:, self.jv] * np.minimum(self.R[self.jv, self.g], arm)
        return X

    def poses(self) -> Optional[np.ndarray]:
        """(n, G, 3, 4) world pose of every robot geometry at the samples of the last motion given to
        :meth:`segments` (None: batched FK does not model the robot)."""
        if self._poses is None and self._last is not None and self._last[3] is not None:
            J = self._last[3]
            k = _kernel(count=False)
            self._poses = (k.geometry_poses(J, self._k_tree[0], self.R_g, self.t_g) if k is not None
                           else geometry_poses_numpy(J, self.geom_joint, self.R_g, self.t_g))
        return self._poses

    def certify(self, due: List[int], d: np.ndarray, k: int, margins: np.ndarray, is_env: np.ndarray,
                rows: np.ndarray, TG: Optional[np.ndarray], mov: np.ndarray, ref: np.ndarray, sched: np.ndarray,
                ext: float, self_too: bool) -> List[int]:
        """Per pair of ``due`` queried at sample k (distances d): −1 in contact, −2 for the caller's own path (a
        clearance or bound that is no finite number), else the last sample certified: where the running sum
        ``rows[c]`` of the bounds from k reaches the clearance (numpy's searchsorted), then, with the poses TG,
        :meth:`extend` for robot–obstacle pairs (and self pairs with ``self_too``) to the clearance less
        ``ext``. The kernel's when it runs (the same numbers)."""
        kernel = _kernel(count=False)
        T = TG if TG is not None else np.zeros((0, 1, 3, 4))
        if kernel is not None:
            return kernel.certify(np.array(due, dtype=np.int64), d, k, margins, is_env, rows, T, mov, ref,
                                  self.box_centre, self.box_radius, sched, ext, BOUND_SLACK, self_too).tolist()
        n = rows.shape[1]
        out = []
        for c, dist in zip(due, d.tolist()):
            free = dist - float(margins[c])
            if free <= 0:
                out.append(-1)
                continue
            target = float(rows[c, k]) + free
            if not (math.isfinite(target) and math.isfinite(rows[c, n - 1])):
                out.append(-2)
                continue
            nxt = int(rows[c].searchsorted(target, side="right")) - 1
            if nxt < n - 1 and len(T) == n and (is_env[c] or self_too):
                nxt = extend_numpy(T, int(mov[c]), int(ref[c]), self.box_centre, self.box_radius, k, nxt, sched,
                                   rows, c, free - ext)
            out.append(nxt)
        return out

    def extend(self, TG: np.ndarray, m: int, r: int, k: int, start: int, sched: np.ndarray, rows: np.ndarray,
               col: int, limit: float) -> int:
        """The first step i ≥ ``start`` (of the motion whose geometry poses are TG) over which geometry m may come
        ``limit`` closer to geometry r (r < 0: to the world) than at sample k (n − 1: none). Over step i a point of
        m moves, relative to r, at most d_i = |x_i − x_k| + ‖A_i − A_k‖_F·ρ from where it was at sample k (A, x:
        m's rotation and its box centre in r's frame, ρ: the box's half diagonal) plus the step's bound s_i times
        the fraction of the step from either end, so at most (d_i + d_i+1 + s_i)/2, with a relative slack of
        1e-9 and 1e-12 m for rounding. Only the sample poses enter: the bound does not add up the path."""
        kernel = _kernel(count=False)
        if kernel is not None:
            return int(kernel.extend(TG, m, r, self.box_centre, self.box_radius, k, start, sched, rows, col, limit,
                                     BOUND_SLACK))
        return extend_numpy(TG, m, r, self.box_centre, self.box_radius, k, start, sched, rows, col, limit)


def _reach(geo: Any, c: np.ndarray) -> float:
    """A bound on how far a point of the space shape ``geo`` occupies moves, per radian of turn of the shape,
    once its point c has been moved with it: the largest distance from c of a point of a cylinder, cone, capsule
    or convex hull (its points), |c| for a sphere (centred at its origin; a turn about its centre moves none of
    the space), each plus the swept-sphere radius and a relative 1e-12; inf for another shape."""
    kind = type(geo).__name__
    sw = float(geo.getSweptSphereRadius()) if hasattr(geo, "getSweptSphereRadius") else math.inf
    cxy, cz = math.hypot(float(c[0]), float(c[1])), abs(float(c[2]))
    if kind == "Sphere":
        out = math.sqrt(cxy * cxy + cz * cz) + sw
    elif kind in ("Cylinder", "Cone"):
        out = math.hypot(float(geo.radius) + cxy, float(geo.halfLength) + cz) + sw
    elif kind == "Capsule":
        out = float(geo.halfLength) + float(geo.radius) + math.sqrt(cxy * cxy + cz * cz) + sw
    elif kind == "Convex" and int(geo.num_points) > 0:
        P = np.asarray(geo.points(), dtype=float).reshape(-1, 3)
        out = float(np.max(np.sqrt(((P - c) ** 2).sum(axis=1)))) + sw
    else:
        return math.inf
    return out * (1 + 1e-12) + 1e-15


_REACHES: dict = {}  # (id(shape), c's bytes) → (shape, _reach(shape, c)): the shapes are the module sets' (shared)


def _kept_reach(geo: Any, c: np.ndarray) -> float:
    """:func:`_reach` of ``geo`` at c, computed once per shape and point (a convex hull's reads all its points)."""
    key = (id(geo), np.asarray(c, dtype=float).tobytes())
    hit = _REACHES.get(key)
    if hit is None or hit[0] is not geo:
        if len(_REACHES) >= 4096:
            _REACHES.clear()
        hit = _REACHES[key] = (geo, _reach(geo, c))
    return hit[1]


def _distinct_columns(idx: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """(the distinct columns of the integer matrix ``idx`` in the order they first appear, int64; per column of
    ``idx`` the index of its own among them): what :meth:`PosedArms.segments` gathers once each."""
    cols = np.ascontiguousarray(idx.T, dtype=np.int64)
    first: dict = {}
    where: List[int] = []
    inverse = np.empty(len(cols), np.int64)
    for p, col in enumerate(map(bytes, cols)):
        i = first.get(col)
        if i is None:
            i = first[col] = len(where)
            where.append(p)
        inverse[p] = i
    return np.ascontiguousarray(cols[where].T), inverse


BOUND_SLACK = 1.0 + 1e-9  # relative slack of PosedArms.extend's bounds (the forward kinematics' rounding)


def geometry_poses_numpy(J: np.ndarray, geom_joint: np.ndarray, Rp: np.ndarray, tp: np.ndarray) -> np.ndarray:
    """(n, G, 3, 4): the joint's pose times the geometry's placement, each entry summed from the left (as the
    kernel)."""
    Jg = J[:, geom_joint]  # (n, G, 4, 4)
    out = np.empty((len(J), len(geom_joint), 3, 4))
    for a in range(3):
        j0, j1, j2 = Jg[:, :, a, 0], Jg[:, :, a, 1], Jg[:, :, a, 2]
        for b in range(3):
            out[:, :, a, b] = (j0 * Rp[:, 0, b] + j1 * Rp[:, 1, b]) + j2 * Rp[:, 2, b]
        out[:, :, a, 3] = ((j0 * tp[:, 0] + j1 * tp[:, 1]) + j2 * tp[:, 2]) + Jg[:, :, a, 3]
    return out


def _relative_numpy(TG: np.ndarray, m: int, r: int, rows, c: np.ndarray):
    """(A (n, 3, 3), x (n, 3)) of sweep_kernel._relative at the samples ``rows``."""
    M = TG[rows, m]
    if r < 0:
        A, t = M[:, :, :3], [M[:, 0, 3], M[:, 1, 3], M[:, 2, 3]]
    else:
        B = TG[rows, r]
        A = np.empty((len(M), 3, 3))
        for a in range(3):
            for b in range(3):
                A[:, a, b] = (B[:, 0, a] * M[:, 0, b] + B[:, 1, a] * M[:, 1, b]) + B[:, 2, a] * M[:, 2, b]
        d0, d1, d2 = M[:, 0, 3] - B[:, 0, 3], M[:, 1, 3] - B[:, 1, 3], M[:, 2, 3] - B[:, 2, 3]
        t = [(B[:, 0, a] * d0 + B[:, 1, a] * d1) + B[:, 2, a] * d2 for a in range(3)]
    x = np.stack([((A[:, a, 0] * c[0] + A[:, a, 1] * c[1]) + A[:, a, 2] * c[2]) + t[a] for a in range(3)], axis=1)
    return A, x


def extend_numpy(TG: np.ndarray, m: int, r: int, cen: np.ndarray, rad: np.ndarray, k: int, start: int,
                 sched: np.ndarray, rows: np.ndarray, col: int, limit: float) -> int:
    """sweep_kernel.extend in numpy (the same numbers and steps): a block of EXTEND_BLOCK steps passes on its end
    samples' displacement and its summed bound (a point is within the summed bound of the block's ends along
    the way), a block that does not, step by step."""
    n = len(TG)
    Ak, xk = _relative_numpy(TG, m, r, [k], cen[m])
    A, x = _relative_numpy(TG, m, r, np.arange(start, n), cen[m])
    e, f = x - xk, np.zeros(len(A))
    for a in range(3):
        for b in range(3):
            d = A[:, a, b] - Ak[0, a, b]
            f = f + d * d
    moved = (np.sqrt((e[:, 0] * e[:, 0] + e[:, 1] * e[:, 1]) + e[:, 2] * e[:, 2]) + np.sqrt(f) * rad[m]).tolist()
    i = start
    while i < n - 1:
        j = min(i + EXTEND_BLOCK, n - 1)
        da, db = moved[i - start], moved[j - start]
        if ((da + db) + (float(rows[col, j]) - float(rows[col, i]))) * 0.5 * BOUND_SLACK + 1e-12 < limit:
            i = j
            continue
        for t in range(i, j):
            d0, d1 = moved[t - start], moved[t + 1 - start]
            if not ((d0 + d1) + float(sched[t, col])) * 0.5 * BOUND_SLACK + 1e-12 < limit:
                return t
        i = j
    return n - 1


EXTEND_BLOCK = 8  # as sweep_kernel.EXTEND_BLOCK


_PASSES = [0]  # posed-arm passes made by this process
NUMPY_PASSES = 4  # passes on the numpy path before a process that has not imported numba imports it
_READY: List[Any] = []  # the kernels' module once they run in this process


def _kernel(count: bool = True) -> Any:
    """The compiled kernels (:mod:`~robodesign.model.sweep_kernel`) when they run in this process, else None.
    Importing numba takes 0.3–1 s: a process that has not imported it makes its first :data:`NUMPY_PASSES` passes
    (``count``: this call is one) on the numpy path (as judge.interval_rnea). Both paths give the same numbers."""
    if _READY:
        return _READY[0]
    _PASSES[0] += count
    if "numba" not in sys.modules and _PASSES[0] <= NUMPY_PASSES:
        return None
    from robodesign.model import sweep_kernel
    if not sweep_kernel.ready():
        return None
    _READY.append(sweep_kernel)  # (once ready, always: as sweep_kernel.ready)
    return sweep_kernel
