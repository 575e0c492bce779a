"""The time scaling's profile sampled by the compiled kernels (issue 25, round 8): topp_kernel.profile_rows' velocity
and position of a TOPP-RA profile along a blended path at given times are those of the numpy path
(timing._ToppraMotion.s_of_t, then the path's own evaluation), and topp_kernel.zoh_rows' samples those of
timing._zoh_from_velocity's numpy calls, bit for bit, on random paths, profiles, times and velocities."""
import numpy as np
import pytest
from conftest import COBRA

from robodesign import Robot, load_module_set
from robodesign.solvers import timing, topp_kernel


def _random_path(rng, dof):
    """A random blended path: straight runs, sharp and shallow corners, reversals, one piece or many."""
    W = np.cumsum(rng.normal(0, 0.4, (int(rng.integers(2, 9)), dof)), axis=0)
    return timing.BlendedPolyline(W, float(rng.choice([0.0, 0.01, 0.05, 0.3])))


def _random_motion(rng, path):
    """A random rest-to-rest profile on the path's grid, built as _toppra_profile builds it from toppra's ṡ."""
    grid = path.gridpoints(float(rng.uniform(0.005, 0.05)))
    sd = rng.uniform(0.0, 3.0, len(grid)) * rng.choice([1.0, 1e-3], len(grid), p=[0.9, 0.1])
    sd[0] = sd[-1] = 0.0
    ds = np.diff(grid)
    dt_i = 2 * ds / (sd[:-1] + sd[1:])
    u = (sd[1:] ** 2 - sd[:-1] ** 2) / (2 * ds)
    T_grid = np.concatenate([[0.0], np.cumsum(dt_i)])
    return timing._ToppraMotion(path, grid, sd, dt_i, u, T_grid)


def _times(rng, m):
    """Sample times as _sample and _fit_limits make them (k·h/λ clipped to the duration), every grid time, times
    beyond both ends, between grid times and a -0.0."""
    T = m.T_grid[-1]
    n = int(rng.integers(1, 300))
    h = T / n * float(rng.uniform(1.0, 1.01))
    lam = n * h / T
    return np.concatenate([np.minimum(h * np.arange(n + 1) / lam, T),
                           np.minimum(np.maximum(h * np.arange(n + 2)[1:] - h, 0.0) / lam, T),
                           m.T_grid, [-0.0, -1e-9, T + 1e-9, 2 * T], rng.uniform(0, T, 40)])


@pytest.fixture(scope="module", autouse=True)
def kernel():
    topp_kernel.warm_up()
    if not topp_kernel.ready():
        pytest.skip("the TOPP-RA kernel is not compiled")


def test_profile_rows_are_the_numpy_profile():
    rng = np.random.default_rng(25)
    for _ in range(300):
        path = _random_path(rng, int(rng.integers(1, 8)))
        m = _random_motion(rng, path)
        t = _times(rng, m)
        s, sdot = m.s_of_t(t)
        for order, want in ((1, path(s, 1) * sdot[:, None]), (0, path(s, 0))):
            got = m._at(t, order)
            assert got.shape == want.shape and got.tobytes() == want.tobytes()


def test_path_orders_are_the_numpy_orders():
    """BlendedPolyline.eval_orders by the kernel (topp_kernel.path_orders) against its numpy _locate and _order, both
    sides, at grid points, every piece boundary, points beyond both ends and a -0.0."""
    rng = np.random.default_rng(17)
    for _ in range(200):
        path = _random_path(rng, int(rng.integers(1, 8)))
        s = np.concatenate([path.gridpoints(float(rng.uniform(0.005, 0.05))), path.breaks,
                            [-0.0, -1e-9, path.length + 1e-9, 2 * path.length], rng.uniform(0, path.length, 50)])
        for left in (False, True):
            got = path.eval_orders(s, (0, 1, 2), left=left)
            at = path._locate(s, left)
            for order in (0, 1, 2):
                want = path._order(*at, order)
                assert got[order].shape == want.shape and got[order].tobytes() == want.tobytes()
        assert path.eval_orders(s, (2, 0))[1].tobytes() == path(s, 0).tobytes()


def test_path_terms_without_blends_take_the_right_limits():
    """A path without blends has q'' = 0 on both sides: _PathTerms' left limits (the right ones, unevaluated) are
    the numbers eval_left gives."""
    rng = np.random.default_rng(4)
    for _ in range(20):
        path = timing.BlendedPolyline(rng.normal(size=(int(rng.integers(2, 5)), 6)), 0.0)
        assert not path.is_blend.any()
        grid = path.gridpoints(0.02)
        tm = timing._PathTerms(None, path, grid, False)
        assert tm.qss_l.tobytes() == path.eval_left(grid, 2).tobytes()


def _random_velocities(rng):
    """Velocity rows as _sample makes them, and harder ones: 1–12 joints, 2–3000 rows, magnitudes over ten decades,
    zero rows and -0.0 entries."""
    n, dof = int(rng.choice([2, 3, 9, 130, 300, 3000])) - int(rng.integers(0, 2)), int(rng.integers(1, 13))
    V = rng.normal(size=(n, dof)) * 10.0 ** rng.integers(-5, 5, size=(n, dof))
    V[rng.random(n) < 0.1] = 0.0
    V[rng.random((n, dof)) < 0.05] = -0.0
    return V


def test_zoh_rows_are_the_numpy_samples(monkeypatch):
    rng = np.random.default_rng(8)
    cases = []
    for _ in range(400):
        V = _random_velocities(rng)
        q0 = rng.normal(size=V.shape[1])
        q1 = q0 + rng.choice([0.0, 1.0, 1e-9]) * rng.normal(size=V.shape[1])
        cases.append((q0, q1, V, float(rng.uniform(1e-4, 0.05))))
    fast = [timing._zoh_from_velocity(q0, q1, V, h) for q0, q1, V, h in cases]
    monkeypatch.setattr(topp_kernel, "ready", lambda: False)
    for (q0, q1, V, h), got in zip(cases, fast):
        want = timing._zoh_from_velocity(q0, q1, V, h)
        for x, y in zip(got, want):
            assert x.shape == y.shape and x.tobytes() == y.tobytes()


def test_time_parameterize_with_and_without_the_kernel(monkeypatch):
    """End to end on random paths of an IMPROV arm, torque limits on: the trajectories are the same bit for bit
    whether the profile is sampled by the kernel or by numpy."""
    rng = np.random.default_rng(3)
    robot = Robot.from_order(load_module_set(COBRA / "modules" / "IMPROV"), ["1", "21", "4", "22", "5", "23", "12"])
    paths = [np.cumsum(rng.normal(0, 0.5, (int(rng.integers(2, 5)), robot.dof)), axis=0) for _ in range(12)]
    fast = [timing.time_parameterize(robot, P) for P in paths]
    monkeypatch.setattr(timing._ToppraMotion, "_at", _numpy_at)
    monkeypatch.setattr(timing, "_zoh_from_velocity", _numpy_zoh)
    for P, a in zip(paths, fast):
        b = timing.time_parameterize(robot, P)
        for x, y in ((a.t, b.t), (a.q, b.q), (a.dq, b.dq), (a.ddq, b.ddq)):
            assert x.tobytes() == y.tobytes()
        assert a.info["max_path_error"] == b.info["max_path_error"] and a.info["method"] == b.info["method"]


def _numpy_at(self, t, order):
    """_ToppraMotion._at without the kernel."""
    s, sdot = self.s_of_t(np.asarray(t, float))
    return self.path(s, 1) * sdot[:, None] if order == 1 else self.path(s, 0)


_ZOH = timing._zoh_from_velocity


def _numpy_zoh(q0, q1, V, h):
    """timing._zoh_from_velocity without the kernel."""
    ready = topp_kernel.ready
    topp_kernel.ready = lambda: False
    try:
        return _ZOH(q0, q1, V, h)
    finally:
        topp_kernel.ready = ready
