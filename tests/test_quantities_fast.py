"""The judge's quantities on their faster paths (issue 25): the goal-time lookup is numpy.isclose's rule, and the
joint poses the TCP twists and the sweep share are batched FK's."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
from conftest import IMPROV, TASKS

from robodesign import load_module_set
from robodesign.formats.assembly import Assembly
from robodesign.formats.task_io import load_task
from robodesign.judge.quantities import TIME_ATOL, TIME_RTOL, TrajectoryQuantities, find_time_index
from robodesign.model.cell import build_robot


def _reference(t, value):
    close = np.nonzero(np.isclose(t, value, rtol=TIME_RTOL, atol=TIME_ATOL))[0]
    return int(close[0]) if len(close) == 1 else None


def test_find_time_index_is_isclose():
    t = np.round(np.arange(351) * 0.01, 12)
    values = [0.0, 0.01, 1.23, 3.5, 3.500000001, 3.5 + 4e-5, 3.5 + 3e-5, -1e-9, 1e-8, 2e-8, 7.0, 100.0, np.inf,
              -np.inf, np.nan, np.float64(1.7), 0.005, 0.015000001]
    rng = np.random.default_rng(0)
    values += list(rng.uniform(0, 3.6, 200)) + list(t[rng.integers(0, 351, 50)] + rng.normal(0, 1e-5, 50))
    found = 0
    for v in values:
        assert find_time_index(t, v) == _reference(t, v), v
        found += find_time_index(t, v) is not None
    assert found > 30  # many values hit a sample (others fall between samples)
    dup = np.array([0.0, 0.01, 0.01, 0.02, np.inf])
    for v in (0.01, 0.0, np.inf, 0.02):
        assert find_time_index(dup, v) == _reference(dup, v)
    assert find_time_index(dup, 0.01) is None and find_time_index(dup, np.inf) == 4


def test_joint_poses_feed_the_twists():
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    robot = build_robot(task, ms, Assembly.from_order(ms, ["1", "21", "4", "22", "5", "23", "12"]), np.eye(4))
    rng = np.random.default_rng(1)
    n = 40
    q = rng.uniform(-2, 2, (n, robot.dof))
    dq = rng.uniform(-1, 1, (n, robot.dof))
    tq = TrajectoryQuantities(robot, np.arange(n) * 0.01, q, dq, np.zeros_like(q), task)
    assert np.array_equal(tq.joint_poses, robot.joint_poses_batch(q))
    for k in (0, 17, n - 1):
        pin.forwardKinematics(robot.model, robot.data, q[k], dq[k])
        pin.updateFramePlacements(robot.model, robot.data)
        v = pin.getFrameVelocity(robot.model, robot.data, robot.tcp_frame, pin.LOCAL_WORLD_ALIGNED).vector
        np.testing.assert_allclose(tq.tcp_twists[k], v, rtol=0, atol=1e-10)
        np.testing.assert_allclose(tq.joint_poses[k, 3], robot.data.oMi[3].homogeneous, rtol=0, atol=1e-12)


def test_cross_is_numpys():
    from robodesign.judge.quantities import _cross
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(500, 3)) * 10 ** rng.uniform(-8, 8, (500, 1)), rng.normal(size=(500, 3))
    a[0], b[1] = np.inf, np.nan
    with np.errstate(invalid="ignore"):
        assert np.array_equal(_cross(a, b), np.cross(a, b), equal_nan=True)
