"""The time scaling's set-up per path (issue 25, round 7): the blended path located once for several orders, and the
velocity constraint's x bounds from the path derivatives already computed, give the numbers of one call per order and
of toppra's own ``compute_constraint_params``, bit for bit."""
import numpy as np
import pytest
from conftest import COBRA

from robodesign import Robot, load_module_set
from robodesign.solvers import timing, toppra_loop

ARM = ["1", "21", "4", "22", "5", "23", "12"]


def _random_path(rng, dof):
    """Waypoints of a random joint path: straight runs, sharp and shallow corners, a repeated point, reversals."""
    W = np.cumsum(rng.normal(0, 0.4, (int(rng.integers(2, 9)), dof)), axis=0)
    if len(W) > 3:
        W[2] = W[1]  # a repeated waypoint (dropped by the path)
    return W


def _points(rng, path):
    """Grid points, every piece boundary, points beyond both ends and a -0.0."""
    g = path.gridpoints(float(rng.uniform(0.005, 0.05)))
    extra = np.concatenate([path.breaks, [-0.0, -1e-9, path.length + 1e-9, 2 * path.length],
                            rng.uniform(0, path.length, 50)])
    return np.concatenate([g, extra])


def test_eval_orders_are_one_call_per_order():
    rng = np.random.default_rng(5)
    for _ in range(60):
        dof = int(rng.integers(1, 8))
        path = timing.BlendedPolyline(_random_path(rng, dof), float(rng.choice([0.0, 0.01, 0.05, 0.3])))
        s = _points(rng, path)
        got = path.eval_orders(s, (0, 1, 2, 3))
        for order, out in enumerate(got):
            want = path(s, order)
            assert out.shape == want.shape and out.tobytes() == want.tobytes()
        assert path(0.3 * path.length, 1).shape == (dof,)  # a scalar point: one row


@pytest.fixture(scope="module")
def arm():
    return Robot.from_order(load_module_set(COBRA / "modules" / "IMPROV"), ARM)


@pytest.mark.parametrize("use_torque", [True, False])
def test_path_terms_are_the_per_order_calls(arm, use_torque):
    rng = np.random.default_rng(11)
    for _ in range(15):
        path = timing.BlendedPolyline(_random_path(rng, arm.dof), 0.05)
        grid = path.gridpoints(0.02)
        tm = timing._PathTerms(arm, path, grid, use_torque)
        for got, want in ((tm.qs, path(grid, 1)), (tm.qss_r, path(grid, 2)), (tm.qss_l, path.eval_left(grid, 2))):
            assert got.tobytes() == want.tobytes()
        if use_torque:
            from robodesign.model.rnea_batch import rnea_rows
            q, qs = path(grid, 0), path(grid, 1)
            zero = np.zeros_like(q)
            G = rnea_rows(arm.model, q, zero, zero)
            assert tm.g.tobytes() == G.tobytes()
            assert tm.a.tobytes() == (rnea_rows(arm.model, q, zero, qs) - G).tobytes()
            assert tm.bR.tobytes() == (rnea_rows(arm.model, q, qs, path(grid, 2)) - G).tobytes()


def test_velocity_xbound_is_toppras():
    rng = np.random.default_rng(2)
    for _ in range(40):
        dof = int(rng.integers(1, 8))
        path = timing.BlendedPolyline(_random_path(rng, dof), float(rng.choice([0.0, 0.05, 0.2])))
        grid = path.gridpoints(float(rng.uniform(0.005, 0.05)))
        vmax = rng.uniform(0.1, 5.0, dof)
        vmax[rng.random(dof) < 0.2] = timing.UNBOUNDED_LIMIT
        vel = timing._velocity_constraint(vmax)
        want = vel.compute_constraint_params(path, grid)[-1]
        got = toppra_loop.velocity_xbound(vel, path(grid, 1))
        assert got.shape == want.shape and got.tobytes() == want.tobytes()
