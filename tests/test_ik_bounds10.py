"""solvers/ik_bounds.py's ``_circle_distance`` (issue 25, tenth round): the norm taken as ``vector_norm`` gives the
former ``float(np.linalg.norm(...))`` formula's distance bit for bit, on many random points, circles and scales."""
import math

import numpy as np

from robodesign.solvers.ik_bounds import _circle_distance


def _former(x, center, axis, radius):
    v = x - center
    h = float(v @ axis)
    w = float(np.linalg.norm(v - h * axis))
    return math.hypot(h, w - radius)


def test_circle_distance_equals_the_former_formula():
    rng = np.random.default_rng(10)
    for _ in range(20000):
        x = rng.normal(size=3) * 10.0 ** rng.uniform(-4, 3)
        center = rng.normal(size=3) * 10.0 ** rng.uniform(-4, 1)
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        radius = abs(rng.normal()) * 10.0 ** rng.uniform(-4, 1)
        assert _circle_distance(x, center, axis, radius) == _former(x, center, axis, radius)
