"""The blended path's set-up (``BlendedPolyline.__init__``, ``gridpoints``) without numpy's wrappers (issue 25,
round 9): the same points, pieces, bounds and grid bit for bit as the code before, kept here as the reference."""
import math

import numpy as np

from robodesign.solvers.blended_path import BlendedPolyline


class Reference(BlendedPolyline):
    """BlendedPolyline with the set-up as it was (np.linalg.norm, np.diff, the grid as a list of numpy floats)."""

    def __init__(self, waypoints: np.ndarray, blend_radius: float = 0.05):
        W = np.asarray(waypoints, dtype=float)
        keep = [0]
        for i in range(1, len(W)):
            if np.linalg.norm(W[i] - W[keep[-1]]) > 1e-12:
                keep.append(i)
        W = W[keep]
        self.points = W
        self._dof = W.shape[1]
        if len(W) < 2:
            raise ValueError("a path needs two distinct waypoints")
        D = np.diff(W, axis=0)
        L = np.linalg.norm(D, axis=1)
        U = D / L[:, None]
        K = len(W)
        r = np.zeros(K)
        theta = np.zeros(K)
        for i in range(1, K - 1):
            c = float(np.clip(U[i - 1] @ U[i], -1.0, 1.0))
            theta[i] = math.acos(c)
            if theta[i] > 1e-9:
                r[i] = min(blend_radius, 0.5 * L[i - 1], 0.5 * L[i])
        self.radii, self.angles = r, theta
        s0, p0, d0, cc, kind = [], [], [], [], []
        s = 0.0
        for i in range(K - 1):
            a = W[i] + r[i] * U[i]
            length = L[i] - r[i] - r[i + 1]
            if length > 1e-12:
                s0.append(s)
                p0.append(a)
                d0.append(U[i])
                cc.append(np.zeros(self._dof))
                kind.append(0)
                s += length
            if i + 1 < K - 1 and r[i + 1] > 0:
                s0.append(s)
                p0.append(W[i + 1] - r[i + 1] * U[i])
                d0.append(U[i])
                cc.append((U[i + 1] - U[i]) / (2 * r[i + 1]))
                kind.append(1)
                s += 2 * r[i + 1]
        self.breaks = np.array(s0 + [s])
        self.p0, self.d0, self.c = np.array(p0), np.array(d0), np.array(cc)
        self.is_blend = np.array(kind, dtype=bool)
        self.length = s
        self._end = W[-1]
        self.max_deviation = float(np.max(r * np.sin(theta) / 4.0, initial=0.0))
        self.max_waypoint_distance = float(np.max(r * np.sin(theta / 2.0) / 2.0, initial=0.0))

    def gridpoints(self, step: float, min_per_blend: int = 4, min_total: int = 100) -> np.ndarray:
        """Grid including every piece boundary; ≥ ``min_per_blend`` intervals per blend."""
        step = min(step, self.length / min_total)
        pts = [0.0]
        for k in range(len(self.p0)):
            a, b = self.breaks[k], self.breaks[k + 1]
            m = max(int(math.ceil((b - a) / step - 1e-9)), min_per_blend if self.is_blend[k] else 1)
            pts.extend(a + (b - a) * np.arange(1, m + 1) / m)
        g = np.array(pts)
        g[-1] = self.length
        return g

FIELDS = ("points", "radii", "angles", "breaks", "p0", "d0", "c", "is_blend")


def random_waypoints(rng):
    """2–8 waypoints of 1–7 joints: random steps, some repeated exactly or within 1e-12 (dropped or kept by the
    duplicate test), straight runs and reversals."""
    K, dof = int(rng.integers(2, 9)), int(rng.integers(1, 8))
    W = np.cumsum(rng.normal(0.0, rng.choice([1e-3, 0.05, 1.0]), (K, dof)), axis=0)
    for i in range(1, K):
        u = rng.uniform()
        if u < 0.15:
            W[i] = W[i - 1]
        elif u < 0.3:
            d = rng.normal(size=dof)
            W[i] = W[i - 1] + d / np.linalg.norm(d) * 1e-12 * rng.choice([0.5, 1.0, 1.0 + 1e-9, 2.0])
        elif u < 0.4 and i >= 2:
            W[i] = W[i - 1] + (W[i - 1] - W[i - 2]) * rng.choice([1.0, -1.0, 0.5])
    return W


def test_the_set_up_and_grid_are_the_references():
    """800 random polylines and blend radii (0–0.3): every field, the length and deviation bounds, and grids at
    three steps are the reference's bytes; both duplicate verdicts occur, near the 1e-12 threshold too."""
    rng = np.random.default_rng(17)
    made = dropped = 0
    for _ in range(800):
        W = random_waypoints(rng)
        radius = float(rng.choice([0.0, 0.01, 0.05, 0.3]))
        try:
            want = Reference(W, radius)
        except ValueError:
            try:
                BlendedPolyline(W, radius)
            except ValueError:
                continue
            raise AssertionError("the reference refused a path the new set-up accepts")
        got = BlendedPolyline(W, radius)
        made += 1
        dropped += len(W) - len(got.points)
        for name in FIELDS:
            a, b = getattr(got, name), getattr(want, name)
            assert a.shape == b.shape and a.tobytes() == b.tobytes(), name
        assert (got.length, got.max_deviation, got.max_waypoint_distance) == \
            (want.length, want.max_deviation, want.max_waypoint_distance)
        for step in (0.02, 0.003, 1.0):
            assert got.gridpoints(step).tobytes() == want.gridpoints(step).tobytes()
    assert made > 600 and dropped > 100
