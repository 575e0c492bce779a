"""Spheres that contain a robot's collision shapes (centre in the shape's frame, radius), kept per shape object: the
bounds of the collision culler (:mod:`.collision_cull`), the sweep's clearance and the robot's geometry screens."""
from __future__ import annotations

from typing import Dict, Tuple

import numpy as np


def _bounding_sphere(shape) -> Tuple[np.ndarray, float]:
    """Centre (in the shape's frame) and radius of a sphere containing ``shape`` (its local AABB's)."""
    shape.computeLocalAABB()
    box = shape.aabb_local
    lo, hi = np.array(box.min_, dtype=float), np.array(box.max_, dtype=float)
    swept = float(shape.getSweptSphereRadius()) if hasattr(shape, "getSweptSphereRadius") else 0.0
    return 0.5 * (lo + hi), 0.5 * float(np.linalg.norm(hi - lo)) + swept


def _tight_sphere(shape) -> Tuple[np.ndarray, float]:
    """A sphere containing ``shape`` (centre in its frame, radius), as tight as the shape's type tells: a sphere's
    own; about the centre of a cylinder, cone or capsule (coal's, on their z axis) the farthest point of its rims or
    caps; a convex polytope's farthest vertex from its box's centre; for any other shape :func:`_bounding_sphere`'s.
    Never larger than that one; coal's swept-sphere radius added."""
    c, r = _bounding_sphere(shape)
    swept = float(shape.getSweptSphereRadius()) if hasattr(shape, "getSweptSphereRadius") else 0.0
    kind, origin = type(shape).__name__, np.zeros(3)
    if kind == "Sphere":
        centre, own = origin, float(shape.radius)
    elif kind in ("Cylinder", "Cone"):
        centre, own = origin, float(np.hypot(shape.radius, shape.halfLength))
    elif kind == "Capsule":
        centre, own = origin, float(shape.radius) + float(shape.halfLength)
    elif kind.startswith("Convex") and shape.num_points:
        P = np.asarray(shape.points(), dtype=float).reshape(-1, 3)
        centre, own = c, float(np.sqrt(((P - c) ** 2).sum(axis=1).max()))
    else:
        return c, r
    return (centre, own + swept) if own + swept < r else (c, r)


_SPHERES: Dict[int, Tuple[object, np.ndarray, float]] = {}   # id(shape) → (shape, centre, radius)
_TIGHT: Dict[int, Tuple[object, np.ndarray, float]] = {}     # id(shape) → (shape, centre, radius): _tight_sphere


def bounding_sphere(shape) -> Tuple[np.ndarray, float]:
    """:func:`_bounding_sphere` of a robot shape, kept per shape object (robots share their coal shapes, which are
    never changed: ``robodesign.model.robot._coal_shapes``)."""
    hit = _SPHERES.get(id(shape))
    if hit is None or hit[0] is not shape:
        hit = _SPHERES[id(shape)] = (shape, *_bounding_sphere(shape))   # (the shape is held: its id is not reused)
    return hit[1], hit[2]


def tight_sphere(shape) -> Tuple[np.ndarray, float]:
    """:func:`_tight_sphere` of a robot shape, kept per shape object (as :func:`bounding_sphere`)."""
    hit = _TIGHT.get(id(shape))
    if hit is None or hit[0] is not shape:
        hit = _TIGHT[id(shape)] = (shape, *_tight_sphere(shape))
    return hit[1], hit[2]


__all__ = ["bounding_sphere", "tight_sphere"]
