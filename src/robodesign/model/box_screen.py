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

from typing import Dict, List, Tuple

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
    infinite or NaN distance) clears it too."""
    rows = list(zip(centres.tolist(), limit.tolist()))
    for x0, y0, z0, x1, y1, z1, s in boxes:
        for (x, y, z), lim in rows:
            dx = x0 - x if x < x0 else (x - x1 if x > x1 else 0.0)
            dy = y0 - y if y < y0 else (y - y1 if y > y1 else 0.0)
            dz = z0 - z if z < z0 else (z - z1 if z > z1 else 0.0)
            if not s * (dx * dx + dy * dy + dz * dz) ** 0.5 - SLACK_M > lim:
                return False
    return True
