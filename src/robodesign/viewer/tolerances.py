"""How the viewer draws a :class:`~robodesign.formats.tolerance.ToleratedPose`: translucent shapes of its
translational tolerance and one line of text per constraint (apart from :mod:`.scene`, which places them)."""
from __future__ import annotations

import math
from typing import Dict, List, Tuple

import numpy as np

from robodesign.formats.tolerance import ToleratedPose

TOLERANCE_CLIP = 0.3  # m: half-size shown for an unbounded translational interval
TOLERANCE_OPACITY = 0.25


def _pose(T) -> List[List[float]]:
    return np.asarray(T, dtype=float).reshape(4, 4).tolist()


def _fmt(x: float) -> str:
    if math.isinf(x):
        return "∞" if x > 0 else "−∞"
    return f"{x:.6g}"


def _frame_rotation(tp: ToleratedPose, frame: str) -> np.ndarray:
    """Q_f: nominal axes → axes of the tolerance frame (see robodesign.formats.tolerance)."""
    Q = getattr(tp, "_Q", {}).get(frame)
    if Q is not None:
        return np.asarray(Q, dtype=float)
    Rn = tp.nominal[:3, :3]
    if frame == "world":
        return Rn.copy()
    if frame != "nominal" and tp.frame_resolver is not None:
        try:
            return np.asarray(tp.frame_resolver(frame), float)[:3, :3].T @ Rn
        except Exception:  # pragma: no cover - unknown frame: show in nominal axes
            pass
    return np.eye(3)


def _clip_interval(lo: float, hi: float, clip: float) -> Tuple[float, float, bool]:
    clipped = False
    if math.isinf(lo) and math.isinf(hi):
        return -clip, clip, True
    if math.isinf(lo):
        lo, clipped = min(hi, 0.0) - clip, True
    if math.isinf(hi):
        hi, clipped = max(lo, 0.0) + clip, True
    return lo, hi, clipped


def tolerance_geometries(tp: ToleratedPose, color: str, clip: float = TOLERANCE_CLIP,
                         opacity: float = TOLERANCE_OPACITY) -> List[dict]:
    """Translucent shapes of the translational tolerance, posed relative to the nominal frame.

    ``r_sph`` → a sphere of radius hi; ``r_cyl`` → a cylinder about the frame's z axis (height from a
    ``z`` interval in the same frame); ``x``/``y``/``z`` → a box in the tolerance frame's axes.
    Unbounded sides are cut at ``clip`` and the shape is drawn as a wireframe. Angular projections
    (``phi_*``, ``theta``, rotations) are listed as text only.
    """
    by_frame: Dict[str, Dict[str, Tuple[float, float]]] = {}
    for c in tp.constraints:
        if not c.info.translational or c.covers_allowed_range():
            continue
        by_frame.setdefault(c.frame, {})[c.projection] = (c.lower(), c.upper())
    out = []
    for frame, d in by_frame.items():
        QT = _frame_rotation(tp, frame).T

        def posed(center):
            P = np.eye(4)
            P[:3, :3] = QT
            P[:3, 3] = QT @ np.asarray(center, float)
            return P

        base = {"role": "tolerance", "color": color, "opacity": float(opacity)}
        if "r_sph" in d and math.isfinite(d["r_sph"][1]):
            out.append(dict(base, type="sphere", radius=max(d["r_sph"][1], 1e-4), pose=_pose(np.eye(4))))
        if "r_cyl" in d and math.isfinite(d["r_cyl"][1]):
            zlo, zhi, cl = _clip_interval(*d.get("z", (-math.inf, math.inf)), clip)
            out.append(dict(base, type="cylinder", radius=max(d["r_cyl"][1], 1e-4), length=max(zhi - zlo, 1e-4),
                            pose=_pose(posed([0.0, 0.0, 0.5 * (zlo + zhi)])), wireframe=cl))
        if "x" in d or "y" in d or ("z" in d and "r_cyl" not in d):
            lo_hi = [_clip_interval(*d.get(a, (-math.inf, math.inf)), clip) for a in "xyz"]
            size = [max(hi - lo, 1e-4) for lo, hi, _ in lo_hi]
            center = [0.5 * (lo + hi) for lo, hi, _ in lo_hi]
            out.append(dict(base, type="box", size=size, pose=_pose(posed(center)),
                            wireframe=any(c for _, _, c in lo_hi)))
    return out


def tolerance_text(tp: ToleratedPose) -> List[str]:
    if tp.is_unconstrained:
        return ["any pose"]
    out = []
    for p, (lo, hi), f in tp.entries:
        out.append(f"{p} ∈ [{_fmt(lo)}, {_fmt(hi)}]" + ("" if f == "nominal" else f" ({f})"))
    return out
