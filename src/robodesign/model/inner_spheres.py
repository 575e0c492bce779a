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

``tests/test_inner_spheres.py`` checks that every sphere lies inside its shape (coal's distances) and that the
culler's verdicts stay coal's.
"""
from __future__ import annotations

from typing import Dict, List, Tuple

import numpy as np

#: the most spheres kept per shape
MAX_SPHERES = 4
#: grid points per side over a convex polytope's box (candidate centres)
GRID = 16

_INNER: Dict[int, Tuple[object, np.ndarray, np.ndarray]] = {}   # id(shape) → (shape, centres, radii)


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


def placed_inner_spheres(shapes, rotations, offsets) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(start, centres, radii) of the inner spheres of ``shapes`` placed at ``rotations[g]``, ``offsets[g]`` in their
    joints' frames, in those frames: geometry ``g``'s are rows ``start[g]`` to ``start[g + 1]``."""
    R = np.array(rotations, dtype=float).reshape(-1, 3, 3)
    t = np.array(offsets, dtype=float).reshape(-1, 3)
    spheres = [inner_spheres(s) for s in shapes]
    counts = np.array([len(r) for _, r in spheres], dtype=np.int64)
    start = np.zeros(len(spheres) + 1, dtype=np.int64)
    np.cumsum(counts, out=start[1:])
    owner = np.repeat(np.arange(len(spheres)), counts)
    C = np.concatenate([c for c, _ in spheres] + [np.zeros((0, 3))])
    centres = np.einsum("mij,mj->mi", R[owner], C) + t[owner]
    return start, np.ascontiguousarray(centres), np.concatenate([r for _, r in spheres] + [np.zeros(0)])


__all__ = ["inner_spheres", "placed_inner_spheres", "MAX_SPHERES", "GRID"]
