"""Tolerated poses: a nominal pose plus per-projection intervals (CoBRA ``ToleratedPose``, paper Table II).

A tolerated pose is checked on ``Δ = nominal⁻¹ · T``, the real pose ``T`` seen from the nominal frame.
Each tolerance *entry* is ``(projection, [lo, hi], frame)``; a pose is valid when every entry holds
(``lo − eps ≤ value ≤ hi + eps``, ``eps = 1e-12`` as in the reference).

Projections (``PROJECTIONS``; the value is a function of Δ expressed in the entry's frame):

=====================  ==========================================================  =================
name                   value                                                        allowed bounds
=====================  ==========================================================  =================
``x``, ``y``, ``z``    translation components                                       any (±Infinity ok)
``r_cyl``              √(x² + y²)                                                   [0, ∞)
``phi_cyl``            atan2(y, x)                                                  angle, see below
``r_sph``              ‖p‖                                                          [0, ∞)
``theta``              polar angle arccos(z / r)                                    [0, π]
``phi_sph``            azimuth atan2(y, x)                                          angle, see below
``R``, ``P``, ``Y``    roll/pitch/yaw about *fixed* X, Y, Z: Rot = Rz(Y)·Ry(P)·Rx(R)  R, Y angle; P [−π/2, π/2]
``Alpha``, ``Beta``,   intrinsic Z-Y'-X'' Euler angles: Rot = Rz(α)·Ry(β)·Rx(γ)      α, γ angle; β [−π/2, π/2]
``Gamma``              (numerically identical to Y, P, R)
``N_x``, ``N_y``,      components of the *scaled* rotation vector n·θ, θ ∈ [0, π]     [−π, π]
``N_z``
``Theta_R``            rotation angle θ                                             [0, π]
``A``, ``B``, ``C``,   unit quaternion (w, x, y, z), sign chosen so that w ≥ 0        A [0, 1]; B, C, D [−1, 1]
``D``                  (if w = 0: the first non-zero of x, y, z is made positive)
=====================  ==========================================================  =================

Frames (``toleranceFrame``, one per entry, default ``"nominal"``), as FORMAT.md §2.5 describes:

* ``nominal``: Δ is projected as it is.
* ``world`` or a named task frame F: Δ's translation and rotation are re-expressed in axes parallel to
  F, keeping the nominal point as origin: with Q = R_Fᵀ·R_nominal, ``p_F = Q·p`` and ``R_F = Q·R·Qᵀ``.
  Named frames are resolved once, at construction, through ``frame_resolver(name) -> 4x4 world pose``.

Decisions (robodesign's own; the reference is silent or does something surprising):

* **Empty tolerance.** The reference treats a missing or empty ``toleranceProjection`` as "always
  valid" (FORMAT.md §2.5 Quirk); all sample ``basePlacement`` poses rely on it. ``ToleratedPose`` does the
  same by default (``empty_means_any=True``; ``is_unconstrained`` is then True). With
  ``empty_means_any=False`` an empty tolerance means "the nominal pose" and gets the reference's default
  for Python-built poses: ±1 mm in x, y, z and 0.5° rotation angle (nominal frame). ``to_json`` still
  writes the (empty) entries exactly as read.
* **Several entries on the same projection and frame** are intersected (as the reference merges them).
  The intersection is computed at construction; an empty intersection is an :class:`InputError`, because
  such a pose could never be valid. Validity checks every entry, which is the same set.
* **Periodic angles** (``phi_cyl``, ``phi_sph``, ``R``, ``Y``, ``Alpha``, ``Gamma``) are compared on the
  circle: −π and π are the same angle, and ``[3.0, π]`` contains an azimuth reported as −π. As an
  *extension* over the reference (which only accepts [−π, π]), their bounds may lie in [−2π, 2π] with
  ``hi − lo ≤ 2π``, so that a wedge crossing ±π can be written ``[2.9, 3.4]``. ``lo > hi`` is still an
  error. Intervals inside [−π, π] behave exactly as in the reference.
* **Signed ``Theta_R`` bounds.** Published tasks write ``Theta_R: [-a, a]``; the reference reads θ as a
  signed angle (a rotation R(n, θ) equals R(−n, −θ)), so such an interval allows |θ| ≤ max(a, b) for
  ``[-a, b]`` (and ``[c, d]`` with d < 0 allows |θ| ∈ [−d, −c]). It is normalised to that range in [0, π].
* **Bound slack.** Bounded angle/quaternion ranges accept bounds up to 1e-4 outside their range (people
  write 3.1416 for π); such bounds are clipped. Anything further out is an :class:`InputError`.
* **Degenerate points.** An azimuth (``phi_*``) at a point on the z-axis and a polar angle (``theta``) at
  the origin are undefined; such a point lies on the boundary of every wedge/cone, so these entries are
  treated as satisfied there (value reported as 0).
* ``Theta_R`` is computed as atan2(‖vee(R − Rᵀ)‖/2, (tr R − 1)/2), which is accurate for tiny angles
  (the reference's rounded arccos has ~1e-7 rad resolution near 0).
* Unknown keys in the JSON object are rejected (typo protection), naming the key.

For IK solvers: :meth:`ToleratedPose.residual` is a vector (one entry per merged constraint, order
``constraint_keys``) of signed distances outside the allowed set — zero exactly when valid, continuous
and piecewise smooth; :meth:`ToleratedPose.project` moves a pose into the tolerance (cyclic projection
onto each constraint) and :meth:`ToleratedPose.sample` draws a random pose inside it.
"""
from __future__ import annotations

import difflib
import math
from dataclasses import InitVar, dataclass, field
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Tuple, cast

import numpy as np

from robodesign.core.errors import InfeasibleError, InputError, PathPart, describe_value
from robodesign.core.spatial import homogeneous, inv, log3, parse_pose, pose_to_list
from robodesign.core.spatial import matrix_to_rpy as rotation_to_rpy
from robodesign.core.spatial import rpy_to_matrix as rpy_matrix
from robodesign.formats.tolerance_check import ValidPlan

FrameResolver = Callable[[str], np.ndarray]

PI = math.pi
TWO_PI = 2.0 * math.pi
EPS = 1e-12
ANGLE_BOUND_SLACK = 1e-4
_DEGENERATE = 1e-12
INF = math.inf


@dataclass(frozen=True)
class ProjectionInfo:
    name: str
    system: str            # 'cart', 'cyl', 'sph', 'rpy', 'euler', 'axis', 'quat'
    lo: float              # allowed range
    hi: float
    periodic: bool = False

    @property
    def translational(self) -> bool:
        return self.system in ("cart", "cyl", "sph")


def _info(name, system, lo, hi, periodic=False):
    return name, ProjectionInfo(name, system, lo, hi, periodic)


PROJECTIONS: Dict[str, ProjectionInfo] = dict([
    _info("x", "cart", -INF, INF), _info("y", "cart", -INF, INF), _info("z", "cart", -INF, INF),
    _info("r_cyl", "cyl", 0.0, INF), _info("phi_cyl", "cyl", -PI, PI, True),
    _info("r_sph", "sph", 0.0, INF), _info("theta", "sph", 0.0, PI), _info("phi_sph", "sph", -PI, PI, True),
    _info("R", "rpy", -PI, PI, True), _info("P", "rpy", -PI / 2, PI / 2), _info("Y", "rpy", -PI, PI, True),
    _info("Alpha", "euler", -PI, PI, True), _info("Beta", "euler", -PI / 2, PI / 2),
    _info("Gamma", "euler", -PI, PI, True),
    _info("N_x", "axis", -PI, PI), _info("N_y", "axis", -PI, PI), _info("N_z", "axis", -PI, PI),
    _info("Theta_R", "axis", 0.0, PI),
    _info("A", "quat", 0.0, 1.0), _info("B", "quat", -1.0, 1.0), _info("C", "quat", -1.0, 1.0),
    _info("D", "quat", -1.0, 1.0),
])

RESERVED_FRAMES = ("nominal", "world")

# Reference default for Python-built poses (Tolerance.py:927): ±1 mm xyz and 0.5° absolute rotation.
DEFAULT_ENTRIES = (("x", (-1e-3, 1e-3), "nominal"), ("y", (-1e-3, 1e-3), "nominal"),
                   ("z", (-1e-3, 1e-3), "nominal"), ("Theta_R", (0.0, math.radians(0.5)), "nominal"))

_JSON_KEYS = ("nominal", "nominalParent", "toleranceProjection", "tolerance", "toleranceFrame")
# "frame" is what the reference *writes* for the per-projection frames of a single tolerance (and
# ignores when reading); it means toleranceFrame.
_JSON_ALIASES = {"frame": "toleranceFrame"}


class ToleranceSamplingError(InfeasibleError):
    """No pose inside the tolerance was found (constraints in different frames may contradict)."""


# ---------------------------------------------------------------------------------------------------------
# Projections of a single (p, R)
# ---------------------------------------------------------------------------------------------------------
def rotation_angle_precise(R: np.ndarray) -> float:
    """θ ∈ [0, π], accurate also for tiny angles."""
    s = 0.5 * math.sqrt((R[2, 1] - R[1, 2]) ** 2 + (R[0, 2] - R[2, 0]) ** 2 + (R[1, 0] - R[0, 1]) ** 2)
    c = 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)
    return math.atan2(s, c)


def rotation_to_quaternion(R: np.ndarray) -> np.ndarray:
    """(w, x, y, z) with w ≥ 0 (if w == 0, the first non-zero of x, y, z is positive)."""
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    if tr > 0:
        s = 2.0 * math.sqrt(tr + 1.0)
        q = np.array([0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s])
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = 2.0 * math.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        q = np.array([(R[2, 1] - R[1, 2]) / s, 0.25 * s, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s])
    elif R[1, 1] > R[2, 2]:
        s = 2.0 * math.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2])
        q = np.array([(R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, 0.25 * s, (R[1, 2] + R[2, 1]) / s])
    else:
        s = 2.0 * math.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1])
        q = np.array([(R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, 0.25 * s])
    q /= np.linalg.norm(q)
    if q[0] < 0 or (q[0] == 0 and _first_nonzero(q[1:]) < 0):
        q = -q
    return q + 0.0


def _first_nonzero(v) -> float:
    for x in v:
        if x != 0:
            return x
    return 0.0


def quaternion_to_rotation(q: Sequence[float] | np.ndarray) -> np.ndarray:
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def exp3(w: Sequence[float] | np.ndarray) -> np.ndarray:
    """Rotation matrix of the rotation vector w (Rodrigues)."""
    w = np.asarray(w, dtype=float)
    th = float(np.linalg.norm(w))
    if th < 1e-15:
        return np.eye(3)
    k = w / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(th) * K + (1 - math.cos(th)) * (K @ K)


def _rotation_vector(R: np.ndarray) -> np.ndarray:
    w = np.asarray(log3(R), dtype=float)
    th = rotation_angle_precise(R)
    n = float(np.linalg.norm(w))
    if n > 1e-300 and th > 0:
        w = w * (th / n)  # consistent with Theta_R
    return w


def translation_values(p: np.ndarray) -> Dict[str, Tuple[float, bool]]:
    """name → (value, degenerate) for the translational projections of p."""
    x, y, z = (float(v) for v in p)
    rho = math.hypot(x, y)
    r = math.sqrt(rho * rho + z * z)
    phi = math.atan2(y, x) if rho >= _DEGENERATE else 0.0
    return {"x": (x, False), "y": (y, False), "z": (z, False),
            "r_cyl": (rho, False), "phi_cyl": (phi, rho < _DEGENERATE),
            "r_sph": (r, False), "theta": (math.atan2(rho, z) if r >= _DEGENERATE else 0.0, r < _DEGENERATE),
            "phi_sph": (phi, rho < _DEGENERATE)}


def rotation_values(R: np.ndarray, systems: Iterable[str] = ("rpy", "euler", "axis", "quat")) \
        -> Dict[str, Tuple[float, bool]]:
    """name → (value, degenerate) for the rotational projections of R (only the requested systems)."""
    out: Dict[str, Tuple[float, bool]] = {}
    systems = set(systems)
    if systems & {"rpy", "euler"}:
        r, p, y = rotation_to_rpy(R)
        out.update({"R": (r, False), "P": (p, False), "Y": (y, False),
                    "Alpha": (y, False), "Beta": (p, False), "Gamma": (r, False)})
    if "axis" in systems:
        w = _rotation_vector(R)
        out.update({"N_x": (float(w[0]), False), "N_y": (float(w[1]), False), "N_z": (float(w[2]), False),
                    "Theta_R": (rotation_angle_precise(R), False)})
    if "quat" in systems:
        q = rotation_to_quaternion(R)
        out.update({"A": (float(q[0]), False), "B": (float(q[1]), False), "C": (float(q[2]), False),
                    "D": (float(q[3]), False)})
    return out


def projection_value(name: str, T: np.ndarray) -> float:
    """Value of one projection of a relative pose T (4x4), e.g. ``projection_value("r_cyl", delta)``."""
    info = PROJECTIONS[name]
    if info.translational:
        return translation_values(T[:3, 3])[name][0]
    return rotation_values(T[:3, :3], (info.system,))[name][0]


# ---------------------------------------------------------------------------------------------------------
# Interval arithmetic (linear intervals and arcs on the circle)
# ---------------------------------------------------------------------------------------------------------
def _arc_contains(v: float, a: float, b: float, eps: float) -> bool:
    w = b - a
    if w >= TWO_PI - eps:
        return True
    d = (v - a) % TWO_PI
    return d <= w + eps or d >= TWO_PI - eps


def _arc_signed_distance(v: float, a: float, b: float) -> float:
    w = b - a
    if w >= TWO_PI:
        return 0.0
    d = (v - a) % TWO_PI
    if d <= w:
        return 0.0
    above, below = d - w, TWO_PI - d
    return above if above <= below else -below


def _lin_contains(v: float, a: float, b: float, eps: float) -> bool:
    return a - eps <= v <= b + eps


def _lin_signed_distance(v: float, a: float, b: float) -> float:
    if v > b:
        return v - b
    if v < a:
        return v - a
    return 0.0


def _intersect_arcs(A: List[Tuple[float, float]], B: List[Tuple[float, float]]) -> List[Tuple[float, float]]:
    out = []
    for a1, b1 in A:
        if b1 - a1 >= TWO_PI - EPS:
            out.extend(B)
            continue
        for a2, b2 in B:
            if b2 - a2 >= TWO_PI - EPS:
                out.append((a1, b1))
                continue
            for k in (-2, -1, 0, 1, 2):
                lo, hi = max(a1, a2 + k * TWO_PI), min(b1, b2 + k * TWO_PI)
                if lo <= hi + EPS:
                    out.append((lo, max(lo, hi)))
    # de-duplicate (pieces equal modulo 2π)
    uniq: List[Tuple[float, float]] = []
    for a, b in out:
        if not any(abs((a - u) % TWO_PI) < 1e-12 and abs((b - a) - (v - u)) < 1e-12 for u, v in uniq):
            uniq.append((a, b))
    return uniq


@dataclass
class ProjectionConstraint:
    """All entries on one (projection, frame), merged into their intersection ``pieces``."""
    projection: str
    frame: str
    pieces: List[Tuple[float, float]]
    entries: List[int]

    @property
    def info(self) -> ProjectionInfo:
        return PROJECTIONS[self.projection]

    @property
    def key(self) -> Tuple[str, str]:
        return self.projection, self.frame

    def signed_distance(self, v: float) -> float:
        best = None
        for a, b in self.pieces:
            d = _arc_signed_distance(v, a, b) if self.info.periodic else _lin_signed_distance(v, a, b)
            if d == 0.0:
                return 0.0
            if best is None or abs(d) < abs(best):
                best = d
        return float(cast(float, best))  # (pieces is never empty: an empty intersection raised)

    def nearest(self, v: float, margin: float = 0.0) -> float:
        """Nearest point of the set to v; with ``margin`` > 0, of the set shrunk by margin on each side."""
        if margin <= 0:
            return v - self.signed_distance(v)
        shrunk = []
        for a, b in self.pieces:
            if self.info.periodic and b - a >= TWO_PI - 1e-12:
                return v
            a2, b2 = (a + margin, b - margin) if b - a > 2 * margin else ((a + b) / 2, (a + b) / 2)
            shrunk.append((a2, b2))
        return v - ProjectionConstraint(self.projection, self.frame, shrunk, self.entries).signed_distance(v)

    def covers_allowed_range(self) -> bool:
        info = self.info
        for a, b in self.pieces:
            if info.periodic and b - a >= TWO_PI - 1e-12:
                return True
            if not info.periodic and a <= info.lo and b >= info.hi:
                return True
        return False

    def upper(self) -> float:
        return max(b for _, b in self.pieces)

    def lower(self) -> float:
        return min(a for a, _ in self.pieces)

    def measure(self, scale: float) -> float:
        total = 0.0
        for a, b in self.pieces:
            a2, b2 = (a, b) if self.info.periodic else (max(a, self.info.lo), min(b, self.info.hi))
            if math.isinf(a2) and math.isinf(b2):
                total += 2 * scale
            elif math.isinf(a2) or math.isinf(b2):
                total += scale
            else:
                total += b2 - a2
        return total

    def draw(self, rng: np.random.Generator, scale: float) -> float:
        """Uniform-ish draw from the set; infinite sides are truncated to ``scale``."""
        spans = []
        for a, b in self.pieces:
            a2, b2 = (a, b) if self.info.periodic else (max(a, self.info.lo), min(b, self.info.hi))
            if math.isinf(a2) and math.isinf(b2):
                a2, b2 = -scale, scale
            elif math.isinf(a2):
                a2 = b2 - scale
            elif math.isinf(b2):
                b2 = a2 + scale
            spans.append((a2, b2))
        lengths = np.array([max(b - a, 0.0) for a, b in spans])
        if lengths.sum() <= 0:
            i = int(rng.integers(len(spans)))
        else:
            i = int(rng.choice(len(spans), p=lengths / lengths.sum()))
        a, b = spans[i]
        return float(rng.uniform(a, b)) if b > a else float(a)


# ---------------------------------------------------------------------------------------------------------
# Validation of entries
# ---------------------------------------------------------------------------------------------------------
def _unknown_projection_message(name) -> str:
    if not isinstance(name, str):
        return f"expected a projection name (string), got {describe_value(name)}"
    close = difflib.get_close_matches(name, list(PROJECTIONS), n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    return (f"unknown tolerance projection {name!r}{hint}; known projections: "
            + ", ".join(PROJECTIONS))


def _number(v, file, path) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise InputError(f"expected a number, got {describe_value(v)}", file=file, path=path)
    v = float(v)
    if math.isnan(v):
        raise InputError("NaN is not a valid bound", file=file, path=path)
    return v


def _check_bounds(name: str, lo: float, hi: float, file, path) -> Tuple[float, float]:
    info = PROJECTIONS[name]
    if lo > hi:
        raise InputError(f"lower bound {lo:g} is greater than upper bound {hi:g} for {name!r}",
                         file=file, path=path)
    if name == "Theta_R" and lo < 0 and lo >= -PI - ANGLE_BOUND_SLACK:
        # signed angle (reference: R(n, θ) = R(−n, −θ), θ ∈ [−π, π]): the set of |θ| that it allows
        lo, hi = (-hi, -lo) if hi < 0 else (0.0, max(hi, -lo))
    if info.periodic:
        slack = ANGLE_BOUND_SLACK
        if lo < -TWO_PI - slack or hi > TWO_PI + slack or hi - lo > TWO_PI + slack:
            raise InputError(f"bounds [{lo:g}, {hi:g}] of angle {name!r} must lie in [-2π, 2π] and span at most 2π "
                             f"(use e.g. [2.9, 3.4] for a wedge crossing ±π)", file=file, path=path)
        return lo, min(hi, lo + TWO_PI)
    if math.isinf(info.lo) and math.isinf(info.hi):
        return lo, hi
    slack = ANGLE_BOUND_SLACK if not math.isinf(info.hi) else 0.0
    if lo < info.lo - slack or hi > info.hi + slack:
        hi_s = "∞" if math.isinf(info.hi) else f"{info.hi:.6g}"
        raise InputError(f"bounds [{lo:g}, {hi:g}] of {name!r} are outside its allowed range "
                         f"[{info.lo:.6g}, {hi_s}]", file=file, path=path)
    lo2, hi2 = max(lo, info.lo), min(hi, info.hi)
    return lo2, max(lo2, hi2)


def _normalize_entries(projections, intervals, frames, file, base: Sequence[PathPart]):
    base = list(base)
    if isinstance(projections, str):
        projections = [projections]
    if not isinstance(projections, (list, tuple)):
        raise InputError(f"expected a list of projection names, got {describe_value(projections)}",
                         file=file, path=base + ["toleranceProjection"])
    n = len(projections)
    if intervals is None:
        intervals = []
    if (n == 1 and isinstance(intervals, (list, tuple)) and len(intervals) == 2
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in intervals)):
        intervals = [intervals]  # a single flat [lo, hi]
    if not isinstance(intervals, (list, tuple)):
        raise InputError(f"expected a list of [lower, upper] pairs, got {describe_value(intervals)}",
                         file=file, path=base + ["tolerance"])
    if frames is None or (isinstance(frames, (list, tuple)) and len(frames) == 0):
        frames = ["nominal"] * n
    elif isinstance(frames, str):
        frames = [frames] * n
    if not isinstance(frames, (list, tuple)):
        raise InputError(f"expected a list of frame names, got {describe_value(frames)}",
                         file=file, path=base + ["toleranceFrame"])
    if len(intervals) != n:
        raise InputError(f"{n} projection(s) in toleranceProjection but {len(intervals)} interval(s) in tolerance; "
                         "give one [lower, upper] per projection", file=file, path=base + ["tolerance"])
    if len(frames) != n:
        raise InputError(f"{n} projection(s) in toleranceProjection but {len(frames)} frame(s) in toleranceFrame; "
                         "give one frame per projection (or omit it for 'nominal')",
                         file=file, path=base + ["toleranceFrame"])
    out_p, out_i, out_f = [], [], []
    for i, (name, iv, fr) in enumerate(zip(projections, intervals, frames)):
        if not isinstance(name, str) or name not in PROJECTIONS:
            raise InputError(_unknown_projection_message(name), file=file, path=base + ["toleranceProjection", i])
        ipath = base + ["tolerance", i]
        if not isinstance(iv, (list, tuple)) or len(iv) != 2:
            raise InputError(f"expected [lower, upper], got {describe_value(iv)}", file=file, path=ipath)
        lo = _number(iv[0], file, ipath + [0])
        hi = _number(iv[1], file, ipath + [1])
        lo, hi = _check_bounds(name, lo, hi, file, ipath)
        if not isinstance(fr, str) or not fr:
            raise InputError(f"expected a frame name, got {describe_value(fr)}", file=file,
                             path=base + ["toleranceFrame", i])
        out_p.append(name)
        out_i.append((lo, hi))
        out_f.append(fr)
    return tuple(out_p), tuple(out_i), tuple(out_f)


def _resolve_frame(resolver: Optional[FrameResolver], name: str, file, path) -> np.ndarray:
    if name == "world":
        return np.eye(4)
    if name == "nominal":
        raise InputError("'nominal' cannot be used here; it is the tolerated pose's own frame", file=file, path=path)
    if resolver is None:
        raise InputError(f"unknown frame {name!r}: no task frames are defined here; use 'nominal', 'world' "
                         "or a frame from the task's 'frames'", file=file, path=path)
    try:
        T = resolver(name)
    except InputError:
        raise
    except (KeyError, LookupError, ValueError) as e:
        raise InputError(f"unknown frame {name!r} ({e})", file=file, path=path) from None
    if T is None:
        raise InputError(f"unknown frame {name!r}", file=file, path=path)
    T = np.asarray(T, dtype=float)
    if T.shape != (4, 4):
        raise InputError(f"frame {name!r} did not resolve to a 4x4 pose", file=file, path=path)
    return T


# ---------------------------------------------------------------------------------------------------------
# ToleratedPose
# ---------------------------------------------------------------------------------------------------------
@dataclass(eq=False)
class ToleratedPose:
    """A nominal world pose with tolerances. See the module docstring for semantics and decisions.

    ``nominal`` is the world pose. ``nominal_parent``/``nominal_local`` remember how it was written
    (``nominal = resolver(nominal_parent) @ nominal_local``) so that ``to_json`` round-trips.
    """
    nominal: np.ndarray
    projections: Tuple[str, ...] = ()
    intervals: Tuple[Tuple[float, float], ...] = ()
    frames: Tuple[str, ...] = ()
    nominal_parent: str = "world"
    nominal_local: Optional[np.ndarray] = None
    frame_resolver: Optional[FrameResolver] = field(default=None, repr=False)
    empty_means_any: bool = True
    source_file: InitVar[Optional[str]] = None
    source_path: InitVar[Sequence[PathPart]] = ()

    def __post_init__(self, source_file, source_path):
        file, base = source_file, list(source_path or ())
        self.nominal = np.array(self.nominal, dtype=float)
        if self.nominal.shape != (4, 4):
            raise InputError("nominal must be a 4x4 pose", file=file, path=base + ["nominal"])
        self.projections, self.intervals, self.frames = _normalize_entries(
            self.projections, self.intervals, self.frames, file, base)
        if self.nominal_parent != "world":
            parent = _resolve_frame(self.frame_resolver, self.nominal_parent, file, base + ["nominalParent"])
            if self.nominal_local is None:
                self.nominal_local = inv(parent) @ self.nominal
        elif self.nominal_local is None:
            self.nominal_local = self.nominal.copy()
        self.nominal_local = np.array(self.nominal_local, dtype=float)
        self._nominal_inv = inv(self.nominal)
        Rn = self.nominal[:3, :3]

        self.uses_default = False
        entries = list(zip(self.projections, self.intervals, self.frames))
        if not entries and not self.empty_means_any:
            entries = [(p, iv, f) for p, iv, f in DEFAULT_ENTRIES]
            self.uses_default = True
        self._entries = entries

        # Q_f: nominal axes → frame axes
        self._Q: Dict[str, np.ndarray] = {"nominal": np.eye(3), "world": Rn.copy()}
        for i, f in enumerate(self.frames):
            if f not in self._Q:
                F = _resolve_frame(self.frame_resolver, f, file, base + ["toleranceFrame", i])
                self._Q[f] = F[:3, :3].T @ Rn

        constraints: Dict[Tuple[str, str], ProjectionConstraint] = {}
        for i, (p, (lo, hi), f) in enumerate(entries):
            key = (p, f)
            if key not in constraints:
                constraints[key] = ProjectionConstraint(p, f, [(lo, hi)], [i])
                continue
            c = constraints[key]
            c.entries.append(i)
            if PROJECTIONS[p].periodic:
                c.pieces = _intersect_arcs(c.pieces, [(lo, hi)])
            else:
                a, b = max(c.pieces[0][0], lo), min(c.pieces[0][1], hi)
                c.pieces = [(a, b)] if a <= b + EPS else []
            if not c.pieces:
                which = ", ".join(f"tolerance[{j}]" for j in c.entries) if not self.uses_default else ""
                raise InputError(f"the intervals for {p!r} in frame {f!r} ({which}) do not overlap: "
                                 "no pose can satisfy them", file=file, path=base + ["tolerance", i])
        self.constraints: List[ProjectionConstraint] = list(constraints.values())
        self._active = [c for c in self.constraints if not c.covers_allowed_range()]
        # per frame: the coordinate systems its constraints need, and whether only x, y, z and Theta_R are
        # asked (the published goals): those are computed alone, without the other values of their systems
        self._need: Dict[str, set] = {}
        names: Dict[str, set] = {}
        for c in self.constraints:
            self._need.setdefault(c.frame, set()).add(c.info.system)
            names.setdefault(c.frame, set()).add(c.projection)
        self._plain = {f: n <= {"x", "y", "z", "Theta_R"} for f, n in names.items()}
        # valid()'s fast path: the same values, only those the entries ask for
        self._plan = ValidPlan(entries, self._Q, self._plain, PROJECTIONS, _DEGENERATE, _arc_contains,
                               rotation_to_quaternion)

    # -- construction from / to JSON ----------------------------------------------------------------------
    @staticmethod
    def canonical_json(obj, file: Optional[str], path: Sequence[PathPart], warnings) -> object:
        """The canonical form of a tolerated-pose object as real files write it (for :meth:`from_json`).

        ``frame`` → ``toleranceFrame`` (both given and different: an error); ``null`` for
        ``nominalParent``/``toleranceFrame`` means absent; unknown keys (ignored by the reference) are
        dropped and reported through ``warnings.ignored_key``. Anything that is not an object is returned
        unchanged (``from_json`` names the problem).
        """
        if not isinstance(obj, dict):
            return obj
        out: dict = {}
        base = list(path)
        for k, v in obj.items():
            canon = _JSON_ALIASES.get(k, k)
            if canon not in _JSON_KEYS:
                warnings.ignored_key(file, base, k, _JSON_KEYS)
                continue
            if v is None and canon in ("nominalParent", "toleranceFrame"):
                continue
            if canon in out and out[canon] != v:
                raise InputError(f"'frame' and {canon!r} are both given, with different frames (they mean the same)",
                                 file=file, path=base + [k])
            out[canon] = v
        return out

    @classmethod
    def from_json(cls, obj, file: Optional[str] = None, path: Sequence[PathPart] | None = None,
                  frame_resolver: Optional[FrameResolver] = None, empty_means_any: bool = True) -> "ToleratedPose":
        base = list(path or [])
        if not isinstance(obj, dict):
            raise InputError(f"expected a tolerated pose object with 'nominal', got {describe_value(obj)}",
                             file=file, path=base)
        for k in obj:
            if k not in _JSON_KEYS:
                close = difflib.get_close_matches(str(k), _JSON_KEYS, n=1)
                hint = f" (did you mean {close[0]!r}?)" if close else ""
                raise InputError(f"unknown key {k!r}{hint}; allowed keys: " + ", ".join(_JSON_KEYS),
                                 file=file, path=base + [str(k)])
        if "nominal" not in obj:
            raise InputError("missing required key 'nominal'", file=file, path=base)
        local = parse_pose(obj["nominal"], file, base + ["nominal"])
        parent = obj.get("nominalParent", "world")
        if not isinstance(parent, str) or not parent:
            raise InputError(f"expected a frame name, got {describe_value(parent)}", file=file,
                             path=base + ["nominalParent"])
        if parent == "world":
            nominal = local
        else:
            nominal = _resolve_frame(frame_resolver, parent, file, base + ["nominalParent"]) @ local
        return cls(nominal=nominal, projections=obj.get("toleranceProjection", ()) or (),
                   intervals=obj.get("tolerance", ()) or (), frames=obj.get("toleranceFrame", ()) or (),
                   nominal_parent=parent, nominal_local=local, frame_resolver=frame_resolver,
                   empty_means_any=empty_means_any, source_file=file, source_path=base)

    def to_json(self) -> dict:
        out: Dict[str, Any] = {"nominal": pose_to_list(cast(np.ndarray, self.nominal_local))}  # (__post_init__ set it)
        if self.nominal_parent != "world":
            out["nominalParent"] = self.nominal_parent
        if self.projections:
            out["toleranceProjection"] = list(self.projections)
            out["tolerance"] = [[float(lo), float(hi)] for lo, hi in self.intervals]
            if any(f != "nominal" for f in self.frames):
                out["toleranceFrame"] = list(self.frames)
        return out

    # -- properties ------------------------------------------------------------------------------------------
    @property
    def is_unconstrained(self) -> bool:
        """True when every pose is valid (no entries with ``empty_means_any``, or only full-range entries)."""
        return not self._active

    @property
    def constraint_keys(self) -> List[Tuple[str, str]]:
        """(projection, frame) of each residual component, in order."""
        return [c.key for c in self.constraints]

    @property
    def entries(self) -> List[Tuple[str, Tuple[float, float], str]]:
        """Effective entries (projection, (lo, hi), frame) — includes the defaults if they apply."""
        return list(self._entries)

    @property
    def nominal_is_valid(self) -> bool:
        return self.valid(self.nominal)

    # -- evaluation --------------------------------------------------------------------------------------------
    def delta(self, T: np.ndarray) -> np.ndarray:
        """Δ = nominal⁻¹ · T."""
        return self._nominal_inv @ np.asarray(T, dtype=float)

    def _frame_values(self, T: np.ndarray) -> Dict[str, Dict[str, Tuple[float, bool]]]:
        D = self.delta(T)
        p, R = D[:3, 3], D[:3, :3]
        out = {}
        for f, systems in self._need.items():
            Q = self._Q[f]
            vals: Dict[str, Tuple[float, bool]] = {}
            if self._plain[f]:  # the same values as below, only those asked
                if "cart" in systems:
                    x, y, z = (float(v) for v in (p if f == "nominal" else Q @ p))
                    vals.update({"x": (x, False), "y": (y, False), "z": (z, False)})
                if "axis" in systems:  # Theta_R is frame-independent (a similarity keeps the angle)
                    vals["Theta_R"] = (rotation_angle_precise(R if f == "nominal" else Q @ R @ Q.T), False)
                out[f] = vals
                continue
            if systems & {"cart", "cyl", "sph"}:
                vals.update(translation_values(Q @ p))
            rs = systems & {"rpy", "euler", "axis", "quat"}
            if rs:
                vals.update(rotation_values(Q @ R @ Q.T, rs))
            out[f] = vals
        return out

    def values(self, T: np.ndarray) -> Dict[Tuple[str, str], float]:
        """(projection, frame) → value of that projection of T."""
        fv = self._frame_values(T)
        return {c.key: fv[c.frame][c.projection][0] for c in self.constraints}

    def violations(self, T: np.ndarray, eps: float = EPS) -> List[Tuple[str, float, float, float]]:
        """Violated entries as (projection, value, lo, hi), in entry order. Empty if valid."""
        if self.is_unconstrained:
            return []
        fv = self._frame_values(T)
        out = []
        for name, (lo, hi), f in self._entries:
            v, degenerate = fv[f][name]
            if degenerate:
                continue
            ok = _arc_contains(v, lo, hi, eps) if PROJECTIONS[name].periodic else _lin_contains(v, lo, hi, eps)
            if not ok:
                out.append((name, v, lo, hi))
        return out

    def valid(self, T: np.ndarray, eps: float = EPS) -> bool:
        """``not violations(T, eps)``, computed by the pose's :class:`~.tolerance_check.ValidPlan` (the same
        values, only those the entries ask for) where it decides."""
        if not self._active:
            return True
        ok = self._plan.valid(self._nominal_inv @ np.asarray(T, dtype=float), eps)
        return not self.violations(T, eps) if ok is None else ok

    def residual(self, T: np.ndarray) -> np.ndarray:
        """Signed distance outside the allowed set for each merged constraint (``constraint_keys``).

        0 inside; > 0 above the upper bound, < 0 below the lower bound (angles on the circle: towards
        the nearer end). Units are those of the projection (m, rad, 1).
        """
        fv = self._frame_values(T) if self.constraints else {}
        res = np.zeros(len(self.constraints))
        for i, c in enumerate(self.constraints):
            v, degenerate = fv[c.frame][c.projection]
            res[i] = 0.0 if degenerate else c.signed_distance(v)
        return res

    # -- projection -------------------------------------------------------------------------------------------
    def project(self, T: np.ndarray, max_iter: int = 100, margin: float = 1e-9) -> Optional[np.ndarray]:
        """A pose inside the tolerance near T (cyclic projection onto each constraint), or None.

        Translation and rotation are handled independently; the result equals T if T is already valid.
        Each step clips to the set shrunk by ``margin`` so that the result is strictly valid.
        """
        T = np.asarray(T, dtype=float)
        if self.valid(T):
            return T.copy()
        D = self.delta(T)
        p, R = D[:3, 3].copy(), D[:3, :3].copy()
        for _ in range(max_iter):
            for c in self._active:
                Q = self._Q[c.frame]
                if c.info.translational:
                    p = Q.T @ _clip_translation(Q @ p, c, margin)
                else:
                    R = Q.T @ _clip_rotation(Q @ R @ Q.T, c, margin) @ Q
            U, _, Vt = np.linalg.svd(R)
            R = U @ Vt
            out = self.nominal @ homogeneous(R, p)
            if self.valid(out):
                return out
        return None

    def project_nominal(self) -> Optional[np.ndarray]:
        """The nominal pose if it is valid, else a nearby pose inside the tolerance (or None)."""
        return self.project(self.nominal)

    # -- sampling ----------------------------------------------------------------------------------------------
    def sample(self, rng=None, max_tries: int = 20000, unbounded_scale: float = 0.1) -> np.ndarray:
        """A random world pose inside the tolerance.

        If no entry constrains the translation (rotation), the nominal position (orientation) is kept.
        Otherwise a proposal is drawn in the coordinate system and frame whose constraints enclose the
        smallest region (unbounded coordinates of that system within ±``unbounded_scale`` m, unbounded
        angles over their full range) and rejected until every entry holds.
        """
        if rng is None or isinstance(rng, (int, np.integer)):
            rng = np.random.default_rng(rng)
        if self.is_unconstrained:
            return self.nominal.copy()
        trans = [c for c in self._active if c.info.translational]
        rot = [c for c in self._active if not c.info.translational]
        p = np.zeros(3)
        R = np.eye(3)
        if trans:
            p = self._sample_part(rng, trans, True, max_tries, unbounded_scale)
        if rot:
            R = self._sample_part(rng, rot, False, max_tries, unbounded_scale)
        return self.nominal @ homogeneous(R, p)

    def _part_ok(self, cs: List[ProjectionConstraint], p=None, R=None) -> bool:
        for c in cs:
            Q = self._Q[c.frame]
            if p is not None:
                v, deg = translation_values(Q @ p)[c.projection]
            else:
                v, deg = rotation_values(Q @ R @ Q.T, (c.info.system,))[c.projection]
            if deg:
                continue
            if not any((_arc_contains(v, a, b, EPS) if c.info.periodic else _lin_contains(v, a, b, EPS))
                       for a, b in c.pieces):
                return False
        return True

    def _sample_part(self, rng, cs: List[ProjectionConstraint], translational: bool, max_tries: int, scale: float):
        # candidate proposals: (volume, frame, system)
        by_frame: Dict[str, Dict[str, ProjectionConstraint]] = {}
        for c in cs:
            by_frame.setdefault(c.frame, {})[c.projection] = c
        candidates = []
        for f, d in by_frame.items():
            sc = scale
            if translational:  # unbounded coordinates should reach the bounded ones of other systems
                for k in ("x", "y", "z", "r_cyl", "r_sph"):
                    if k in d:
                        sc = max(sc, *(abs(v) for ab in d[k].pieces for v in ab if not math.isinf(v)))
            systems = ("cart", "cyl", "sph") if translational else ("axis", "rpy", "euler", "quat")
            for s in systems:
                if any(PROJECTIONS[k].system == s for k in d):
                    candidates.append((_proposal_volume(s, d, sc), f, s, sc))
        candidates.sort(key=lambda x: x[0])
        # Mostly the tightest proposal; every 4th try cycles through the others (robust to bad volume guesses).
        for i in range(max_tries):
            if i % 4 == 3 and len(candidates) > 1:
                _, frame, system, sc = candidates[1 + (i // 4) % (len(candidates) - 1)]
            else:
                _, frame, system, sc = candidates[0]
            d = by_frame[frame]
            Q = self._Q[frame]
            x = _propose(system, d, rng, sc)
            if x is None:
                continue
            if translational:
                p = Q.T @ x
                if self._part_ok(cs, p=p):
                    return p
            else:
                R = Q.T @ x @ Q
                if self._part_ok(cs, R=R):
                    return R
        what = "position" if translational else "orientation"
        raise ToleranceSamplingError(f"no {what} inside the tolerance found after {max_tries} tries; "
                                     "constraints in different frames may contradict each other")


# ---------------------------------------------------------------------------------------------------------
# Helpers for project() and sample()
# ---------------------------------------------------------------------------------------------------------
def _clip_translation(p: np.ndarray, c: ProjectionConstraint, margin: float = 0.0) -> np.ndarray:
    x, y, z = (float(v) for v in p)
    name = c.projection
    if name in ("x", "y", "z"):
        i = "xyz".index(name)
        out = np.array([x, y, z])
        out[i] = c.nearest(out[i], margin)
        return out
    rho = math.hypot(x, y)
    r = math.sqrt(rho * rho + z * z)
    if name == "r_cyl":
        r2 = c.nearest(rho, margin)
        if rho > _DEGENERATE:
            return np.array([x * r2 / rho, y * r2 / rho, z])
        return np.array([r2, 0.0, z])
    if name in ("phi_cyl", "phi_sph"):
        if rho < _DEGENERATE:
            return np.array([x, y, z])
        phi = c.nearest(math.atan2(y, x), margin)
        return np.array([rho * math.cos(phi), rho * math.sin(phi), z])
    if name == "r_sph":
        r2 = c.nearest(r, margin)
        if r > _DEGENERATE:
            return np.array([x, y, z]) * (r2 / r)
        return np.array([0.0, 0.0, r2])
    if name == "theta":
        if r < _DEGENERATE:
            return np.array([x, y, z])
        th = c.nearest(math.atan2(rho, z), margin)
        phi = math.atan2(y, x) if rho > _DEGENERATE else 0.0
        return r * np.array([math.sin(th) * math.cos(phi), math.sin(th) * math.sin(phi), math.cos(th)])
    raise AssertionError(name)


def _clip_rotation(R: np.ndarray, c: ProjectionConstraint, margin: float = 0.0) -> np.ndarray:
    name, system = c.projection, c.info.system
    if system in ("rpy", "euler"):
        r, p, y = rotation_to_rpy(R)
        idx = {"R": 0, "P": 1, "Y": 2, "Gamma": 0, "Beta": 1, "Alpha": 2}[name]
        a = [r, p, y]
        a[idx] = c.nearest(a[idx], margin)
        return rpy_matrix(*a)
    if system == "axis":
        w = _rotation_vector(R)
        if name == "Theta_R":
            th = float(np.linalg.norm(w))
            th2 = c.nearest(th, margin)
            w = w * (th2 / th) if th > 1e-12 else np.array([0.0, 0.0, th2])
        else:
            i = ["N_x", "N_y", "N_z"].index(name)
            w[i] = c.nearest(w[i], margin)
        return exp3(w)
    if system == "quat":
        q = rotation_to_quaternion(R)
        i = "ABCD".index(name)
        qi = c.nearest(q[i], margin)
        rest = [j for j in range(4) if j != i]
        n = float(np.linalg.norm(q[rest]))
        s = math.sqrt(max(0.0, 1.0 - qi * qi))
        q[i] = qi
        if n > 1e-12:
            q[rest] = q[rest] * (s / n)
        else:
            q[rest] = 0.0
            q[rest[0]] = s
        return quaternion_to_rotation(q)
    raise AssertionError(name)


def _proposal_volume(system: str, d: Dict[str, ProjectionConstraint], scale: float) -> float:
    def m(name, default):
        return d[name].measure(scale) if name in d else default

    def hi(name, default):
        return min(d[name].upper(), default) if name in d else default

    if system == "cart":
        L = 2 * min(scale, hi("r_cyl", INF), hi("r_sph", INF))
        return m("x", L) * m("y", L) * m("z", 2 * min(scale, hi("r_sph", INF)))
    if system == "cyl":
        r1 = min(hi("r_cyl", scale), hi("r_sph", INF))
        r0 = d["r_cyl"].lower() if "r_cyl" in d else 0.0
        phi = m("phi_cyl", TWO_PI)
        return 0.5 * phi * max(r1 * r1 - r0 * r0, 1e-300) * m("z", 2 * min(scale, hi("r_sph", INF)))
    if system == "sph":
        r1 = hi("r_sph", scale)
        r0 = d["r_sph"].lower() if "r_sph" in d else 0.0
        th = m("theta", PI)
        return (r1 ** 3 - r0 ** 3) / 3.0 * m("phi_sph", TWO_PI) * th
    if system == "axis":
        tmax = hi("Theta_R", PI)
        if any(k in d for k in ("N_x", "N_y", "N_z")):
            return m("N_x", 2 * tmax) * m("N_y", 2 * tmax) * m("N_z", 2 * tmax)
        t0 = d["Theta_R"].lower()
        return 4.0 / 3.0 * PI * (tmax ** 3 - t0 ** 3) + 1e-300
    if system == "rpy":
        return m("R", TWO_PI) * m("P", PI) * m("Y", TWO_PI)
    if system == "euler":
        return m("Gamma", TWO_PI) * m("Beta", PI) * m("Alpha", TWO_PI)
    if system == "quat":
        return 8.0 * m("B", 2.0) * m("C", 2.0) * m("D", 2.0)
    raise AssertionError(system)


def _propose(system: str, d: Dict[str, ProjectionConstraint], rng: np.random.Generator, scale: float):
    def draw(name, lo, hi):
        return d[name].draw(rng, scale) if name in d else float(rng.uniform(lo, hi))

    def hi(name, default):
        return min(d[name].upper(), default) if name in d else default

    if system == "cart":
        L = min(scale, hi("r_cyl", INF), hi("r_sph", INF))
        Lz = min(scale, hi("r_sph", INF))
        return np.array([draw("x", -L, L), draw("y", -L, L), draw("z", -Lz, Lz)])
    if system == "cyl":
        rmax = min(hi("r_cyl", scale), hi("r_sph", INF))
        r = d["r_cyl"].draw(rng, scale) if "r_cyl" in d else rmax * math.sqrt(rng.uniform())
        phi = draw("phi_cyl", -PI, PI)
        Lz = min(scale, hi("r_sph", INF))
        return np.array([r * math.cos(phi), r * math.sin(phi), draw("z", -Lz, Lz)])
    if system == "sph":
        r = d["r_sph"].draw(rng, scale) if "r_sph" in d else scale * rng.uniform() ** (1 / 3)
        th = d["theta"].draw(rng, scale) if "theta" in d else math.acos(rng.uniform(-1, 1))
        phi = draw("phi_sph", -PI, PI)
        return r * np.array([math.sin(th) * math.cos(phi), math.sin(th) * math.sin(phi), math.cos(th)])
    if system == "axis":
        tmax = hi("Theta_R", PI)
        if any(k in d for k in ("N_x", "N_y", "N_z")):
            return exp3([draw(k, -tmax, tmax) for k in ("N_x", "N_y", "N_z")])
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        return exp3(axis * d["Theta_R"].draw(rng, scale))
    if system == "rpy":
        return rpy_matrix(draw("R", -PI, PI), draw("P", -PI / 2, PI / 2), draw("Y", -PI, PI))
    if system == "euler":
        return rpy_matrix(draw("Gamma", -PI, PI), draw("Beta", -PI / 2, PI / 2), draw("Alpha", -PI, PI))
    if system == "quat":
        b, c_, dd = draw("B", -1, 1), draw("C", -1, 1), draw("D", -1, 1)
        s = 1.0 - (b * b + c_ * c_ + dd * dd)
        if s < 0:
            return None
        return quaternion_to_rotation([math.sqrt(s), b, c_, dd])
    raise AssertionError(system)
