"""The whole-step torque bounds of judge.arc_torques' prefilter by the compiled kernel
(judge.interval_kernel.steps_certified) decide every step and joint as the numpy path does (issue 25): on random
groups, rates, velocities, accelerations, end torques and switch jumps, with the limits set exactly at a bound
(so that a bound one unit in the last place off would flip a decision), exact zeros, equal rate bounds, and inputs
the kernel leaves to numpy (non-finite, huge)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from robodesign.judge import arc_torques, interval_kernel
from robodesign.model.robot import COULOMB_SMOOTHING


@pytest.fixture(scope="module")
def kernels():
    assert interval_kernel.warm_up()
    return interval_kernel


def _case(rng, groups: int, steps: int, dof: int):
    """(T, robot, V, acc, c, ends, h): the inputs of _steps_within."""
    scale = 10.0 ** rng.integers(-3, 3)
    T = SimpleNamespace(dm=rng.normal(0, 50, (groups, dof)) * scale, dr=rng.random((groups, dof)) * 20 * scale)
    V = (rng.normal(0, 1, (groups, dof)), rng.random((groups, dof)) * rng.choice([0.0, 0.01, 1.0]))
    a = np.sort(rng.normal(0, 3, (2, groups, dof)), axis=0)
    robot = SimpleNamespace(friction_viscous=rng.random(dof) * rng.choice([0.0, 1.0]),
                            friction_coulomb=rng.random(dof) * rng.choice([0.0, 2.0]))
    c = np.sort(rng.integers(0, groups, steps))
    ta, tb = rng.normal(0, 40, (steps, dof)) * scale, rng.normal(0, 40, (steps, dof)) * scale
    J = rng.random((steps, dof)) * 5 * rng.choice([0.0, 1.0])
    h = np.full((steps, 1), rng.choice([0.01, 0.004, 1e-5]))
    if rng.random() < 0.3:  # zero rates and velocities: equal bounds, ±0
        T.dm[:, 0], T.dr[:, 0], V[0][:, 0], V[1][:, 0], a[:, :, 0] = 0.0, 0.0, -0.0, 0.0, 0.0
        ta[:, 0], tb[:, 0] = -0.0, 0.0
    return T, robot, V, (a[0], a[1]), c, (ta, tb, J), h


def _numpy(T, robot, V, acc, c, ends, h, lim):
    """_steps_within's numpy path, and its bounds (ub, lb)."""
    ta, tb, J = ends
    d_lo, d_hi = arc_torques._with_friction(T, robot, V, acc[0], acc[1])
    ub = arc_torques._upper(ta + J, tb + J, d_lo[c], d_hi[c], h)
    lb = arc_torques._lower(ta - J, tb - J, d_lo[c], d_hi[c], h)
    return (ub <= lim) & (lb >= -lim), ub, lb


def test_kernel_decides_as_numpy(kernels):
    rng = np.random.default_rng(3)
    decided = mixed = 0
    for i in range(300):
        dof = int(rng.integers(1, 8))
        args = _case(rng, int(rng.integers(1, 25)), int(rng.integers(1, 120)), dof)
        with np.errstate(all="ignore"):
            _, ub, lb = _numpy(*args, np.full(dof, np.inf))
        s = rng.integers(0, len(ub), dof)
        lim = np.where(rng.random(dof) < 0.5, ub[s, np.arange(dof)], -lb[s, np.arange(dof)])  # exactly at a bound
        lim = np.where(np.isfinite(lim) & (lim > 0), lim, 1.0)
        with np.errstate(all="ignore"):
            want = _numpy(*args, lim)[0]
        T, robot, V, acc, c, ends, h = args
        f = lambda x: np.ascontiguousarray(x, dtype=float)  # noqa: E731
        got = kernels.steps_certified(f(T.dm), f(T.dr), f(V[0]), f(V[1]), f(acc[0]), f(acc[1]),
                                      f(robot.friction_viscous), f(robot.friction_coulomb), COULOMB_SMOOTHING,
                                      c.astype(np.int64), f(ends[0]), f(ends[1]), f(ends[2]), f(h[:, 0]), f(lim))
        assert got.shape == want.shape and np.array_equal(got, want)
        assert np.array_equal(arc_torques._steps_within(*args, lim), want)
        decided += got.size
        mixed += bool(want.any() and not want.all())
    assert decided > 10000 and mixed > 50  # cases with both certified and open steps


def test_inputs_left_to_numpy(kernels):
    """Non-finite or huge inputs: the kernel declines ((0, dof)) and _steps_within decides by numpy."""
    rng = np.random.default_rng(4)
    for bad in (np.inf, -np.inf, np.nan, 1e200):
        T, robot, V, acc, c, ends, h = _case(rng, 4, 30, 3)
        ends[0][rng.integers(0, 30), 1] = bad
        lim = np.full(3, 100.0)
        f = lambda x: np.ascontiguousarray(x, dtype=float)  # noqa: E731
        got = kernels.steps_certified(f(T.dm), f(T.dr), f(V[0]), f(V[1]), f(acc[0]), f(acc[1]),
                                      f(robot.friction_viscous), f(robot.friction_coulomb), COULOMB_SMOOTHING,
                                      c.astype(np.int64), f(ends[0]), f(ends[1]), f(ends[2]), f(h[:, 0]), f(lim))
        assert got.shape == (0, 3)
        with np.errstate(all="ignore"):
            want = _numpy(T, robot, V, acc, c, ends, h, lim)[0]
            assert np.array_equal(arc_torques._steps_within(T, robot, V, acc, c, ends, h, lim), want)
