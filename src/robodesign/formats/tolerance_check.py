"""The fast exact check behind :meth:`ToleratedPose.valid <robodesign.formats.tolerance.ToleratedPose.valid>`
(issue 25: the IK loop asks it once per converged descent).

The reference is :meth:`ToleratedPose.violations`: it builds, per frame, a dict of every projection of each
coordinate system an entry uses (e.g. all eight translational values and the rotation vector for an
``r_sph`` + ``Theta_R`` goal) and then checks the entries. A :class:`ValidPlan`, compiled once per tolerated
pose (plain data: it pickles with the pose), computes only the values the entries ask for and checks them, with
the same floating-point operations:

* Δ = nominal⁻¹·T is the caller's (the same numpy product as ``ToleratedPose.delta``); a frame's re-expression
  ``Q @ p`` and ``Q @ R @ Q.T`` are the same products on the same arrays;
* every value is the reference's formula evaluated on Python floats taken from those arrays: the same IEEE
  operations (numpy's float64 scalars and Python floats round alike; ``**`` is the same ``pow``), the R/P/Y,
  Euler and quaternion values by the very same functions, ‖log3 R‖ as ``np.linalg.norm`` computes it
  (√ of the vector's ``dot`` with itself);
* one product is left out: in the ``nominal`` frame Q is the identity, and ``I @ p`` equals p but for the sign
  of a zero (and for an infinite coordinate, which turns the others into NaN). The plan leaves it out only where
  the reference does too (x, y, z and Theta_R alone: ``_plain``) or where no value it feeds tells a zero's sign
  (no azimuth and no R/P/Y, Euler or quaternion value: atan2's branch cut is the only place a zero's sign
  shows), and then only for a finite pose (:meth:`ValidPlan.valid` returns None for another: the reference
  decides).

tests/test_tolerance_check.py compares values and verdicts with the reference on random poses on, near and off
the bounds of every projection kind, in the nominal frame and others.
"""
from __future__ import annotations

import math
from typing import Callable, Dict, List, Mapping, Optional, Tuple

import numpy as np

from robodesign.core.spatial import log3 as _log3
from robodesign.core.spatial import matrix_to_rpy as _rpy

_TRANS = ("x", "y", "z", "r_cyl", "phi_cyl", "r_sph", "theta", "phi_sph")
_AZIMUTHS = {"phi_cyl", "phi_sph"}
_RPY = {"R": 0, "P": 1, "Y": 2, "Gamma": 0, "Beta": 1, "Alpha": 2}
_QUAT = {"A": 0, "B": 1, "C": 2, "D": 3}
_AXIS = {"N_x": 0, "N_y": 1, "N_z": 2}
#: the values a frame of :meth:`_Frame.radial_values` holds, in its order: never degenerate, none periodic
_RADIAL = ("x", "y", "z", "r_cyl", "r_sph", "Theta_R")


def _angle(r0, r1, r2) -> float:
    """:func:`~robodesign.formats.tolerance.rotation_angle_precise` of the rows r0, r1, r2 (Python floats)."""
    s = 0.5 * math.sqrt((r2[1] - r1[2]) ** 2 + (r0[2] - r2[0]) ** 2 + (r1[0] - r0[1]) ** 2)
    c = 0.5 * (r0[0] + r1[1] + r2[2] - 1.0)
    return math.atan2(s, c)


class _Frame:
    """One tolerance frame of a plan: its entries and which values they need."""

    def __init__(self, frame: str, Q: np.ndarray, plain: bool, entries: List[Tuple[str, float, float, bool]],
                 systems: Mapping[str, str], degenerate: float, quaternion: Callable[[np.ndarray], np.ndarray]):
        names = {e[0] for e in entries}
        self.frame, self.entries = frame, entries
        self.degenerate, self.quaternion = degenerate, quaternion
        self.Q, self.QT = Q, Q.T
        self.p_names = names & set(_TRANS)
        self.r_names = names - self.p_names
        r_systems = {systems[n] for n in self.r_names}
        nominal = frame == "nominal"
        # leave out I @ p / I @ R @ I.T where the reference does, or where no value tells a zero's sign
        self.skip_p = nominal and not (self.p_names & _AZIMUTHS)
        self.skip_r = nominal and r_systems <= {"axis"}
        # … which equals the reference's product only for a finite pose (the plain path has no product)
        self.needs_finite = nominal and not plain and bool((self.skip_p and self.p_names)
                                                           or (self.skip_r and self.r_names))
        self.rho = bool(self.p_names - {"x", "y", "z"})
        self.r = bool(self.p_names & {"r_sph", "theta"})
        self.phi = bool(self.p_names & _AZIMUTHS)
        self.theta_r = "Theta_R" in self.r_names
        self.axis = sorted(self.r_names & set(_AXIS))
        self.rpy = sorted(self.r_names & set(_RPY))
        self.quat = sorted(self.r_names & set(_QUAT))
        # a frame of x, y, z, r_cyl, r_sph and Theta_R only: the entries' values in their order, without the dict
        self.radial = names <= set(_RADIAL) and not any(e[3] for e in entries)
        self.slots = [_RADIAL.index(e[0]) for e in entries] if self.radial else []

    def radial_values(self, D: np.ndarray, rows) -> List[float]:
        """The value of every entry, in their order, for a :attr:`radial` frame: those of :meth:`values` (the same
        operations on the same numbers; none of these is ever degenerate)."""
        x = y = z = rho = r = th = 0.0
        if self.p_names:
            if self.skip_p:
                x, y, z = rows[0][3], rows[1][3], rows[2][3]
            else:
                x, y, z = (self.Q @ D[:3, 3]).tolist()
            if self.rho:
                rho = math.hypot(x, y)
                if self.r:
                    r = math.sqrt(rho * rho + z * z)
        if self.theta_r:
            m = rows if self.skip_r else (self.Q @ D[:3, :3] @ self.QT).tolist()
            th = _angle(m[0], m[1], m[2])
        v = (x, y, z, rho, r, th)
        return [v[i] for i in self.slots]

    def values(self, D: np.ndarray, rows) -> Dict[str, Tuple[float, bool]]:
        """name → (value, degenerate), as the reference's ``_frame_values(T)[frame]`` has them."""
        out: Dict[str, Tuple[float, bool]] = {}
        if self.p_names:
            if self.skip_p:
                x, y, z = rows[0][3], rows[1][3], rows[2][3]
            else:
                x, y, z = (self.Q @ D[:3, 3]).tolist()
            for c, v in (("x", x), ("y", y), ("z", z)):
                if c in self.p_names:
                    out[c] = (v, False)
            if self.rho:     # translation_values, only what is asked
                rho = math.hypot(x, y)
                if "r_cyl" in self.p_names:
                    out["r_cyl"] = (rho, False)
                if self.phi:
                    phi = math.atan2(y, x) if rho >= self.degenerate else 0.0
                    for c in self.p_names & _AZIMUTHS:
                        out[c] = (phi, rho < self.degenerate)
                if self.r:
                    r = math.sqrt(rho * rho + z * z)
                    if "r_sph" in self.p_names:
                        out["r_sph"] = (r, False)
                    if "theta" in self.p_names:
                        d = self.degenerate
                        out["theta"] = (math.atan2(rho, z) if r >= d else 0.0, r < d)
        if self.r_names:
            if self.skip_r:
                M, m = D[:3, :3], rows
            else:
                M = self.Q @ D[:3, :3] @ self.QT
                m = M.tolist()
            if self.theta_r or self.axis:
                th = _angle(m[0], m[1], m[2])
                if self.theta_r:
                    out["Theta_R"] = (th, False)
                if self.axis:    # _rotation_vector: log3 scaled to the precise angle
                    w = np.asarray(_log3(M), dtype=float)
                    norm = math.sqrt(w.dot(w))
                    wl = w.tolist()
                    if norm > 1e-300 and th > 0:
                        f = th / norm
                        wl = [wl[0] * f, wl[1] * f, wl[2] * f]
                    for name in self.axis:
                        out[name] = (wl[_AXIS[name]], False)
            if self.rpy:
                a = _rpy(M)
                for name in self.rpy:
                    out[name] = (a[_RPY[name]], False)
            if self.quat:
                q = self.quaternion(M).tolist()
                for name in self.quat:
                    out[name] = (q[_QUAT[name]], False)
        return out


class ValidPlan:
    """The entries of a tolerated pose grouped by frame, each frame with the values its entries need.

    ``entries``: (projection, (lo, hi), frame) in the pose's order; ``Q``: frame → Q_f (nominal axes → frame
    axes); ``plain``: frame → whether only x, y, z and Theta_R are asked there; ``projections``: name →
    its ``ProjectionInfo`` (``system``, ``periodic``); ``degenerate``, ``arc_contains`` and ``quaternion``: the
    tolerance module's own threshold, circle test and quaternion (passed in: this module sits below it)."""

    def __init__(self, entries, Q: Mapping[str, np.ndarray], plain: Mapping[str, bool], projections: Mapping,
                 degenerate: float, arc_contains: Callable[[float, float, float, float], bool],
                 quaternion: Callable[[np.ndarray], np.ndarray]) -> None:
        by_frame: Dict[str, List[Tuple[str, float, float, bool]]] = {}
        for name, (lo, hi), f in entries:
            by_frame.setdefault(f, []).append((name, lo, hi, projections[name].periodic))
        systems = {n: info.system for n, info in projections.items()}
        self.frames = [_Frame(f, Q[f], plain[f], e, systems, degenerate, quaternion) for f, e in by_frame.items()]
        self.needs_finite = any(fr.needs_finite for fr in self.frames)
        self.arc_contains = arc_contains
        self.radial = all(fr.radial for fr in self.frames)   # every frame's values without dicts (valid_radial)

    def values(self, D: np.ndarray) -> Optional[List[Dict[str, Tuple[float, bool]]]]:
        """Per frame of :attr:`frames`: name → (value, degenerate) of Δ = ``D`` (4×4), as the reference's
        ``_frame_values`` has them; None for a pose the plan leaves to the reference (not finite)."""
        rows = D.tolist()
        if self.needs_finite and not math.isfinite(sum(rows[0]) + sum(rows[1]) + sum(rows[2])):
            return None
        return [fr.values(D, rows) for fr in self.frames]

    def valid(self, D: np.ndarray, eps: float) -> Optional[bool]:
        """Whether Δ = ``D`` satisfies every entry (``lo − eps ≤ v ≤ hi + eps``, angles on the circle), or None
        for a pose the plan leaves to the reference (not finite). Every value is computed before any is checked,
        as the reference does (a value that raises raises here too)."""
        if self.radial:
            return self.valid_radial(D, eps)
        try:
            vals = self.values(D)
        except OverflowError:   # a Python float's ** raises where numpy's float64 gives inf: the reference decides
            return None
        if vals is None:
            return None
        arc_contains = self.arc_contains
        for fr, fv in zip(self.frames, vals):
            for name, lo, hi, periodic in fr.entries:
                v, degenerate = fv[name]
                if degenerate:
                    continue
                if periodic:
                    if not arc_contains(v, lo, hi, eps):
                        return False
                elif not lo - eps <= v <= hi + eps:
                    return False
        return True

    def valid_radial(self, D: np.ndarray, eps: float) -> Optional[bool]:
        """:meth:`valid` of a plan whose every frame is :attr:`_Frame.radial`: the same values (every one computed
        before any is checked), checked as ``lo − eps ≤ v ≤ hi + eps`` in the same order, None where it gives None."""
        rows = D.tolist()
        if self.needs_finite and not math.isfinite(sum(rows[0]) + sum(rows[1]) + sum(rows[2])):
            return None
        try:
            vals = [fr.radial_values(D, rows) for fr in self.frames]
        except OverflowError:
            return None
        for fr, fv in zip(self.frames, vals):
            for (_, lo, hi, _), v in zip(fr.entries, fv):
                if not lo - eps <= v <= hi + eps:
                    return False
        return True
