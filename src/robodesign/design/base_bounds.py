"""The base-pose parameters of a search space (:class:`BaseBounds`: offsets x, y, z, yaw from the nominal base pose
within box bounds and the task's base-placement tolerance) and the bounding spheres that let a sampled base position
skip the exact inside-test of the obstacles it is far from (:func:`clearance_spheres`), how far the goals lie
beyond an order's reach bound at a proposed base pose (:func:`beyond_reach`) and the base parameters that
``SearchSpace.sample_base`` proposes for an order (:class:`BaseProposals`)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Optional, Sequence, Tuple

import numpy as np

from robodesign.core.spatial import rot_z

if TYPE_CHECKING:
    from robodesign.formats.tolerance import ToleratedPose


@dataclass(frozen=True)
class BaseBounds:
    """Box bounds on (x, y, z, yaw) offsets from ``nominal``; a parameter with lo == hi is fixed."""
    nominal: np.ndarray = field(default_factory=lambda: np.eye(4))
    lower: Tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    upper: Tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    tolerance: Optional[ToleratedPose] = None  # that a base pose must satisfy (None: any)

    @cached_property
    def free(self) -> Tuple[int, ...]:
        return tuple(i for i in range(4) if self.upper[i] > self.lower[i])

    def pose(self, params: Sequence[float]) -> np.ndarray:
        full = [0.0, 0.0, 0.0, 0.0]
        for i, v in zip(self.free, params):
            full[i] = float(v)
        c, s = math.cos(full[3]), math.sin(full[3])  # (homogeneous(rot_z(yaw), xyz), written out)
        return self.nominal @ np.array([[c, -s, 0.0, full[0]], [s, c, 0.0, full[1]], [0.0, 0.0, 1.0, full[2]],
                                        [0.0, 0.0, 0.0, 1.0]])

    def valid(self, params: Sequence[float], pose: Optional[np.ndarray] = None) -> bool:   # (pose: made already)
        return self.within(params) and (self.tolerance is None or
                                        self.tolerance.valid(self.pose(params) if pose is None else pose))

    def within(self, params: Sequence[float]) -> bool:
        """Whether ``params`` has one value per free parameter, each within its bounds (:meth:`valid` without
        the base-placement tolerance)."""
        free = self.free
        if len(params) != len(free):
            return False
        for i, v in zip(free, params):
            if not (self.lower[i] - 1e-12 <= v <= self.upper[i] + 1e-12):
                return False
        return True

    def sample(self, rng, max_tries: int = 1000) -> Tuple[float, ...]:
        free = self.free
        for _ in range(max_tries):
            p = tuple(float(rng.uniform(self.lower[i], self.upper[i])) for i in free)
            if self.valid(p):
                return p
        return tuple(0.0 for _ in free)

    @staticmethod
    def from_tolerance(tp) -> "BaseBounds":
        """Bounds from a base-placement ToleratedPose: x/y/z intervals (nominal or world frame), r_cyl or
        r_sph as a box, yaw from N_z or Theta_R. An unconstrained tolerance gives a fixed base."""
        if tp is None:
            return BaseBounds()
        nominal = np.array(tp.nominal, dtype=float)
        if getattr(tp, "is_unconstrained", False):
            return BaseBounds(nominal=nominal, tolerance=None)
        lo = [0.0, 0.0, 0.0, 0.0]
        hi = [0.0, 0.0, 0.0, 0.0]
        for name, (a, b), _frame in tp.entries:
            if name in ("x", "y", "z"):
                i = "xyz".index(name)
                lo[i], hi[i] = max(lo[i], a) if lo[i] else a, min(hi[i], b) if hi[i] else b
            elif name in ("r_cyl", "r_sph"):
                for i in (0, 1) if name == "r_cyl" else (0, 1, 2):
                    lo[i], hi[i] = -b, b
            elif name in ("N_z", "Y", "Alpha"):
                lo[3], hi[3] = a, b
            elif name == "Theta_R":
                lo[3], hi[3] = -b, b
        lo = [max(-10.0, v) for v in lo]
        hi = [min(10.0, v) for v in hi]
        return BaseBounds(nominal=nominal, lower=(lo[0], lo[1], lo[2], lo[3]), upper=(hi[0], hi[1], hi[2], hi[3]),
                          tolerance=tp)


def clearance_spheres(obstacles) -> list:
    """(spec, centre, squared radius or None) of each primitive obstacle (``SearchSpace._clear``'s; meshes are
    left out). contains_point tests the point's coordinates in the shape's frame, ``local = R⁻¹ (p − t)``, and every
    point inside has ``|local|`` at most the shape's radius r (box: half its diagonal); ``|local| ≥ |p − t| /
    σ_max(R)``, so a point farther than ``σ_max(R)·(r + 1e-6)`` from t is outside (1e-6 m: far above the test's
    1e-12 and the rounding of the frame change). None (the exact test always runs): a pose whose last row is
    not (0, 0, 0, 1), or a size that is not finite."""
    out = []
    for g in obstacles:
        if g.kind == "mesh":
            continue
        T, size = np.asarray(g.pose, float), [abs(float(v)) for v in g.size]
        r = {"box": 0.5 * math.sqrt(sum(v * v for v in size[:3])) if len(size) >= 3 else math.inf,
             "cylinder": math.hypot(size[0], 0.5 * size[1]) if len(size) >= 2 else math.inf,
             "sphere": size[0] if size else math.inf}.get(g.kind, math.inf)
        affine = T.shape == (4, 4) and bool(np.all(T[3] == (0.0, 0.0, 0.0, 1.0))) and bool(np.isfinite(T).all())
        bound = float(np.linalg.svd(T[:3, :3], compute_uv=False)[0]) * (r + 1e-6) if affine else math.inf
        out.append((g, tuple(float(v) for v in T[:3, 3]), bound * bound if math.isfinite(bound) else None))
    return out


def beyond_reach(goals, R: float, pose: np.ndarray, o_h: np.ndarray) -> float:
    """How far [m] the farthest goal (rows x, y, z, slack) lies beyond the reach bound of radius ``R`` around
    ``pose @ o_h`` (the first joint; ``o_h``: its homogeneous position in the base frame), each goal's slack off;
    0 when none does. The numbers of ``max(0, max(norm(G[:, :3] - o, axis=1) - G[:, 3] - R))`` in numpy (whose
    norm along an axis is the square root of the squares summed in order), in Python floats (a few goals)."""
    ox, oy, oz = (pose @ o_h)[:3].tolist()
    worst = -math.inf
    for x, y, z, slack in goals:
        dx, dy, dz = x - ox, y - oy, z - oz
        d = math.sqrt(dx * dx + dy * dy + dz * dz) - slack - R
        if d != d:
            return 0.0   # (numpy's max is NaN then, and max(0.0, NaN) is 0.0)
        if d > worst:
            worst = d
    return max(0.0, worst)


_NEAR, _FAR = 0.2, 0.75   # a geometric proposal's first joint: at this share of the reach radius from a goal


class BaseProposals:
    """The base parameters :meth:`SearchSpace.sample_base` proposes for one order, each with the draws it made and
    the numbers it had, in fewer calls: ``rng.uniform(lo, hi)`` is numpy's ``lo + (hi − lo)·u`` of the double
    ``rng.random()`` gives (so a vector of ``rng.random`` draws gives a row of them), and ``np.linalg.norm`` of a
    vector is the square root of its dot product. ``goals``: rows (x, y, z, slack) in the world; ``o_local``: the
    first joint in the frame of the base parameters' origin; ``R``: the order's reach radius."""

    def __init__(self, bounds: BaseBounds, goals, o_local: np.ndarray, R: float, inverse_nominal: np.ndarray):
        self.free = bounds.free
        self.lo = [float(v) for v in bounds.lower]
        self.span = [float(h) - lo for h, lo in zip(bounds.upper, self.lo)]
        if not all(math.isfinite(s) for s in self.span):
            raise OverflowError("high - low range exceeds valid bounds")   # (numpy's uniform raises it)
        self.goals, self.o_local, self.inv = goals, o_local, inverse_nominal
        self.radius = min(R, 10.0)
        # the first joint turned by the yaw, made once when the yaw is fixed (its every draw is lo + 0.0)
        self.turned = rot_z(self.lo[3] + 0.0) @ o_local if self.span[3] == 0.0 else None

    def geometric(self, rng) -> Tuple[float, ...]:
        """The first joint at a random point 20–75 % of the reach radius (at most 10 m) from a random goal: every
        parameter drawn in its bounds, then the free x, y, z set to put the first joint there (at the drawn yaw)."""
        lo, span = self.lo, self.span
        u = rng.random(4).tolist()
        full = [lo[0] + span[0] * u[0], lo[1] + span[1] * u[1], lo[2] + span[2] * u[2], lo[3] + span[3] * u[3]]
        gx, gy, gz, _ = self.goals[int(rng.integers(len(self.goals)))]
        v = rng.normal(size=3)
        f = (_NEAR + (_FAR - _NEAR) * rng.random()) * self.radius / max(math.sqrt(float(v.dot(v))), 1e-12)
        vx, vy, vz = v.tolist()
        o_n = (self.inv @ np.array([gx + vx * f, gy + vy * f, gz + vz * f, 1.0]))[:3]   # in the nominal frame
        turned = self.turned if self.turned is not None else rot_z(full[3]) @ self.o_local
        t = (o_n - turned).tolist()
        return tuple(t[i] if i < 3 else full[i] for i in self.free)

    def uniform(self, rng) -> Tuple[float, ...]:
        """The free parameters drawn uniformly in their bounds."""
        lo, span = self.lo, self.span
        return tuple(lo[i] + span[i] * u for i, u in zip(self.free, rng.random(len(self.free)).tolist()))
