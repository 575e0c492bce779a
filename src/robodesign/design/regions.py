"""The region of positions a tolerated pose accepts, as bounds: how far an accepted position can lie from
the nominal one (:func:`position_radius`) and how close it can come to a point (:func:`distance_to_region`).
Used by the reach proof (design/reach.py) and the blocked-goal proof (design/blocked.py)."""
from __future__ import annotations

import math
from typing import Dict

import numpy as np
import numpy.typing as npt

from robodesign.formats.tolerance import ToleratedPose


def _frame_boxes(tp: ToleratedPose) -> Dict[str, dict]:
    """Per tolerance frame: the x/y/z intervals, the r_cyl and r_sph radii (the position constraints)."""
    out: Dict[str, dict] = {}
    for name, (lo, hi), frame in tp.entries:
        f = out.setdefault(frame, {"x": (-math.inf, math.inf), "y": (-math.inf, math.inf),
                                   "z": (-math.inf, math.inf), "r_cyl": math.inf, "r_sph": math.inf})
        if name in ("x", "y", "z"):
            a, b = f[name]
            f[name] = (max(a, lo), min(b, hi))
        elif name in ("r_cyl", "r_sph"):
            f[name] = min(f[name], hi)
    return out


def _frame_rotation(tp: ToleratedPose, frame: str) -> np.ndarray:
    """Q_f: nominal axes → the frame's axes (tolerance.py, "Frames")."""
    Q = getattr(tp, "_Q", {}).get(frame)
    if Q is None:
        Q = tp.nominal[:3, :3] if frame == "world" else np.eye(3)
    return np.asarray(Q, dtype=float)


def position_radius(tp: ToleratedPose) -> float:
    """An upper bound of how far a position allowed by ``tp`` can be from its nominal position (inf when
    some direction is unbounded)."""
    best = math.inf
    for f in _frame_boxes(tp).values():
        box = [max(abs(a), abs(b)) for a, b in (f["x"], f["y"], f["z"])]
        best = min(best, math.sqrt(sum(v * v for v in box)), f["r_sph"],
                   math.hypot(f["r_cyl"], box[2]) if math.isfinite(f["r_cyl"]) else math.inf)
    return best


def distance_to_region(tp: ToleratedPose, point: npt.ArrayLike) -> float:
    """A lower bound of the distance from world ``point`` to every position ``tp`` allows (0 when a direction
    is unbounded and the point lies that way)."""
    d_nom = tp.nominal[:3, :3].T @ (np.asarray(point, dtype=float) - tp.nominal[:3, 3])
    best = 0.0
    for frame, f in _frame_boxes(tp).items():
        v = _frame_rotation(tp, frame) @ d_nom
        lo = np.array([f[k][0] for k in "xyz"])
        hi = np.array([f[k][1] for k in "xyz"])
        best = max(best, float(np.linalg.norm(v - np.clip(v, lo, hi))))
        if math.isfinite(f["r_sph"]):
            best = max(best, float(np.linalg.norm(v)) - f["r_sph"])
        if math.isfinite(f["r_cyl"]):
            radial = max(0.0, math.hypot(v[0], v[1]) - f["r_cyl"])
            axial = max(0.0, v[2] - hi[2], lo[2] - v[2])
            best = max(best, math.hypot(radial, axial))
    return best
