"""Self pairs that can never collide, proven once per kind of pair (:func:`never_collides`).

Two robot bodies a (on joint i) and b (on joint j, i an ancestor of j or j itself) keep a relative pose that depends
only on the joints on the path from i to j (the *chain*). When every chain joint is revolute (about x, y, z or an
unaligned axis), that pose is 2π-periodic in each joint angle, so the box [−π, π]^k of the k chain angles holds every
pose the pair can take, at any configuration, inside the joint limits or not. :func:`chain_clears` proves a lower
bound of the pair's distance over that whole box:

* cells of the box, each asked of coal at its centre c (``coal.distance`` of the two shapes at their relative
  pose there);
* turning chain joint m by δ moves b relative to a by at most ``arm_m · |δ|`` (``arm_m``: how far a point of b, or
  of a, can lie from m's axis: :func:`chain_arms`), so over the cell the pair is at least
  ``d(c) − Σ_m halfwidth_m · arm_m`` apart (from c to any point of the cell one joint at a time);
* a cell whose bound is not above the limit is split in two along its largest term, until every cell clears (the
  pair is proven), or a centre's distance is not above the limit, or the budget of distance queries is spent (not
  proven).

A proven pair is farther apart than its security margin + the culler's slack in every configuration, so coal's
collision test of it is False at every configuration: :class:`~robodesign.model.collision_cull.CollisionCuller`
drops it like an inactive pair. The verdict depends only on the two shapes, their placements in their joints, each
chain joint's type, axis and placement, and the limit; it is kept per process by exactly those (the robots of a
search and the evaluations of one arm share their module chains).
"""
from __future__ import annotations

from typing import Dict, List, Optional, Tuple

import numpy as np

#: distance queries one proof may ask before it gives up (the pair is then asked of coal as before)
BUDGET = 4000
#: cells per chain angle the proof starts from
START = 6
#: chain joints the proof takes on (more: not tried)
MAX_CHAIN = 3
#: decimals the relative placements are rounded to (:func:`in_a_frame`)
DIGITS = 9
#: metres proven on top of the limit: covers the rounding (≤ 4 factors × (1.5e-9 · REACH_MAX + 1e-9) ≈ 6e-7 m)
ALLOWANCE = 1e-6
#: the farthest (m) a point of b may lie from a's frame for the allowance to cover the rounding (else: not tried)
REACH_MAX = 100.0
_AXES = {"JointModelRX": (1.0, 0.0, 0.0), "JointModelRY": (0.0, 1.0, 0.0), "JointModelRZ": (0.0, 0.0, 1.0)}
#: verdicts kept (the oldest is dropped beyond)
KEPT = 1 << 16
_KNOWN: Dict[tuple, Tuple[tuple, bool]] = {}   # key → (the shapes, held so their ids are not reused; verdict)
_FRAMED: Dict[tuple, Tuple[bytes, tuple]] = {}   # :func:`framed`'s: by the raw placements' bytes
_EYE4 = np.eye(4)   # (:func:`chain_poses`' identity stacks are filled from it)


def chain(model, i: int, j: int) -> Optional[List[Tuple[np.ndarray, np.ndarray]]]:
    """The joints on the path from joint i (exclusive) to its descendant j (inclusive) as (placement 4×4 in the
    parent joint's frame, unit axis), root side first; None when i is not j or an ancestor of j, a chain joint is
    not revolute, or the chain is longer than :data:`MAX_CHAIN`."""
    path: List[int] = []
    m = j
    while m != i:
        if m == 0 or len(path) == MAX_CHAIN:
            return None
        path.append(m)
        m = int(model.parents[m])
    links = []
    for m in reversed(path):
        jm = model.joints[m]
        name = jm.shortname()
        if name in _AXES:
            axis = np.array(_AXES[name])
        elif name == "JointModelRevoluteUnaligned":
            axis = np.array(jm.extract().axis, dtype=float)
        else:
            return None
        links.append((np.array(model.jointPlacements[m].homogeneous), axis / np.linalg.norm(axis)))
    return links


def _far(points: np.ndarray, origin: np.ndarray, axis: Optional[np.ndarray]) -> float:
    """The largest distance of the rows of ``points`` from the line through ``origin`` along the unit ``axis``
    (None: from the point ``origin``)."""
    v = np.asarray(points, dtype=float).reshape(-1, 3) - origin
    if axis is not None:
        v = v - np.outer(v @ axis, axis)
    return float(np.sqrt(np.einsum("ij,ij->i", v, v).max()))


def _swept(shape) -> float:
    """coal's swept-sphere radius of ``shape`` (0 for a shape without one)."""
    return float(shape.getSweptSphereRadius()) if hasattr(shape, "getSweptSphereRadius") else 0.0


def reach(shape, P: np.ndarray, origin: np.ndarray, axis: Optional[np.ndarray]) -> float:
    """An upper bound of the distance of every point of ``shape`` (posed by the 4×4 ``P``) from the line through
    ``origin`` along the unit ``axis`` (None: from the point): a convex polytope's or a box's farthest vertex; a
    sphere's centre, a cylinder's, cone's or capsule's two end centres (on its z axis) plus the radius; any other
    shape its local AABB's corners; plus coal's swept-sphere radius (the largest distance of a convex set from a
    line or point is at its extreme points)."""
    kind, R, t = type(shape).__name__, P[:3, :3], P[:3, 3]
    if kind == "Sphere":
        return _far(t, origin, axis) + float(shape.radius) + _swept(shape)
    if kind in ("Cylinder", "Cone", "Capsule"):
        ends = t + np.outer([-1.0, 1.0], R[:, 2] * float(shape.halfLength))
        return _far(ends, origin, axis) + float(shape.radius) + _swept(shape)
    if kind.startswith("Convex") and shape.num_points:
        local = np.asarray(shape.points(), dtype=float).reshape(-1, 3)
    else:
        shape.computeLocalAABB()
        lo, hi = np.asarray(shape.aabb_local.min_, dtype=float), np.asarray(shape.aabb_local.max_, dtype=float)
        local = np.array([[(lo, hi)[b >> n & 1][n] for n in range(3)] for b in range(8)])
    return _far(local @ R.T + t, origin, axis) + _swept(shape)


def arm(shape, P: np.ndarray, origin: np.ndarray, axis: np.ndarray) -> float:
    """How far turning by one radian about the line (``origin``, unit ``axis``) moves ``shape`` (posed by ``P``) as
    a set: its :func:`reach` from the line, or less for a body of revolution (a sphere; a cylinder, cone or capsule
    about its z axis u'): turned about its own axis it is the same set, so it moves by at most the distance e of its
    centre from the line plus |u − u'|·ρ (ρ: its farthest point from its centre), per radian."""
    kind, R, t = type(shape).__name__, P[:3, :3], P[:3, 3]
    far = reach(shape, P, origin, axis)
    e = _far(t, origin, axis)
    if kind == "Sphere":
        return min(far, e)
    if kind in ("Cylinder", "Cone", "Capsule"):
        u = R[:, 2] if R[:, 2] @ axis >= 0 else -R[:, 2]
        h, r = float(shape.halfLength), float(shape.radius)
        rho = (h + r if kind == "Capsule" else float(np.hypot(h, r))) + _swept(shape)
        return min(far, e + float(np.linalg.norm(axis - u)) * rho)
    return far


def chain_arms(links, obj_a: Tuple[object, np.ndarray], obj_b: Tuple[object, np.ndarray]) -> np.ndarray:
    """Per chain joint m, a bound of how far turning m by one radian moves b relative to a, at any angles of the
    chain: the smaller of b's and a's :func:`arm` about m's axis (``obj_a``, ``obj_b``: (shape, 4×4 placement in
    its joint's frame)). A body next to m (b on m itself, a on m's parent) is measured against the axis line itself;
    otherwise (the chain's angles in between unknown) from m's origin, through the norms of the chain's placements
    in between (:func:`reach` from a point)."""
    k = len(links)
    steps = [float(np.linalg.norm(M[:3, 3])) for M, _ in links]
    out = np.empty(k)
    zero = np.zeros(3)
    for m, (M, axis) in enumerate(links):
        if m == k - 1:
            rb = arm(obj_b[0], obj_b[1], zero, axis)
        else:
            rb = sum(steps[m + 1:]) + reach(obj_b[0], obj_b[1], zero, None)
        if m == 0:
            ra = arm(obj_a[0], obj_a[1], M[:3, 3], M[:3, :3] @ axis)
        else:
            ra = sum(steps[:m + 1]) + reach(obj_a[0], obj_a[1], zero, None)
        out[m] = min(rb, ra)
    return out


def chain_poses(links, angles: np.ndarray) -> np.ndarray:
    """(n × 4 × 4) the poses of the last chain joint's frame in joint i's frame at the rows of chain ``angles``
    (n × k; a rotation of θ about the unit axis u is Rodrigues' I + sin θ K + (1 − cos θ) K², K = [u]×)."""
    n = len(angles)
    T = np.empty((n, 4, 4))
    T[:] = _EYE4
    for (M, axis), a in zip(links, angles.T):
        x, y, z = axis
        K = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
        X = np.empty((n, 4, 4))
        X[:] = _EYE4
        X[:, :3, :3] += np.sin(a)[:, None, None] * K + (1.0 - np.cos(a))[:, None, None] * (K @ K)
        T = T @ M @ X
    return T


class _PairDistance:
    """coal's distances of shape a (fixed, at ``Pa`` in joint i's frame) and shape b (at ``Pb`` in joint j's frame)
    at rows of chain angles, by coal's distance functor of the two shapes (``coal.ComputeDistance``: the function
    ``coal.distance`` looks up at every call, looked up once; the same numbers); ``asked``: the distances computed."""

    def __init__(self, shape_a, Pa: np.ndarray, shape_b, Pb: np.ndarray, links):
        import coal
        self.links = links
        self.a, self.b, self.Pb = shape_a, shape_b, Pb
        self.Ta = coal.Transform3s(Pa[:3, :3].copy(), Pa[:3, 3].copy())
        self.Tb = coal.Transform3s()   # b's pose, set per row
        self._distance = coal.ComputeDistance(shape_a, shape_b)
        self.req, self.res = coal.DistanceRequest(), coal.DistanceResult()
        self.asked = 0

    def __call__(self, angles: np.ndarray, stop: float = -np.inf) -> np.ndarray:
        """The distances at the rows of ``angles`` in order, up to the first one not above ``stop`` (the rows
        after it are not asked); b's pose set row by row in one ``Transform3s`` (the same numbers as a new one
        made of each row's rotation and translation)."""
        T = chain_poses(self.links, angles) @ self.Pb
        R, t = np.ascontiguousarray(T[:, :3, :3]), np.ascontiguousarray(T[:, :3, 3])
        Ta, Tb, req, res = self.Ta, self.Tb, self.req, self.res
        distance, clear, turn, move = self._distance, res.clear, Tb.setRotation, Tb.setTranslation
        out = []
        for Rn, tn in zip(R, t):
            turn(Rn)
            move(tn)
            clear()
            d = distance(Ta, Tb, req, res)
            out.append(d)
            if d <= stop:
                break
        self.asked += len(out)
        return np.array(out, dtype=float)


def chain_clears(distance, arms: np.ndarray, limit: float, budget: int = BUDGET) -> bool:
    """Whether ``distance`` (rows of chain angles, a stop → coal's distances in row order, up to the first one not
    above the stop) is above ``limit`` over the whole box [−π, π]^k of the chain angles, by the cells of the module
    docstring with ``arms`` (per chain angle) as the Lipschitz bounds: all cells of a round asked at once (up to
    the first centre not above ``limit``: the pair is then not proven, whatever the rest), the failing ones split
    for the next round."""
    k = len(arms)
    h = np.pi / START
    axes = [-np.pi + h * (2 * np.arange(START) + 1)] * k
    C = np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=1).reshape(-1, k)
    HW = np.full(C.shape, h)
    asked = 0
    while len(C):
        if asked + len(C) > budget:
            return False
        d = distance(C, limit)
        asked += len(C)
        if len(d) < len(C) or (d <= limit).any():
            return False
        terms = HW * arms
        open_ = d - terms.sum(axis=1) <= limit
        C, HW, terms = C[open_], HW[open_], terms[open_]
        m = np.argmax(terms, axis=1) if k else np.zeros(0, np.int64)
        rows = np.arange(len(C))
        HW = HW.copy()
        HW[rows, m] *= 0.5
        lo, hi = C.copy(), C.copy()
        lo[rows, m] -= HW[rows, m]
        hi[rows, m] += HW[rows, m]
        C, HW = np.vstack([lo, hi]), np.vstack([HW, HW])
    return True


def worth_proving(shapes) -> bool:
    """Whether the self pairs of a robot of these shapes are worth proofs: it has a convex mesh (coal's ``Convex``,
    a collision test of some 2–5 µs; the IMPROV modules). A robot of primitives only (the built-in arms' cylinders
    and spheres, each test about a microsecond) is not: the proofs' distance queries cost the genetic search on
    the built-in arms more than the tests they saved (as for the planner's certificates:
    ``robodesign.solvers.pair_certificates``)."""
    return any(type(s).__name__.startswith("Convex") for s in shapes)


def in_a_frame(Pa: np.ndarray, links, Pb: np.ndarray):
    """(links, Pb) of the pair seen from body a (its shape's frame: a at the identity), rounded to :data:`DIGITS`
    decimals: the first chain placement (or, without a chain, b's placement) premultiplied by ``Pa``⁻¹, the others
    as they are. The same for every base pose of a pair on the base (up to the rounding)."""
    inv = np.eye(4)
    inv[:3, :3] = Pa[:3, :3].T
    inv[:3, 3] = -Pa[:3, :3].T @ Pa[:3, 3]
    if not links:
        return [], np.round(inv @ Pb, DIGITS)
    first = [(inv @ links[0][0], links[0][1])] + list(links[1:])
    return [(np.round(M, DIGITS), axis) for M, axis in first], np.round(Pb, DIGITS)


def framed(Pa: np.ndarray, links, Pb: np.ndarray) -> Tuple[bytes, tuple]:
    """The bytes of :func:`in_a_frame`'s ``Pb`` and of its links' (placement, axis) pairs: the pair's part of the
    verdicts' key, kept per the bytes of ``Pa``, ``Pb`` and the links (a function of those only; the pairs of a
    module chain recur across the robots of a search)."""
    raw = (Pa.tobytes(), Pb.tobytes(), tuple((M.tobytes(), axis.tobytes()) for M, axis in links))
    hit = _FRAMED.get(raw)
    if hit is None:
        f_links, f_Pb = in_a_frame(Pa, links, Pb)
        if len(_FRAMED) >= KEPT:
            _FRAMED.pop(next(iter(_FRAMED)))
        hit = _FRAMED[raw] = (f_Pb.tobytes(), tuple((M.tobytes(), axis.tobytes()) for M, axis in f_links))
    return hit


def never_collides(model, end_a: Tuple[object, np.ndarray, int], end_b: Tuple[object, np.ndarray, int], limit: float,
                   chains: Optional[Dict[Tuple[int, int], object]] = None, prove: bool = True) -> Optional[bool]:
    """Whether the self pair of a robot ``model`` whose ends are ``end_a``, ``end_b`` (each: coal shape, 4×4
    placement in its parent joint's frame, parent joint) is proven farther apart than ``limit`` at every
    configuration (module docstring). ``chains``: the caller's memo of :func:`chain` for this model.

    The proof is made on the pair as :func:`in_a_frame` gives it, at ``limit`` + :data:`ALLOWANCE`, and kept per
    process by exactly that (the two shapes, the rounded placements, the axes, the limit): a robot's own relative
    poses differ from the rounded ones by at most 10^−DIGITS per entry, which moves no point within
    :data:`REACH_MAX` of a by more than the allowance. A pair with a triangle mesh is not tried (its distance costs
    more than its collision tests). With ``prove`` False only a kept verdict (or a pair that is not tried) is answered,
    None where a proof would be needed."""
    if any(type(e[0]).__name__.startswith("BVH") for e in (end_a, end_b)):
        return False
    memo: Dict[Tuple[int, int], object] = {} if chains is None else chains
    for i, j in ((end_a[2], end_b[2]), (end_b[2], end_a[2])):
        if (i, j) not in memo:
            memo[i, j] = chain(model, i, j)
    links = memo[end_a[2], end_b[2]]
    if links is None:
        links = memo[end_b[2], end_a[2]]
        if links is None:
            return False
        end_a, end_b = end_b, end_a
    shapes = (end_a[0], end_b[0])
    Pb_frame, links_frame = framed(end_a[1], links, end_b[1])
    key = (id(shapes[0]), id(shapes[1]), Pb_frame, float(limit), links_frame)
    hit = _KNOWN.get(key)
    if hit is not None and hit[0][0] is shapes[0] and hit[0][1] is shapes[1]:
        return hit[1]
    if not prove:
        return None
    links, Pb = in_a_frame(end_a[1], links, end_b[1])
    eye = np.eye(4)
    far = sum(float(np.linalg.norm(M[:3, 3])) for M, _ in links) + reach(shapes[1], Pb, np.zeros(3), None)
    proven = far <= REACH_MAX and chain_clears(_PairDistance(shapes[0], eye, shapes[1], Pb, links),
                                               chain_arms(links, (shapes[0], eye), (shapes[1], Pb)),
                                               float(limit) + ALLOWANCE)
    if len(_KNOWN) >= KEPT:
        _KNOWN.pop(next(iter(_KNOWN)))
    _KNOWN[key] = (shapes, proven)
    return proven


__all__ = ["ALLOWANCE", "BUDGET", "DIGITS", "KEPT", "MAX_CHAIN", "REACH_MAX", "START", "arm", "chain", "chain_arms",
           "chain_clears", "chain_poses", "framed", "in_a_frame", "never_collides", "reach",
           "worth_proving"]
