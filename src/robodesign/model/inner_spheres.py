"""Spheres inside a robot's collision shapes: a cheap proof that a self pair collides.

Two shapes whose inner spheres overlap by more than :data:`~robodesign.model.collision_cull.SLACK` beyond the pair's
security margin (centres closer than the radii + margin − slack) penetrate each other deeper than coal's tolerances
(~1e-6 m), so coal's collision test reports them colliding. :class:`~.collision_cull.CollisionCuller` answers such a
configuration without asking coal (issue 25: the IK stage's converged solutions that collide, most of them between
an arm's last modules).

The spheres of a shape (in its own frame; coal's swept-sphere radius added to each radius):

* a sphere: itself;
* a cylinder, capsule or box: up to :data:`MAX_SPHERES` spheres on its longest axis, each as large as the shape's
  section (the radius; the box's smaller half sides) and within its length;
* a convex polytope: up to :data:`MAX_SPHERES` of the largest spheres centred on a grid over its box
  (:data:`GRID` points a side) inside the convex hull of its points, the radius the distance to the nearest face
  plane of that hull (scipy's), each new one not mostly inside one taken before;
* any other shape: none.

A convex polytope's hull (:func:`hull`: the edges and face planes of the convex hull of its points, scipy's) proves
a pair colliding too: a point of an edge of one shape inside the other's hull deeper than |margin − slack| (every
face plane's ``n·x + d`` below −|margin − slack|) is a point of both whose depth bounds the penetration from below,
so the pair's distance is below margin − slack; the second's swept-sphere radius only adds to it. On the PTP_3 arm
it proves 392 of 393 collisions coal finds between 5.5.c0.2 and 12.12.c0.3 (penetrating 0.01–5 mm; a vertex inside:
163), which no inner sphere proves.

``tests/test_inner_spheres.py`` checks that every sphere lies inside its shape (coal's distances) and that the
culler's verdicts stay coal's; ``tests/test_hull_proofs.py`` that every edge's ends lie on its shape and every plane
beyond it.
"""
from __future__ import annotations

from typing import Dict, List, Tuple

import numpy as np

#: the most spheres kept per shape
MAX_SPHERES = 4
#: grid points per side over a convex polytope's box (candidate centres)
GRID = 16

_INNER: Dict[int, Tuple[object, np.ndarray, np.ndarray]] = {}   # id(shape) → (shape, centres, radii)
_HULL: Dict[int, Tuple[object, np.ndarray, np.ndarray]] = {}    # id(shape) → (shape, edges' ends, planes)
_PLACED: Dict[tuple, Tuple[tuple, Tuple[np.ndarray, np.ndarray, np.ndarray]]] = {}   # placed_inner_spheres' results
_PIECES: Dict[tuple, Tuple[object, Tuple[np.ndarray, ...]]] = {}   # placed_piece's: (id(shape), R, t bytes) → pieces


def _on_axis(radius: float, half: float, axis: int, rounded: bool) -> List[Tuple[np.ndarray, float]]:
    """Spheres of radius ``radius`` (at most ``half``, unless ``rounded``: a capsule's caps) on one axis, their
    centres spread over the part of [-half, half] that keeps them inside."""
    rho = radius if rounded else min(radius, half)
    reach = half if rounded else half - rho
    n = 1 if reach <= 0.0 else min(MAX_SPHERES, int(np.ceil(reach / rho)) + 1)
    out = []
    for z in np.linspace(-reach, reach, n) if n > 1 else [0.0]:
        c = np.zeros(3)
        c[axis] = z
        out.append((c, rho))
    return out


def _in_polytope(points: np.ndarray) -> List[Tuple[np.ndarray, float]]:
    """The largest spheres centred on a grid inside the convex hull of ``points`` (module docstring)."""
    from scipy.spatial import ConvexHull  # type: ignore[import-untyped]
    try:
        eq = ConvexHull(points).equations          # rows (n, d): n·x + d ≤ 0 inside, n of unit length
    except Exception:   # flat or degenerate: no volume, no sphere
        return []
    lo, hi = points.min(axis=0), points.max(axis=0)
    axes = [np.linspace(lo[i], hi[i], GRID) for i in range(3)]
    C = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    r = -(C @ eq[:, :3].T + eq[:, 3]).max(axis=1)
    out: List[Tuple[np.ndarray, float]] = []
    for i in np.argsort(-r, kind="stable").tolist():
        if r[i] <= 0.0 or len(out) >= MAX_SPHERES:
            break
        if all(np.linalg.norm(C[i] - c) + 0.5 * r[i] > rc for c, rc in out):
            out.append((C[i].copy(), float(r[i])))
    return out


def _inner_spheres(shape) -> Tuple[np.ndarray, np.ndarray]:
    """(centres k × 3 in the shape's frame, radii k) of ``shape``'s inner spheres (module docstring)."""
    kind = type(shape).__name__
    if kind == "Sphere":
        spheres = [(np.zeros(3), float(shape.radius))]
    elif kind in ("Cylinder", "Capsule"):
        spheres = _on_axis(float(shape.radius), float(shape.halfLength), 2, kind == "Capsule")
    elif kind == "Box":
        half = np.asarray(shape.halfSide, dtype=float).reshape(3)
        axis = int(np.argmax(half))
        spheres = _on_axis(float(np.delete(half, axis).min()), float(half[axis]), axis, False)
    elif kind.startswith("Convex") and shape.num_points >= 4:
        spheres = _in_polytope(np.asarray(shape.points(), dtype=float).reshape(-1, 3))
    else:
        spheres = []
    swept = float(shape.getSweptSphereRadius()) if hasattr(shape, "getSweptSphereRadius") else 0.0
    centres = np.array([c for c, _ in spheres], dtype=float).reshape(-1, 3)
    return centres, np.array([r + swept for _, r in spheres], dtype=float)


def inner_spheres(shape) -> Tuple[np.ndarray, np.ndarray]:
    """:func:`_inner_spheres` of a robot shape, kept per shape object (robots share their coal shapes, which are
    never changed)."""
    hit = _INNER.get(id(shape))
    if hit is None or hit[0] is not shape:
        hit = _INNER[id(shape)] = (shape, *_inner_spheres(shape))   # (the shape is held: its id is not reused)
    return hit[1], hit[2]


def _hull(shape) -> Tuple[np.ndarray, np.ndarray]:
    """(the ends of the hull's edges, 2e × 3: rows 2i and 2i + 1 are edge i's; its face planes f × 4: n (unit), d with
    n·x + d ≤ 0 inside) of a convex polytope, in its own frame; none for another shape or a flat one. The edges are
    the sides of scipy's triangles (a face's diagonals too: segments of the shape all the same)."""
    if not (type(shape).__name__.startswith("Convex") and shape.num_points >= 4):
        return np.zeros((0, 3)), np.zeros((0, 4))
    from scipy.spatial import ConvexHull  # type: ignore[import-untyped]
    points = np.asarray(shape.points(), dtype=float).reshape(-1, 3)
    try:
        hull_ = ConvexHull(points)
    except Exception:   # flat or degenerate: no volume
        return np.zeros((0, 3)), np.zeros((0, 4))
    edges = sorted({(min(a, b), max(a, b)) for tri in hull_.simplices.tolist() for a, b in zip(tri, tri[1:] + tri[:1])})
    ends = points[np.array(edges, dtype=np.int64).reshape(-1)].reshape(-1, 3)
    return ends, np.asarray(hull_.equations, dtype=float).reshape(-1, 4)


def hull(shape) -> Tuple[np.ndarray, np.ndarray]:
    """:func:`_hull` of a robot shape, kept per shape object (as :func:`inner_spheres`)."""
    hit = _HULL.get(id(shape))
    if hit is None or hit[0] is not shape:
        hit = _HULL[id(shape)] = (shape, *_hull(shape))
    return hit[1], hit[2]


def placed_inner_spheres(shapes, rotations, offsets) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_placed` of ``shapes`` at ``rotations``, ``offsets``, kept per shapes and placements (a build's robots
    share them; the hulls' edges make a few thousand rows, ~0.4 ms to place). The arrays are shared: not to be
    written to."""
    R = np.array(rotations, dtype=float).reshape(-1, 3, 3)
    t = np.array(offsets, dtype=float).reshape(-1, 3)
    key = (tuple(map(id, shapes)), R.tobytes(), t.tobytes())
    hit = _PLACED.get(key)
    if hit is None or any(a is not b for a, b in zip(hit[0], shapes)):
        if len(_PLACED) >= 256:   # (a few thousand rows each: at most a few tens of MB)
            _PLACED.clear()
        arrays = _placed(shapes, R, t)
        for a in arrays:
            a.setflags(write=False)
        hit = _PLACED[key] = (tuple(shapes), arrays)   # (the shapes held: their ids not reused)
    return hit[1]


def _placed(shapes, R: np.ndarray, t: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(start, rows, values): the inner spheres, hull edges and hull planes of ``shapes`` placed at
    ``R[g]``, ``t[g]`` in their joints' frames, in those frames, in three blocks. With G shapes,
    geometry ``g``'s spheres are rows ``start[g]`` to ``start[g + 1]`` (``rows``: centres, ``values``: radii), its
    hull's edges' ends rows ``start[G + 1 + g]`` to ``start[G + 2 + g]`` (in pairs; ``values``: 0) and its planes rows
    ``start[2G + 2 + g]`` to ``start[2G + 3 + g]`` (``rows``: unit normal n, ``values``: d; a point x of the joint
    frame lies inside when n·x + d ≤ 0). Each geometry's rows are :func:`placed_piece`'s."""
    G = len(R)
    pieces = [placed_piece(s, R[g], t[g]) for g, s in enumerate(shapes)]
    parts = [p[b] for b in range(3) for p in pieces]   # 3 blocks of G: spheres, edges' ends, normals
    counts = np.array([len(a) for a in parts], dtype=np.int64)
    start = np.zeros(3 * G + 3, dtype=np.int64)
    ends = np.cumsum(counts)
    for b in range(3):   # each block's starts: its first row, then each geometry's end
        start[b * (G + 1)] = ends[b * G - 1] if b and G else 0
        start[b * (G + 1) + 1:(b + 1) * (G + 1)] = ends[b * G:(b + 1) * G]
    rows = np.concatenate(parts + [np.zeros((0, 3))])
    values = np.concatenate([p[3] for p in pieces] + [np.zeros(start[2 * (G + 1)] - start[G + 1])]
                            + [p[4] for p in pieces] + [np.zeros(0)])
    return start, np.ascontiguousarray(rows), values


def placed_piece(shape, R: np.ndarray, t: np.ndarray) -> Tuple[np.ndarray, ...]:
    """(sphere centres, edges' ends, plane normals, sphere radii, plane offsets d) of ``shape``'s inner spheres and
    hull at rotation ``R``, offset ``t`` in its joint's frame (points turned and moved, normals turned, d − n·t),
    kept per shape object and the bytes of R and t (a module's shapes sit at the same placements in every build).
    Read-only arrays."""
    R, t = np.asarray(R, dtype=float).reshape(3, 3), np.asarray(t, dtype=float).reshape(3)
    key = (id(shape), R.tobytes(), t.tobytes())
    hit = _PIECES.get(key)
    if hit is None or hit[0] is not shape:
        if len(_PIECES) >= 4096:
            _PIECES.clear()
        hit = _PIECES[key] = (shape, _piece(shape, R, t))   # (the shape held: its id not reused)
    return hit[1]


def _piece(shape, R: np.ndarray, t: np.ndarray) -> Tuple[np.ndarray, ...]:
    """:func:`placed_piece`'s arrays, made: all rows turned by one einsum, the points then moved by t."""
    (c, r), (v, p) = inner_spheres(shape), hull(shape)
    n_pts = len(c) + len(v)
    local = np.concatenate([c, v, p[:, :3]])
    rows = np.einsum("mij,mj->mi", np.repeat(R[None], len(local), axis=0), local)
    rows[:n_pts] += t
    normals = rows[n_pts:]
    out = (rows[:len(c)], rows[len(c):n_pts], normals, r, p[:, 3] - (normals * t).sum(axis=1))
    rows.setflags(write=False)
    out[4].setflags(write=False)
    return out


__all__ = ["hull", "inner_spheres", "placed_inner_spheres", "MAX_SPHERES", "GRID"]
