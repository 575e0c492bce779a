"""The blended joint path of the time scaling (:mod:`robodesign.solvers.timing`, "toppra path: parabolic blends"):
the planner's polyline with each corner replaced by a parabolic blend, C¹ with unit speed in joint-space arc length
on the straight parts; toppra's geometric-path interface plus left limits."""
from __future__ import annotations

import math
from typing import List, Literal, Sequence, Tuple

import numpy as np


class BlendedPolyline:
    """Piecewise-linear joint path with parabolic corner blends (see module docstring).

    Pieces are ``q(s) = p0 + d0·σ + ½·c·σ²`` with σ = s − s_start; straight pieces have c = 0 and
    |d0| = 1. Implements toppra's ``AbstractGeometricPath`` interface (``__call__(s, order)``,
    ``dof``, ``path_interval``) plus left limits (:meth:`eval_left`).
    """

    def __init__(self, waypoints: np.ndarray, blend_radius: float = 0.05):
        W = np.asarray(waypoints, dtype=float)
        keep = [0]
        for i in range(1, len(W)):
            x = W[i] - W[keep[-1]]
            if math.sqrt(x.dot(x)) > 1e-12:   # (np.linalg.norm's own sum; so are L's below)
                keep.append(i)
        W = W[keep]
        self.points = W
        self._dof = W.shape[1]
        if len(W) < 2:
            raise ValueError("a path needs two distinct waypoints")
        D = W[1:] - W[:-1]
        L = np.sqrt(np.add.reduce(D * D, axis=1))
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

    @property
    def dof(self) -> int:
        return self._dof

    @property
    def path_interval(self) -> np.ndarray:
        return np.array([0.0, self.length])

    @property
    def waypoints(self):
        return None

    def _locate(self, s, left: bool) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(s clipped to the path (1-d), its piece k, σ = s − the piece's start (a column)); ``left``: a point on a
        boundary belongs to the piece before it."""
        s = np.clip(np.atleast_1d(np.asarray(s, float)), 0.0, self.length)
        side: Literal["left", "right"] = "left" if left else "right"
        k = np.minimum(np.maximum(np.searchsorted(self.breaks, s, side=side) - 1, 0), len(self.p0) - 1)
        return s, k, (s - self.breaks[k])[:, None]

    def _order(self, s: np.ndarray, k: np.ndarray, sig: np.ndarray, order: int) -> np.ndarray:
        """The ``order``-th derivative at the located points (:meth:`_locate`)."""
        if order == 0:
            out = self.p0[k] + self.d0[k] * sig + 0.5 * self.c[k] * sig ** 2
            out[s >= self.length] = self._end
        elif order == 1:
            out = self.d0[k] + self.c[k] * sig
        elif order == 2:
            out = self.c[k].copy()
        else:
            out = np.zeros((len(s), self._dof))
        return out

    def _eval(self, s, order: int, left: bool) -> np.ndarray:
        out = self._order(*self._locate(s, left), order)
        return out[0] if np.ndim(s) == 0 else out

    def eval_orders(self, s, orders: Sequence[int], left: bool = False) -> List[np.ndarray]:
        """``[self(s, order) for order in orders]`` for 1-d ``s`` (``left``: ``[self.eval_left(s, order) ...]``),
        the points located once; orders up to 2 by the compiled topp_kernel.path_orders once it is ready (the same
        numbers)."""
        from robodesign.solvers import topp_kernel
        s = np.asarray(s, float)
        if s.ndim == 1 and max(orders, default=0) <= 2 and topp_kernel.ready():
            out = [np.empty((len(s), self._dof)) for _ in range(3)]
            topp_kernel.path_orders(self.breaks, self.p0, self.d0, self.c, float(self.length), self._end,
                                    np.array(s, dtype=float), left, *out)
            return [out[order] for order in orders]
        at = self._locate(s, left)
        return [self._order(*at, order) for order in orders]

    def __call__(self, s, order: int = 0) -> np.ndarray:
        return self._eval(s, order, left=False)

    def eval(self, s):
        return self._eval(s, 0, False)

    def evald(self, s):
        return self._eval(s, 1, False)

    def evaldd(self, s):
        return self._eval(s, 2, False)

    def eval_left(self, s, order: int) -> np.ndarray:
        return self._eval(s, order, left=True)

    def gridpoints(self, step: float, min_per_blend: int = 4, min_total: int = 100) -> np.ndarray:
        """Grid including every piece boundary; ≥ ``min_per_blend`` intervals per blend."""
        step = min(step, self.length / min_total)
        pts = [np.zeros(1)]
        for k in range(len(self.p0)):
            a, b = self.breaks[k], self.breaks[k + 1]
            m = max(int(math.ceil((b - a) / step - 1e-9)), min_per_blend if self.is_blend[k] else 1)
            pts.append(a + (b - a) * np.arange(1, m + 1) / m)
        g = np.concatenate(pts)
        g[-1] = self.length
        return g
