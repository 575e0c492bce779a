"""A quick screen in front of :meth:`robodesign.model.collision_cull.ObstacleBounds.near` for the base stage: whether
every sphere lies clear of every obstacle's box by more than its limit, tested in Python floats against each box's
world AABB. In an evaluation numpy's code is cold (``near`` makes a dozen numpy calls), and most robots' bases stand
far from every obstacle; where the screen clears everything, ``near`` would answer that no pair is near.

Why a cleared pair is one ``near`` clears: ``near`` measures a sphere centre c in the box's frame, x = R_inv·(c − t),
against the box [lo, hi] there. The box's world points t + R_inv⁻¹·y (y in [lo, hi]) lie in the AABB of its corners,
and ‖R_inv·v‖ ≥ s·‖v‖ with s the smallest singular value of R_inv (a rotation read from a file need not be exactly
orthonormal): so that distance is at least s times the centre's distance to the AABB. The screen asks it to exceed
the limit by :data:`SLACK_M` on top, far above the rounding of either computation.
"""
from __future__ import annotations

import math
from typing import Dict, List, Optional, Tuple

import numpy as np

#: metres by which the screen must clear a sphere (grown AABBs, and the test's own margin)
SLACK_M = 1e-6
_BOXES: Dict[int, Tuple[object, List[tuple]]] = {}   # id(ObstacleBounds) → (it, its boxes: box_aabb's)
_KEPT = 64


def box_aabb(R_inv: np.ndarray, t: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple:
    """(lower corner, upper corner, s) of a box [lo, hi] in the frame x = R_inv·(c − t): the world AABB of its corners
    grown by :data:`SLACK_M`, and s, R_inv's smallest singular value less 1e-9 of it. A singular or non-finite R_inv
    gets s = NaN, which clears nothing."""
    if not np.isfinite(R_inv).all() or abs(np.linalg.det(R_inv)) < 1e-6:
        return (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, float("nan"))
    corners = np.array([[(lo, hi)[b >> i & 1][i] for i in range(3)] for b in range(8)])
    world = corners @ np.linalg.inv(R_inv).T + t
    s = float(np.linalg.svd(R_inv, compute_uv=False)[-1]) * (1.0 - 1e-9)
    return (*(world.min(axis=0) - SLACK_M).tolist(), *(world.max(axis=0) + SLACK_M).tolist(), s)


def boxes_of(bounds) -> List[tuple]:
    """:func:`box_aabb` of each obstacle of an ``ObstacleBounds`` (made once per bounds object, which the process
    keeps per set of obstacles)."""
    hit = _BOXES.get(id(bounds))
    if hit is None or hit[0] is not bounds:   # (the object is held: its id is not reused while the entry lives)
        if len(_BOXES) >= _KEPT:
            _BOXES.clear()
        boxes = [box_aabb(bounds.R_inv[o], bounds.t[o, 0], bounds.lo[o, 0], bounds.hi[o, 0])
                 for o in range(len(bounds.fields))]
        hit = _BOXES[id(bounds)] = (bounds, boxes)
    return hit[1]


def all_clear(boxes: List[tuple], centres: np.ndarray, limit: np.ndarray) -> bool:
    """Whether every sphere (rows of ``centres``; ``limit``: the distance each must keep) lies farther than its limit
    from every box (:func:`box_aabb`). A NaN fails the test; an infinite centre passes it, and ``near``'s bound (an
    infinite or NaN distance) clears it too. Box by box, the spheres are first tested together (:func:`_group`), then
    one by one where that does not clear them."""
    rows = list(zip(centres.tolist(), limit.tolist()))
    group = _group(rows)
    for box in boxes:
        if group is not None and _clear(box, *group):
            continue
        x0, y0, z0, x1, y1, z1, s = box
        for (x, y, z), lim in rows:
            dx = x0 - x if x < x0 else (x - x1 if x > x1 else 0.0)
            dy = y0 - y if y < y0 else (y - y1 if y > y1 else 0.0)
            dz = z0 - z if z < z0 else (z - z1 if z > z1 else 0.0)
            if not s * (dx * dx + dy * dy + dz * dz) ** 0.5 - SLACK_M > lim:
                return False
    return True


def _group(rows: List[tuple]) -> Optional[tuple]:
    """(lower corner, upper corner, largest limit) of the AABB of the sphere centres (``rows``: (centre, limit) each);
    None unless every number is finite (such spheres are tested one by one)."""
    if not rows:
        return None
    (cx, cy, cz), lims = zip(*[c for c, _ in rows]), [lim for _, lim in rows]
    if not math.isfinite(sum(cx) + sum(cy) + sum(cz) + sum(lims)):
        return None
    return min(cx), min(cy), min(cz), max(cx), max(cy), max(cz), max(lims)


def _clear(box: tuple, lx: float, ly: float, lz: float, hx: float, hy: float, hz: float, lim: float) -> bool:
    """Whether the AABB [l, h] of sphere centres lies farther than ``lim`` (the largest limit) from ``box``, by
    :func:`all_clear`'s test; then every sphere passes that test against the box. A centre in the AABB is no nearer
    the box on any axis: its gap (``x0 − x`` or ``x − x1``, rounded) is at least the AABB's, as rounding keeps
    subtraction monotone; so are the squares, the sum, the root and the product by s ≥ 0."""
    x0, y0, z0, x1, y1, z1, s = box
    dx = x0 - hx if hx < x0 else (lx - x1 if lx > x1 else 0.0)
    dy = y0 - hy if hy < y0 else (ly - y1 if ly > y1 else 0.0)
    dz = z0 - hz if hz < z0 else (lz - z1 if lz > z1 else 0.0)
    return s * (dx * dx + dy * dy + dz * dz) ** 0.5 - SLACK_M > lim
