"""Exact collision verdicts of many configurations at once (a path's dense states), with a conservative broad
phase in front of the robot's own narrow phase.

``robot.in_collision(q)`` asks coal about every collision pair (self pairs, then robot–obstacle pairs) until one
collides. :class:`CollisionCuller` gives the same verdict per state, asking coal (the same
``pin.computeCollision`` of the same pair on the same placements) only about the pairs that a lower bound of
their distance does not clear:

* every robot geometry is bounded by a sphere (its local AABB's centre and half diagonal, plus coal's swept-
  sphere radius); the centres of all states come from one vectorised forward kinematics pass
  (:meth:`Robot.joint_poses_batch`);
* a self pair is cleared when its spheres lie farther apart than the pair's security margin;
* a robot–obstacle pair is cleared when the sphere lies farther from the obstacle than the margin, measured
  with :class:`DistanceField`: the exact distance (coal) from the centre of the grid cell of the sphere's centre
  to the obstacle, minus the centre's distance to that cell centre (distance is 1-Lipschitz). Cells are computed
  on first use and kept per obstacle shape and pose for the process (tasks share shapes between candidates).

Every bound keeps a slack of :data:`SLACK` metres on top of the margin, far above coal's tolerances, so a
cleared pair is one coal would not report; the verdicts are identical to ``in_collision``
(tests/test_collision_cull.py compares them state by state).
"""
from __future__ import annotations

import weakref
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

import numpy as np
import pinocchio as pin

#: metres kept on top of every margin by the bounds (coal's GJK/EPA tolerances are ~1e-6 m)
SLACK = 1e-4
#: edge length [m] of the distance fields' cells
CELL = 0.04
_FIELD_LIMIT = 64  # distance fields kept (obstacle shape × pose); the oldest is dropped beyond


def _bounding_sphere(shape) -> Tuple[np.ndarray, float]:
    """Centre (in the shape's frame) and radius of a sphere containing ``shape`` (its local AABB's)."""
    shape.computeLocalAABB()
    box = shape.aabb_local
    lo, hi = np.array(box.min_, dtype=float), np.array(box.max_, dtype=float)
    swept = float(shape.getSweptSphereRadius()) if hasattr(shape, "getSweptSphereRadius") else 0.0
    return 0.5 * (lo + hi), 0.5 * float(np.linalg.norm(hi - lo)) + swept


class DistanceField:
    """Lower bounds of the distance from points to one obstacle (a coal shape at a world pose): the exact
    distance from the centre of the point's grid cell (edge :data:`CELL`), computed once per cell, minus the
    point's distance to that centre."""

    def __init__(self, shape, pose: np.ndarray, cell: float = CELL):
        self.shape, self.cell = shape, float(cell)
        M = np.asarray(pose, dtype=float)
        self.tf = pin.SE3(M[:3, :3].copy(), M[:3, 3].copy())
        self.known: Dict[int, float] = {}  # by the cell's packed integer coordinates
        import coal
        self._coal = coal
        self._point = coal.Sphere(0.0)
        self._req = coal.DistanceRequest()
        self._res = coal.DistanceResult()

    def _exact(self, c: np.ndarray) -> float:
        coal = self._coal
        self._res.clear()
        d = coal.distance(self._point, coal.Transform3s(np.eye(3), c), self.shape, self.tf, self._req, self._res)
        return float(d)

    def lower_bounds(self, P: np.ndarray) -> np.ndarray:
        """A lower bound of the distance to the obstacle of every point (row) of ``P``."""
        h = self.cell
        idx = np.floor(P / h).astype(np.int64)
        centres = (idx + 0.5) * h
        code = (idx[:, 0] << 42) + ((idx[:, 1] & _MASK) << 21) + (idx[:, 2] & _MASK)  # |index| < 2²⁰ cells
        keys, first, inverse = np.unique(code, return_index=True, return_inverse=True)
        known = self.known
        D = np.empty(len(keys))
        for i, (k, f) in enumerate(zip(keys.tolist(), first.tolist())):
            d = known.get(k)
            if d is None:
                d = known[k] = self._exact(centres[f])
            D[i] = d
        return D[inverse.reshape(-1)] - np.linalg.norm(P - centres, axis=1)


_MASK = (1 << 21) - 1
_FIELDS: Dict[Tuple[int, bytes], Tuple[object, DistanceField]] = {}


def distance_field(shape, pose: np.ndarray) -> DistanceField:
    """The process's :class:`DistanceField` of ``shape`` at ``pose`` (shared: task shapes are cached objects)."""
    key = (id(shape), np.asarray(pose, dtype=float).tobytes())
    hit = _FIELDS.get(key)
    if hit is not None and hit[0] is shape:
        return hit[1]
    if len(_FIELDS) >= _FIELD_LIMIT:
        _FIELDS.pop(next(iter(_FIELDS)))
    f = DistanceField(shape, pose)
    _FIELDS[key] = (shape, f)   # the shape is held, so its id is not reused while the entry lives
    return f


class CollisionCuller:
    """``robot.in_collision`` for many configurations: the pairs a bound clears are not asked (module docstring).
    Built for the robot's current geometry (base pose, obstacles, margins); the robot's own ``data`` and
    ``geom_data`` are the scratch space, as for ``in_collision``."""

    def __init__(self, robot):
        self.robot = robot
        robot.joint_poses_batch(np.zeros((1, robot.dof)))   # NotImplementedError now for a joint it cannot batch
        gm, gd = robot.geom_model, robot.geom_data
        objs = gm.geometryObjects
        n_robot = robot.n_collision_geometries
        self.parent = np.array([int(objs[i].parentJoint) for i in range(n_robot)])
        centres, radii = [], []
        for i in range(n_robot):
            c, r = _bounding_sphere(objs[i].geometry)
            P = objs[i].placement
            centres.append(np.asarray(P.rotation) @ c + np.asarray(P.translation))   # in the parent joint's frame
            radii.append(r)
        self.local = np.array(centres).reshape(-1, 3)
        self.radius = np.array(radii)
        pairs = [(int(cp.first), int(cp.second)) for cp in gm.collisionPairs]
        margin = np.array([float(gd.collisionRequests[k].security_margin) for k in range(len(pairs))])
        active = np.array([bool(a) for a in gd.activeCollisionPairs], dtype=bool) if len(pairs) else np.zeros(0, bool)
        self.n_pairs = len(pairs)
        self.active = active
        selfp = [k for k, (a, b) in enumerate(pairs) if a < n_robot and b < n_robot]
        self.self_k = np.array(selfp, dtype=int)
        self.self_a = np.array([pairs[k][0] for k in selfp], dtype=int)
        self.self_b = np.array([pairs[k][1] for k in selfp], dtype=int)
        self.self_limit = self.radius[self.self_a] + self.radius[self.self_b] + margin[self.self_k] + SLACK
        # robot–obstacle pairs, grouped by obstacle
        self.obstacles: List[Tuple[DistanceField, np.ndarray, np.ndarray, np.ndarray]] = []
        by_ob: Dict[int, List[int]] = {}
        for k, (a, b) in enumerate(pairs):
            if a < n_robot <= b:
                by_ob.setdefault(b, []).append(k)
            elif b < n_robot <= a:
                raise NotImplementedError("an obstacle listed first in a collision pair")
        for ob, ks in by_ob.items():
            o = objs[ob]
            field = distance_field(o.geometry, o.placement.homogeneous)
            kk = np.array(ks, dtype=int)
            geo = np.array([pairs[k][0] for k in ks], dtype=int)
            self.obstacles.append((field, kk, geo, self.radius[geo] + margin[kk] + SLACK))
        self.narrow = 0   # narrow-phase queries asked (statistics)

    def centres(self, Q: np.ndarray) -> np.ndarray:
        """World centres (N × geometries × 3) of the bounding spheres at every row of ``Q``."""
        J = self.robot.joint_poses_batch(Q)[:, self.parent]          # N × G × 4 × 4
        return np.einsum("ngij,gj->ngi", J[:, :, :3, :3], self.local) + J[:, :, :3, 3]

    def survivors(self, Q: np.ndarray) -> np.ndarray:
        """(N × pairs) booleans: the pairs the bounds do not clear at each row of ``Q`` (active pairs only)."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        N = len(Q)
        out = np.zeros((N, self.n_pairs), dtype=bool)
        if self.n_pairs == 0 or N == 0:
            return out
        C = self.centres(Q)
        if len(self.self_k):
            d = np.linalg.norm(C[:, self.self_a] - C[:, self.self_b], axis=2)
            out[:, self.self_k] = d <= self.self_limit
        for field, kk, geo, limit in self.obstacles:
            lb = field.lower_bounds(C[:, geo].reshape(-1, 3)).reshape(N, len(geo))
            out[:, kk] = lb <= limit
        out &= self.active
        return out

    def collides(self, q: np.ndarray, pairs: Iterable) -> bool:
        """Whether any of ``pairs`` collides at ``q`` (coal, as ``in_collision`` asks it)."""
        r = self.robot
        gm, gd = r.geom_model, r.geom_data
        pin.updateGeometryPlacements(r.model, r.data, gm, gd, np.asarray(q, dtype=float))
        for k in pairs:
            self.narrow += 1
            if pin.computeCollision(gm, gd, int(k)):
                return True
        return False

    def first_collision(self, Q: np.ndarray, order: Optional[Sequence[int]] = None) -> int:
        """The first row of ``Q`` in ``order`` (default: row order) that ``robot.in_collision`` finds in
        collision, or -1."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        S = self.survivors(Q)
        rows = range(len(Q)) if order is None else order
        for i in rows:
            ks = np.flatnonzero(S[i])
            if len(ks) and self.collides(Q[i], ks):
                return int(i)
        return -1


_CULLERS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def culler_of(robot) -> CollisionCuller:
    """The robot's :class:`CollisionCuller`, kept while its geometry stays the same: the same geometry model
    and data objects (held by the entry, so they are the same objects, not a new one at a reused address), base
    pose, safety margin and obstacle placements (what ``set_base_pose``, ``set_obstacles`` and
    ``move_obstacle`` change)."""
    gm, gd = robot.geom_model, robot.geom_data
    objs = gm.geometryObjects
    state = (robot.base_pose.tobytes(), float(getattr(robot, "safety_margin", 0.0)),
             b"".join(objs[k].placement.homogeneous.tobytes() for k in range(robot.n_collision_geometries, len(objs))))
    hit = _CULLERS.get(robot)
    if hit is not None and hit[0] is gm and hit[1] is gd and hit[2] == state:
        return hit[3]
    c = CollisionCuller(robot)
    try:
        _CULLERS[robot] = (gm, gd, state, c)
    except TypeError:   # an object without weak references: not kept
        pass
    return c


__all__ = ["CollisionCuller", "DistanceField", "culler_of", "distance_field", "SLACK", "CELL"]
