"""The time-optimal bounds of many moves (``timing.time_optimal_bounds``, the IK choice's costs): the path for
positive finite limits gives the numbers of the general broadcast formula bit for bit (issue 25, round 9)."""
import numpy as np

from robodesign.solvers.timing import time_optimal_bounds


class _Limits:
    def __init__(self, v, a):
        self.dq_max, self.ddq_max = v, a


def broadcast_formula(robot, D):
    """The formula as it was before (every limit broadcast to D's shape; inf and zero limits handled)."""
    D = np.abs(np.asarray(D, dtype=float))
    v = np.broadcast_to(np.asarray(robot.dq_max, dtype=float), D.shape)
    a = np.broadcast_to(np.asarray(robot.ddq_max, dtype=float), D.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        bang = 2.0 * np.sqrt(D / a)
        trap = D / v + v / a
        t = np.where(np.isinf(v) | (D <= v * v / a), bang, trap)
        t = np.where(np.isinf(a), np.where(np.isinf(v), 0.0, D / v), t)
    t = np.where(D == 0.0, 0.0, t)
    return t.max(axis=-1) if t.shape[-1] else np.zeros(t.shape[:-1])


def test_the_finite_limits_path_gives_the_broadcast_numbers():
    """600 random sets of moves (1–9 joints, 0–3 leading axes of 1–12, distances over twelve decades with zeros,
    −0.0, NaN and inf) and limits (positive finite, some with inf or 0 to take the general path): the same bytes
    as the broadcast formula; both branches of the trapezoid many times."""
    rng = np.random.default_rng(9)
    bang = trap = general = 0
    for _ in range(600):
        dof = int(rng.integers(1, 10))
        shape = tuple(int(x) for x in rng.integers(1, 13, int(rng.integers(0, 4)))) + (dof,)
        D = np.exp(rng.uniform(-14, 14, shape)) * rng.choice([-1.0, 1.0], shape)
        special = rng.uniform(size=shape)
        D[special < 0.05] = 0.0
        D[(special >= 0.05) & (special < 0.07)] = -0.0
        if rng.uniform() < 0.1:
            D[special > 0.99] = np.nan
            D[(special > 0.98) & (special <= 0.99)] = np.inf
        v = np.exp(rng.uniform(-3, 3, dof))
        a = np.exp(rng.uniform(-3, 3, dof))
        if rng.uniform() < 0.2:
            v[rng.integers(dof)] = rng.choice([np.inf, 0.0])
            a[rng.integers(dof)] = rng.choice([np.inf, 0.0])
            general += 1
        robot = _Limits(v, a)
        got, want = time_optimal_bounds(robot, D), broadcast_formula(robot, D)
        assert got.shape == want.shape and got.tobytes() == want.tobytes()
        with np.errstate(divide="ignore", invalid="ignore"):
            thr = v * v / a
        bang += int((np.abs(D) <= thr).sum())
        trap += int((np.abs(D) > thr).sum())
    assert bang > 1000 and trap > 1000 and general > 50
