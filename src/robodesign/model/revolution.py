"""Bodies of revolution about a joint's axis: which joints are revolute and about which axis, and whether a primitive
(sphere, cylinder, capsule, cone) is symmetric about a line, so that a rotation about it leaves the space it occupies
unchanged. The sweep's lever arms (:mod:`robodesign.model.sweep`) and the set-up it carries to another base pose
(:mod:`robodesign.model.sweep_rebase`) both ask it."""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

#: a primitive counts as a body of revolution about a line when its centre lies within this distance of
#: the line and (cylinder, capsule, cone) its axis is within this angle of the line's direction: the
#: occupied space then moves by less than 1e-9·(size + 1) m under any rotation about the line
SYMMETRY_EPS = 1e-9
_ROTATIONAL = ("Cylinder", "Capsule", "Cone")  # bodies of revolution about their local z axis


def revolute_axis(model, j: int) -> Optional[np.ndarray]:
    """Unit axis of joint ``j`` in its own frame if it is a revolute joint (RX, RY, RZ, unaligned, and their
    unbounded forms), else None."""
    return _revolute_axis(model.joints[j])


def _revolute_axis(joint) -> Optional[np.ndarray]:
    name = joint.shortname()
    for suffix, axis in (("RX", (1.0, 0, 0)), ("RY", (0, 1.0, 0)), ("RZ", (0, 0, 1.0))):
        if name in ("JointModel" + suffix, "JointModelRUB" + suffix[1]):
            return np.array(axis, dtype=float)
    if name in ("JointModelRevoluteUnaligned", "JointModelRevoluteUnboundedUnaligned"):
        a = np.asarray(joint.extract().axis, dtype=float)
        return a / np.linalg.norm(a)
    return None


def _cross_norm(a, b) -> float:
    """|a × b| of two 3-vectors, on Python floats (numpy's cross of 3-vectors costs ~20 µs)."""
    a0, a1, a2 = (float(x) for x in a)
    b0, b1, b2 = (float(x) for x in b)
    x, y, z = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0
    return math.sqrt(x * x + y * y + z * z)


def symmetric_about(obj, point: np.ndarray, direction: np.ndarray, eps: float = SYMMETRY_EPS) -> bool:
    """Whether geometry object ``obj`` (a sphere, cylinder, capsule or cone) is a body of revolution about the
    line through ``point`` along the unit vector ``direction``, both in the frame of its parent joint: a
    rotation about that line then leaves the space it occupies unchanged."""
    return _symmetric(type(obj.geometry).__name__, obj.placement, point, direction, eps)


def _symmetric(kind: str, placement, point, direction, eps: float = SYMMETRY_EPS) -> bool:
    if kind != "Sphere" and kind not in _ROTATIONAL:
        return False
    centre = np.asarray(placement.translation, dtype=float)
    if _cross_norm(centre - point, direction) > eps:
        return False
    if kind == "Sphere":
        return True
    return _cross_norm(placement.rotation[:, 2], direction) <= eps


__all__ = ["SYMMETRY_EPS", "revolute_axis", "symmetric_about"]
