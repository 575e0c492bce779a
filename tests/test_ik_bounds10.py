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


def test_the_reach_test_skipped_when_the_nominal_is_inside_gives_the_former_verdicts():
    """Goals whose nominal lies |o − pn| = R·(1 + δ) from the first joint's origin o (δ from −1e-3 to 1e-3, down to
    1e-13 and 0), with boxes holding the nominal or not, r_sph and Theta_R sets: ``ChainBounds._unreachable`` gives
    what the former formula gives (tests/test_fast_fail7's); the skip is taken, and both verdicts are met near the
    boundary."""
    from robodesign.formats.tolerance import ToleratedPose
    from robodesign.solvers.ik import ChainBounds, goal_model
    from robodesign.solvers.ik_bounds import _nominal_inside

    from test_fast_fail import _twins
    from test_fast_fail7 import _old_unreachable

    rng = np.random.default_rng(12)
    verdicts, skipped = {}, 0
    for robot, _ in _twins("robodesign_arm", 12, 30):
        cb = ChainBounds(robot)
        if not math.isfinite(cb.R) or cb.R <= 0:
            continue
        for delta in (-1e-3, -1e-9, -1e-13, 0.0, 1e-13, 1e-9, 1e-3):
            u = rng.normal(size=3)
            N = np.eye(4)
            N[:3, 3] = cb.o + u / np.linalg.norm(u) * cb.R * (1.0 + delta)
            w = float(rng.uniform(1e-4, 1e-2))
            shift = 0.0 if rng.random() < 0.7 else float(rng.uniform(-3, 3)) * w
            if rng.random() < 0.5:
                pose = ToleratedPose(N, ("x", "y", "z", "Theta_R"), ((shift - w, shift + w),) * 3 + ((0.0, 0.01),))
            else:
                pose = ToleratedPose(N, ("r_sph", "Theta_R"), ((0.0, w), (0.0, 0.01)))
            gm = goal_model(pose)
            got = cb._unreachable(gm)
            assert got == _old_unreachable(cb, gm), (delta, shift)
            skipped += cb._surely_within(gm, N[:3, 3]) and _nominal_inside(gm)
            verdicts[got] = verdicts.get(got, 0) + 1
    assert skipped >= 40 and verdicts.get("out_of_reach", 0) >= 20 and verdicts.get("", 0) >= 20, (skipped, verdicts)
