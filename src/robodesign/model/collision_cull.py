"""Exact collision verdicts with a conservative broad phase in front of coal: for one configuration
(:meth:`CollisionCuller.in_collision`, which ``Robot.in_collision`` uses once a geometry has been asked a few
times) and for many at once (:meth:`CollisionCuller.survivors`, a path's dense states).

``pin.computeCollisions`` asks coal about every collision pair (self pairs, then robot–obstacle pairs) until one
collides. :class:`CollisionCuller` gives the same verdict per state, asking coal (the same
``pin.computeCollision`` of the same pair on the same placements) only about the pairs that a lower bound of
their distance does not clear:

* every robot geometry is bounded by a sphere (:func:`tight_sphere`: the shape's own circumscribed sphere where its
  type gives one, else its local AABB's centre and half diagonal; plus coal's swept-sphere radius), its centre from
  the joint poses of the state;
* a self pair is cleared when its spheres lie farther apart than the pair's security margin, and for good once
  :mod:`.pair_clearance` has proven it farther apart than that at every configuration (on a robot with a convex
  mesh: when coal has been asked about the pair :data:`PROVE_AFTER` times, a verdict kept for it is taken and,
  without one, the proof is made at :data:`PROVE_NEW` asks, or at :data:`PROVE_AFTER` in the build's next robot; a
  proven pair is switched off in ``active``, like an inactive pair);
* a robot–obstacle pair is cleared when the sphere lies farther from the obstacle than the margin: first by the
  distance to the obstacle's box (its local AABB in its frame, which contains it: the exact distance for a box),
  then, for another shape, by :class:`DistanceField`: the exact distance (coal) from the centre of the grid cell
  of the sphere's centre to the obstacle, minus the centre's distance to that cell centre (distance is
  1-Lipschitz). Cells are computed on first use and kept per obstacle shape and pose for the process (tasks share
  shapes between candidates), in a dense grid around the obstacle's box and a dictionary beyond.

The compiled kernels of :mod:`.geometry_kernel` evaluate these bounds (numpy's pass for many states until they
are compiled). Every bound keeps a slack of :data:`SLACK` metres on top of the margin, far above coal's
tolerances, so a cleared pair is one coal would not report; the verdicts are those of asking coal about every pair
(tests/test_collision_cull.py and tests/test_geometry_kernel.py compare them state by state).
"""
from __future__ import annotations

import weakref
from typing import Any, Dict, Iterable, List, Optional, Sequence, Tuple, cast

import numpy as np
import pinocchio as pin

from robodesign.model import geometry_kernel, pair_clearance
from robodesign.model.batch_fk import batch_kinematics
from robodesign.model.culler_keep import geometry_state, taken_up
from robodesign.model.inner_spheres import placed_inner_spheres
from robodesign.model.pair_scratch import PairScratch, fresh_guesses
from robodesign.model.shape_spheres import _bounding_sphere, bounding_sphere, tight_sphere  # noqa: F401 (re-exported)

#: metres kept on top of every margin by the bounds (coal's GJK/EPA tolerances are ~1e-6 m)
SLACK = 1e-4
#: edge length [m] of the distance fields' cells
CELL = 0.04
_FIELD_LIMIT = 64  # distance fields kept (obstacle shape × pose); the oldest is dropped beyond
#: metres around an obstacle's box that its dense grid covers (farther points: the box bound clears them)
REACH = 0.5
#: the largest dense grid (cells, 8 bytes each) of one obstacle; a larger one keeps all its cells in the dictionary
GRID_CELLS_MAX = 1 << 22
#: the dense grids' cells kept in all (64 MB; the oldest fields are dropped beyond)
GRID_CELLS_KEPT = 1 << 23
#: the asks of a self pair of coal after which the culler looks up whether it is known never to collide
#: (:mod:`.pair_clearance`'s kept verdicts), and proves it when an earlier robot of the build was asked it as often
PROVE_AFTER = 8
#: the asks of a self pair after which the culler proves it (a proof costs some hundreds of asks: a pair first asked
#: this often in one robot is asked often enough to pay for it)
PROVE_NEW = 512


class ObstacleBounds:
    """The bounds of :class:`CollisionCuller` for several obstacles at once (each one's :class:`DistanceField`): which
    spheres each obstacle's box, then its distance field, does not clear."""

    def __init__(self, fields: Sequence["DistanceField"]):
        self.fields = list(fields)
        O = len(self.fields)
        self.R_inv = np.array([f.R_inv for f in self.fields]).reshape(O, 3, 3)
        self.t = np.array([f.t for f in self.fields]).reshape(O, 1, 3)
        self.lo = np.array([f.box_lo for f in self.fields]).reshape(O, 1, 3)
        self.hi = np.array([f.box_hi for f in self.fields]).reshape(O, 1, 3)

    def near(self, centres: np.ndarray, radii: np.ndarray, margin: float) -> np.ndarray:
        """(obstacles × spheres) booleans: the spheres (rows of ``centres``, ``radii``) that the bounds do not clear
        of each obstacle at ``margin`` (+ :data:`SLACK`). Coal reports no collision of an obstacle, at that margin,
        with a geometry inside a sphere that is not kept."""
        limit = np.asarray(radii, dtype=float) + (float(margin) + SLACK)
        x = np.einsum("oij,omj->omi", self.R_inv, np.asarray(centres, dtype=float)[None] - self.t)   # box frames
        e = np.maximum(np.maximum(self.lo - x, x - self.hi), 0.0)
        near = np.sqrt(np.einsum("omi,omi->om", e, e)) <= limit                                     # the box bound
        for o in np.flatnonzero(near.any(axis=1)).tolist():
            self.fields[o].field_near(np.asarray(centres, dtype=float), limit, near[o])   # then the field's
        return near


class DistanceField:
    """Lower bounds of the distance from points to one obstacle (a coal shape at a world pose): the exact
    distance from the centre of the point's grid cell (edge :data:`CELL`), computed once per cell, minus the
    point's distance to that centre.

    The cells within :data:`REACH` of the shape's box are held in a dense array (``values``, NaN until
    computed; :meth:`grid`, which the compiled single-configuration bound reads), the others in a dictionary;
    both hold the same numbers for the same cell. A box obstacle has no grid (its box bound is exact)."""

    def __init__(self, shape, pose: np.ndarray, cell: float = CELL):
        self.shape, self.cell = shape, float(cell)
        M = np.asarray(pose, dtype=float)
        self.tf = pin.SE3(M[:3, :3].copy(), M[:3, 3].copy())
        self.known: Dict[int, float] = {}  # by the cell's packed integer coordinates (cells outside the grid)
        import coal
        self._coal = coal
        self._point = coal.Sphere(0.0)
        self._at = coal.Transform3s(_EYE, np.zeros(3))   # the point's pose (its translation set per query)
        self._req = coal.DistanceRequest()
        self._res = coal.DistanceResult()
        # the shape's box (its local AABB grown by coal's swept-sphere radius): in its frame, and the grid around it
        shape.computeLocalAABB()
        swept = float(shape.getSweptSphereRadius()) if hasattr(shape, "getSweptSphereRadius") else 0.0
        self.box_lo = np.array(shape.aabb_local.min_, dtype=float) - swept
        self.box_hi = np.array(shape.aabb_local.max_, dtype=float) + swept
        self.R_inv, self.t = M[:3, :3].T.copy(), M[:3, 3].copy()
        corners = np.array([[(self.box_lo, self.box_hi)[b >> i & 1][i] for i in range(3)] for b in range(8)])
        world = corners @ M[:3, :3].T + M[:3, 3]
        lo = np.floor((world.min(axis=0) - REACH) / self.cell).astype(np.int64)
        dim = np.floor((world.max(axis=0) + REACH) / self.cell).astype(np.int64) - lo + 1
        self.is_box = type(shape).__name__ == "Box"   # its box is the shape: the box bound is its exact distance
        if self.is_box or int(np.prod(dim)) > GRID_CELLS_MAX:
            lo, dim = np.zeros(3, np.int64), np.zeros(3, np.int64)
        self.grid_lo, self.grid_dim = lo, dim
        self.values = np.full(int(np.prod(dim)), np.nan)

    def _exact(self, c: np.ndarray) -> float:
        """coal's distance from the point ``c`` (world) to the obstacle."""
        self._res.clear()
        self._at.setTranslation(c)
        return float(self._coal.distance(self._point, self._at, self.shape, self.tf, self._req, self._res))

    def fill(self, flat: np.ndarray) -> np.ndarray:
        """The exact distances of the grid cells ``flat`` (indices into ``values``), computed where unknown (their
        centres in one numpy pass, then coal cell by cell in increasing index order)."""
        v = self.values
        todo = np.unique(flat)
        todo = todo[np.isnan(v[todo])]
        if len(todo):
            dz, dy = int(self.grid_dim[2]), int(self.grid_dim[1])
            centres = (self.grid_lo + np.stack([todo // (dy * dz), todo // dz % dy, todo % dz], axis=1) + 0.5) * self.cell
            for f, c in zip(todo.tolist(), centres):
                v[f] = self._exact(c)
        return v[flat]

    def box_bounds(self, P: np.ndarray) -> np.ndarray:
        """The distance of every point (row) of ``P`` to the shape's box: a lower bound of its distance to the
        shape (the exact distance for a box)."""
        x = (P - self.t) @ self.R_inv.T
        e = np.maximum(np.maximum(self.box_lo - x, x - self.box_hi), 0.0)
        return np.sqrt(np.einsum("ij,ij->i", e, e))

    def field_near(self, P: np.ndarray, limit: np.ndarray, near: np.ndarray) -> np.ndarray:
        """``near`` (booleans per row of ``P``: the box bound does not clear the point at ``limit``) where the field's
        bound does not clear it either (in place; a box obstacle's box bound is exact: unchanged)."""
        if not self.is_box and near.any():
            idx = np.flatnonzero(near)
            near[idx] = self.lower_bounds(P[idx]) <= limit[idx]
        return near

    def lower_bounds(self, P: np.ndarray) -> np.ndarray:
        """A lower bound of the distance to the obstacle of every point (row) of ``P``: the field's (the exact
        distance of the point's cell minus the point's distance to the cell's centre)."""
        h = self.cell
        idx = np.floor(P / h).astype(np.int64)
        centres = (idx + 0.5) * h
        D = np.empty(len(P))
        local = idx - self.grid_lo
        inside = ((local >= 0) & (local < self.grid_dim)).all(axis=1)
        if inside.any():
            li = local[inside]
            D[inside] = self.fill((li[:, 0] * self.grid_dim[1] + li[:, 1]) * self.grid_dim[2] + li[:, 2])
        out = ~inside
        if out.any():
            io, co = idx[out], centres[out]
            code = (io[:, 0] << 42) + ((io[:, 1] & _MASK) << 21) + (io[:, 2] & _MASK)  # |index| < 2²⁰ cells
            keys, first, inverse = np.unique(code, return_index=True, return_inverse=True)
            known = self.known
            Dk = np.empty(len(keys))
            for i, (k, f) in enumerate(zip(keys.tolist(), first.tolist())):
                d = known.get(k)
                if d is None:
                    d = known[k] = self._exact(co[f])
                Dk[i] = d
            D[out] = Dk[inverse.reshape(-1)]
        return D - np.linalg.norm(P - centres, axis=1)


_MASK = (1 << 21) - 1
_EYE = np.eye(3)
_FIELDS: Dict[Tuple[int, bytes], Tuple[object, DistanceField]] = {}


def distance_field(shape, pose: np.ndarray) -> DistanceField:
    """The process's :class:`DistanceField` of ``shape`` at ``pose`` (shared: task shapes are cached objects)."""
    key = (id(shape), np.asarray(pose, dtype=float).tobytes())
    hit = _FIELDS.get(key)
    if hit is not None and hit[0] is shape:
        return hit[1]
    f = DistanceField(shape, pose)
    while _FIELDS and (len(_FIELDS) >= _FIELD_LIMIT
                       or sum(len(g.values) for _, g in _FIELDS.values()) + len(f.values) > GRID_CELLS_KEPT):
        _FIELDS.pop(next(iter(_FIELDS)))
    _FIELDS[key] = (shape, f)   # the shape is held, so its id is not reused while the entry lives
    return f


_BOUNDS: Dict[Tuple[int, ...], Tuple[Tuple[DistanceField, ...], ObstacleBounds]] = {}


def obstacle_bounds(fields: Sequence[DistanceField]) -> ObstacleBounds:
    """The process's :class:`ObstacleBounds` of ``fields`` (the same field objects in the same order: every robot of a
    cell asks for the same ones; :func:`distance_field` keeps them). The fields are held with it, so their ids are
    not reused while the entry lives; at most :data:`_FIELD_LIMIT` sets are kept."""
    key = tuple(id(f) for f in fields)
    hit = _BOUNDS.get(key)
    if hit is not None and len(hit[0]) == len(fields) and all(a is b for a, b in zip(hit[0], fields)):
        return hit[1]
    if len(_BOUNDS) >= _FIELD_LIMIT:
        _BOUNDS.pop(next(iter(_BOUNDS)))
    b = ObstacleBounds(fields)
    _BOUNDS[key] = (tuple(fields), b)
    return b


def pair_ends(gm, n_robot: int) -> Tuple[np.ndarray, np.ndarray]:
    """(first, second): the objects of every collision pair of the geometry model ``gm`` (int64 arrays in pair
    order), a robot object first in a robot–obstacle pair (the robot's objects are those below ``n_robot``). From
    the model's pair map (``collisionPairMapping``: the pair index of (i, j) and of (j, i)), each pair as (smaller,
    larger) object index: the bounds are symmetric; a map that does not hold every pair once falls back to the
    pairs themselves (an obstacle listed first: NotImplementedError)."""
    n = len(gm.collisionPairs)
    M = np.asarray(gm.collisionPairMapping)
    i, j = np.nonzero(M >= 0)
    upper = i < j
    i, j = i[upper], j[upper]
    k = M[i, j].astype(np.int64)
    first, second = np.full(n, -1, np.int64), np.full(n, -1, np.int64)
    if len(k) == n and (n == 0 or (k.min() >= 0 and k.max() < n)):
        first[k], second[k] = i, j
        if (first >= 0).all():
            return first, second
    pairs = [(cp.first, cp.second) for cp in gm.collisionPairs]
    if any(b < n_robot <= a for a, b in pairs):
        raise NotImplementedError("an obstacle listed first in a collision pair")
    return (np.array([a for a, _ in pairs], dtype=np.int64).reshape(n),
            np.array([b for _, b in pairs], dtype=np.int64).reshape(n))


def pair_settings(robot) -> Tuple[np.ndarray, np.ndarray]:
    """(security margins, active flags) of every collision pair of ``robot``: its own record
    (``RobotGeometry.pair_requests``, which does not make the scratch space), else read from its scratch space."""
    own = getattr(robot, "pair_requests", None)
    if own is not None:
        return own()
    gd = robot.geom_data
    n = len(gd.collisionRequests)
    return pair_margins(robot, gd), np.fromiter(gd.activeCollisionPairs, dtype=bool, count=n)


def pair_margins(robot, gd) -> np.ndarray:
    """The security margin of every collision request of ``gd``: the robot's record of the margins it set
    (``RobotGeometry.request_margins``, kept with the scratch space it set them on), else read request by
    request."""
    known = getattr(robot, "request_margins", None)
    m = known(gd) if known is not None else None
    if m is None:
        m = np.array([req.security_margin for req in gd.collisionRequests], dtype=float)
    return m.reshape(len(gd.collisionRequests))


class CollisionCuller:
    """``robot.in_collision`` for many configurations: the pairs a bound clears are not asked (module docstring).
    Built for the robot's current geometry (base pose, obstacles, margins); the robot's own ``data`` and a
    :class:`~robodesign.model.pair_scratch.PairScratch` of the pairs asked (``scratch``) are the scratch space."""

    def __init__(self, robot):
        self.robot = robot
        robot.joint_poses_batch(np.zeros((1, robot.dof)))   # NotImplementedError now for a joint it cannot batch
        gm = robot.geom_model
        objs = gm.geometryObjects
        n_robot = robot.n_collision_geometries
        parent, centres, radii, shapes, rotations, offsets = [], [], [], [], [], []
        for o, _ in zip(objs, range(n_robot)):   # (iterating: one wrapper per object)
            shapes.append(o.geometry)
            c, r = tight_sphere(shapes[-1])
            P = o.placement
            Rp, tp = P.rotation, P.translation
            centres.append(Rp @ c + tp)   # in the parent joint's frame
            radii.append(r)
            parent.append(o.parentJoint)
            rotations.append(Rp)
            offsets.append(tp)
        self.parent = np.array(parent, dtype=int).reshape(n_robot)
        self.shapes = shapes
        self.provable = pair_clearance.worth_proving(shapes)   # (else its pairs are not counted nor proven)
        self._chains: Dict[Tuple[int, int], object] = {}    # pair_clearance.chain's, by joint pair (the proofs')
        self.local = np.array(centres).reshape(-1, 3)
        self.radius = np.array(radii)
        first, second = pair_ends(gm, n_robot)
        margin, active = pair_settings(robot)
        self.active = np.array(active, dtype=np.bool_)   # (its own: proven pairs are switched off in it, in place)
        self.margin, self.first, self.second = margin, first, second
        self.n_pairs = len(first)
        selfp = (first < n_robot) & (second < n_robot)
        self.self_k = np.flatnonzero(selfp)
        self.self_a, self.self_b = first[self.self_k], second[self.self_k]
        self.self_limit = self.radius[self.self_a] + self.radius[self.self_b] + margin[self.self_k] + SLACK
        self.inner_start, self.inner_local, self.inner_radius = placed_inner_spheres(shapes, rotations, offsets)
        self.self_proof = margin[self.self_k] - SLACK   # inner spheres overlapping beyond it prove a self collision
        # robot–obstacle pairs, grouped by obstacle (in the order of each obstacle's first pair)
        self.obstacles: List[Tuple[DistanceField, np.ndarray, np.ndarray, np.ndarray]] = []
        obp = np.flatnonzero((first < n_robot) & (second >= n_robot))
        obs, first_at = np.unique(second[obp], return_index=True)
        for ob in obs[np.argsort(first_at, kind="stable")].tolist():
            o = objs[ob]
            field = distance_field(o.geometry, o.placement.homogeneous)
            kk = obp[second[obp] == ob]
            geo = first[kk]
            self.obstacles.append((field, kk, geo, self.radius[geo] + margin[kk] + SLACK))
        self.narrow = 0   # narrow-phase queries asked (statistics)
        self.until_proof = np.full(self.n_pairs * self.provable, PROVE_AFTER, np.int64)   # asks left (to the proof)
        self._due_k = np.zeros(self.n_pairs + 1, np.int64)   # the pairs whose count the kernel took to 0 (scratch)
        self._deferred = np.zeros(self.n_pairs * self.provable, np.bool_)   # pairs whose proof was put off
        self.proven = 0   # self pairs proven never to collide (:mod:`.pair_clearance`), dropped since
        self._known = _known_proofs(robot, shapes) if self.provable else None
        self._switch_off_known()
        self.scratch = PairScratch(gm, margin)   # coal's scratch space of the pairs asked
        self._one: Optional[tuple] = None    # the compiled single-configuration bound's arrays (on first use)
        self._last_hit = -1                  # the pair collides found colliding last
        self.geom, self.state = gm, geometry_state(robot, margin, active)   # what it was built for (culler_of)

    def _switch_off_known(self) -> None:
        """Switch off the pairs this build's earlier robots proved never to collide (before the first query)."""
        for k, ends in (self._known or {}).items():
            if (int(self.first[k]), int(self.second[k]), float(self.margin[k]) + SLACK, True) == ends and self.active[k]:
                self.active[k] = False
                self.proven += 1

    def restart(self) -> None:
        """Start again as a new culler of the same geometry state would (:func:`culler_of` takes a robot's culler up
        again): the scratch space's GJK guesses set back to a new one's (as ``Robot.set_base_pose`` does to the
        robot's own), no pair found colliding last, the counts to the proofs as at the start, the build's record
        looked up again. It keeps what a new one would make the same (the bounds' arrays, the kernel's arguments, the
        pairs in the scratch space) and the pairs proven never to collide (off in ``active``: coal finds none of
        them colliding at any configuration, so no verdict changes)."""
        fresh_guesses(self.scratch.data)
        self._last_hit, self.narrow = -1, 0
        self.until_proof.fill(PROVE_AFTER)
        self._deferred.fill(False)
        self._known = _known_proofs(self.robot, self.shapes) if self.provable else None
        self._switch_off_known()

    def centres(self, Q: np.ndarray) -> np.ndarray:
        """World centres (N × geometries × 3) of the bounding spheres at every row of ``Q``."""
        J = self.robot.joint_poses_batch(Q)[:, self.parent]          # N × G × 4 × 4
        return np.einsum("ngij,gj->ngi", J[:, :, :3, :3], self.local) + J[:, :, :3, 3]

    def survivors(self, Q: np.ndarray) -> np.ndarray:
        """(N × pairs) booleans: the pairs the bounds do not clear at each row of ``Q`` (active pairs only). The
        compiled bounds of :meth:`in_collision` row by row when the kernel is ready, else numpy's pass over all rows
        (the sphere–sphere, box and field bounds): either keeps every pair coal would find colliding."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        N = len(Q)
        out = np.zeros((N, self.n_pairs), dtype=bool)
        if self.n_pairs == 0 or N == 0:
            return out
        if geometry_kernel.ready():
            args, grids, _ = self._one = self._one or self._kernel_args()
            unknown = np.empty(N * len(args[-1]), np.int64)   # each row's room (every robot–obstacle pair, + 1)
            nu = cast(Any, geometry_kernel.survivors_rows)(Q, *args, out, unknown)   # (numba's stub: one argument)
            if nu:
                self._fill(grids, unknown[:nu])
            return out
        C = self.centres(Q)
        if len(self.self_k):
            d = np.linalg.norm(C[:, self.self_a] - C[:, self.self_b], axis=2)
            out[:, self.self_k] = d <= self.self_limit
        for field, kk, geo, limit in self.obstacles:
            P = C[:, geo].reshape(-1, 3)
            lim = np.tile(limit, N)
            near = field.field_near(P, lim, field.box_bounds(P) <= lim)   # the box bound, then the field's
            out[:, kk] = near.reshape(N, len(geo))
        out &= self.active
        return out

    def collides(self, q: np.ndarray, pairs: Iterable) -> bool:
        """Whether any of ``pairs`` collides at ``q`` (coal, as ``in_collision`` asks it, on ``scratch``; the pair
        that collided last is asked first: consecutive queries tend to share it); the asks counted (:meth:`_count`)."""
        ks = list(pairs) if type(pairs) is list else [int(k) for k in pairs]
        if self.provable:
            self._count(ks)
        return self._ask(q, ks)

    def _ask(self, q: np.ndarray, ks: List[int]) -> bool:
        """:meth:`collides` without counting the asks (``ks``: Python ints, reordered in place)."""
        r, last = self.robot, self._last_hit
        if last >= 0 and last in ks:
            ks.remove(last)
            ks.insert(0, last)
        sc, q = self.scratch, np.asarray(q, dtype=float)
        local, gm, gd = sc.local, sc.model, sc.data
        pin.updateGeometryPlacements(r.kinematic_model, r.data, gm, gd, q)
        compute = pin.computeCollision
        for i, k in enumerate(ks):
            j = local.get(k)
            if j is None:   # a pair not asked before: it and the rest of this query's enter the scratch space
                sc.add(ks[i:])
                j, gd = local[k], sc.data
                pin.updateGeometryPlacements(r.kinematic_model, r.data, gm, gd, q)
            if compute(gm, gd, j):
                self.narrow += i + 1
                self._last_hit = k
                return True
        self.narrow += len(ks)
        return False

    def _count(self, ks: List[int]) -> None:
        """Count down the asks left of the pairs ``ks`` (``until_proof``); a pair whose count reaches 0 is decided by
        :meth:`_due` (a kept verdict of :func:`~robodesign.model.pair_clearance.never_collides`, or its proof; a pair
        proven is switched off in ``active``: the bounds clear it from then on, coal would not find it colliding at
        any configuration). :func:`~robodesign.model.geometry_kernel.survivors_packed` counts in_collision's the same."""
        left = self.until_proof
        for k in ks:
            if left[k] > 0:
                left[k] -= 1
                if left[k] == 0:
                    self._due(k)

    def _due(self, k: int) -> None:
        """Pair ``k``'s count reached 0: at :data:`PROVE_AFTER` asks the verdict kept for it, else (when no earlier
        robot of this build was asked it as often) the proof put off until :data:`PROVE_NEW` asks; then the proof."""
        self._prove(k, now=bool(self._deferred[k]))

    def _prove(self, k: int, now: bool = True) -> None:
        """Switch pair ``k`` off in ``active`` when it is a self pair proven never closer than its margin +
        :data:`SLACK` (not asked again when this build's earlier robots found it not proven: :data:`_PROOFS`). With
        ``now`` False only a kept verdict is taken: without one, the proof is put off (the count set to reach 0 again
        at :data:`PROVE_NEW` asks) unless an earlier robot of the build put it off too."""
        a, b = int(self.first[k]), int(self.second[k])
        limit = float(self.margin[k]) + SLACK
        known = self._known or {}
        if b >= len(self.parent) or not self.active[k] or known.get(k) == (a, b, limit, False):
            return
        objs = self.robot.geom_model.geometryObjects
        a_end, b_end = ((self.shapes[g], np.array(objs[g].placement.homogeneous), int(self.parent[g])) for g in (a, b))
        later = not now and known.get(k) != (a, b, limit, None)
        proven = pair_clearance.never_collides(self.robot.kinematic_model, a_end, b_end, limit, self._chains,
                                               prove=not later)
        if proven is None:   # no verdict kept: proven at PROVE_NEW asks (or by the build's next robot at PROVE_AFTER)
            self._deferred[k] = True
            self.until_proof[k] = PROVE_NEW - PROVE_AFTER
            if self._known is not None:
                self._known[k] = (a, b, limit, None)
            return
        if proven:
            self.active[k] = False
            self.proven += 1
        if self._known is not None and a_end[2] > 0 and b_end[2] > 0:
            self._known[k] = (a, b, limit, proven)

    # -- one configuration: the compiled broad phase (model/geometry_kernel.py) -------------------------------
    def _kernel_args(self) -> tuple:
        """(the kernel's arguments: views into the third, their packed form (``geometry_kernel.pack``); the grids):
        the joint tree, spheres, self pairs, robot–obstacle pairs, every obstacle's box and grid (one gridded
        obstacle's ``values`` themselves, several: a copy of each in one array, :meth:`in_collision` writing the cells
        it fills to both), scratch space, the outputs (surviving pairs, unknown cells: the last two arguments); the
        grids: (fields, their offsets in the grid array, the one gridded field or None, the grid array)."""
        tree, _ = batch_kinematics(self.robot).arrays()   # (the culler keeps scratch space of its own below)
        J = len(tree[0])
        oa, ob, olim, ok = [], [], [], []
        for o, (field, kk, geo, limit) in enumerate(self.obstacles):
            oa += geo.tolist()
            ob += [o] * len(kk)
            olim += limit.tolist()
            ok += kk.tolist()
        fields = [f for f, *_ in self.obstacles]
        gridded = [f for f in fields if len(f.values)]
        offsets = np.cumsum([0] + [len(f.values) for f in fields])[:-1].astype(np.int64)
        if len(gridded) == 1:
            grid = gridded[0].values
            offsets = np.zeros(len(fields), np.int64)
        else:
            grid = np.concatenate([f.values for f in fields]) if fields else np.zeros(0)
        grids = (fields, offsets, gridded[0] if len(gridded) == 1 else None, grid)
        O = len(fields)
        obs = (np.array(oa, np.int64), np.array(ob, np.int64), np.array(olim, float), np.array(ok, np.int64),
               np.array([f.R_inv for f in fields]).reshape(O, 3, 3), np.array([f.t for f in fields]).reshape(O, 3),
               np.array([f.box_lo for f in fields]).reshape(O, 3), np.array([f.box_hi for f in fields]).reshape(O, 3),
               np.array([f.grid_lo for f in fields], np.int64).reshape(O, 3),
               np.array([f.grid_dim for f in fields], np.int64).reshape(O, 3), offsets, CELL, grid)
        assert all(f.cell == CELL for f in fields)
        sp = (self.parent.astype(np.int64), np.ascontiguousarray(self.local, dtype=float),
              self.self_a.astype(np.int64), self.self_b.astype(np.int64), self.self_limit.astype(float),
              self.self_k.astype(np.int64), self.inner_start, self.inner_local, self.inner_radius,
              self.self_proof.astype(float))
        work = (np.zeros((J + 1, 3, 3)), np.zeros((J + 1, 3)), np.zeros((len(self.parent), 3)))
        out, unknown = np.zeros(self.n_pairs + 1, np.int64), np.zeros(len(ok) + 1, np.int64)
        packed, args = geometry_kernel.pack((*tree, *sp, *obs, self.active, *work, out, unknown))
        return args, grids, (*packed, self.until_proof, self._due_k)   # (+ the count of the asks before the proofs)

    def in_collision(self, q: np.ndarray) -> bool:
        """``robot.in_collision(q)`` (the same verdict): coal asked about the pairs the compiled bounds do not clear
        (:func:`robodesign.model.geometry_kernel.survivors`) unless their inner spheres prove one colliding; the grid
        cells it asked about unknown are computed afterwards, for the next queries."""
        args, grids, packed = self._one = self._one or self._kernel_args()
        n, nu, proven, due = cast(Any, geometry_kernel.survivors_packed)(q, *packed, self._last_hit)   # (hull proof: last hit)
        for k in self._due_k[:due].tolist():   # the asks counted (by the kernel), the pairs due decided in their order
            self._due(k)
        if proven >= 0:   # two inner spheres overlap: coal finds that pair colliding
            self._last_hit = proven
        hit = proven >= 0 or (bool(n) and self._ask(q, args[-2][:n].tolist()))
        if nu:
            self._fill(grids, args[-1][:nu].copy())
        return hit

    @staticmethod
    def _fill(grids: tuple, flat: np.ndarray) -> None:
        """Compute the grid cells ``flat`` (indices into the kernel's grid array) in their fields (and the copy)."""
        fields, offsets, direct, grid = grids
        if direct is not None:
            direct.fill(flat)
            return
        for o in np.unique(np.searchsorted(offsets, flat, side="right") - 1).tolist():
            f = fields[o]
            lo = int(offsets[o])
            mine = flat[(flat >= lo) & (flat < lo + len(f.values))]
            grid[mine] = f.fill(mine - lo)

    def first_collision(self, Q: np.ndarray, order: Optional[Sequence[int]] = None) -> int:
        """The first row of ``Q`` in ``order`` (default: row order) that ``robot.in_collision`` finds in
        collision, or -1."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        S = self.survivors(Q)
        for i in (range(len(Q)) if order is None else order):
            ks = np.flatnonzero(S[i])
            if len(ks) and self.collides(Q[i], ks):
                return int(i)
        return -1


_CULLERS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()

#: per robot build (module set, assembly, collision shapes), the self pairs whose two bodies lie beyond the first joint
#: that a proof was tried on: pair → (its two objects, the limit, whether proven never to collide). Such a pair's
#: proof reads only what the build fixes (the shapes, their placements in their joints, the placements and axes of
#: the joints between them), never the base pose, so :func:`~robodesign.model.pair_clearance.never_collides` answers
#: every robot of the build as it answered the first: the build's next cullers switch the proven pairs off when they
#: are made, and do not try the others again.
_PROOFS: Dict[tuple, Tuple[tuple, Dict[int, Tuple[int, int, float, bool]]]] = {}


def _known_proofs(robot, shapes: List[object]) -> Optional[Dict[int, Tuple[int, int, float, bool]]]:
    """The pairs tried in ``robot``'s build (:data:`_PROOFS`; a new empty record for a new build), or None for a
    robot without a module set and assembly."""
    ms, asm = getattr(robot, "module_set", None), getattr(robot, "assembly", None)
    if ms is None or asm is None:
        return None
    key = (id(ms), asm.key(), tuple(map(id, shapes)))
    hit = _PROOFS.get(key)
    if hit is not None and hit[0][0] is ms and all(a is b for a, b in zip(hit[0][1], shapes)):
        return hit[1]
    if len(_PROOFS) >= 4096:
        _PROOFS.clear()
    _PROOFS[key] = ((ms, tuple(shapes)), {})   # (held: their ids are not reused while the entry lives)
    return _PROOFS[key][1]


def culler_of(robot) -> CollisionCuller:
    """The robot's :class:`CollisionCuller`, kept while its geometry stays the same. A
    :class:`~robodesign.model.robot.Robot` keeps it itself (``_culler``, forgotten at every change of its geometry:
    base pose, obstacles, safety margin, scratch space; taken up again, restarted, when the geometry comes back to the
    state it was made for: :func:`~.culler_keep.taken_up`). Another robot object: the same geometry model and data
    objects (held by the entry, so they are the same objects, not a new one at a reused address), base pose, safety
    margin and obstacle placements (what ``set_base_pose``, ``set_obstacles`` and ``move_obstacle`` change)."""
    if hasattr(robot, "_culler"):
        own: Optional[CollisionCuller] = robot._culler
        if own is None:
            own = robot._culler = taken_up(robot, pair_settings) or CollisionCuller(robot)
        return own
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


__all__ = ["CollisionCuller", "DistanceField", "bounding_sphere", "tight_sphere", "culler_of", "distance_field", "ObstacleBounds",
           "SLACK", "CELL", "pair_ends", "pair_margins", "pair_settings"]
