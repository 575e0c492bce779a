"""The judge's quantities on their faster paths (issue 25): the goal-time lookup is numpy.isclose's rule, and the
joint poses the TCP twists and the sweep share are batched FK's."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
from conftest import IMPROV, PRIMITIVES, TASKS

from robodesign import load_module_set
from robodesign.core.errors import AssemblyError
from robodesign.formats.assembly import Assembly, random_serial_order
from robodesign.formats.task_io import load_task
from robodesign.judge.quantities import TIME_ATOL, TIME_RTOL, TrajectoryQuantities, _chain_axes, find_time_index
from robodesign.model.cell import build_robot
from robodesign.model.robot import Robot


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


def _former_twists(tq):
    """The twists as tcp_twists computed them before (issue 25, round 7): numpy's batched product and cross."""
    axes = _chain_axes(tq.robot)
    J, p = tq.joint_poses, tq.tcp_poses[:, :3, 3]
    v, w = np.zeros((tq.n, 3)), np.zeros((tq.n, 3))
    for j, iv, prismatic, ax in axes:
        z = J[:, j, :3, :3] @ ax
        qd = tq.dq[:, iv, None]
        if prismatic:
            v += z * qd
        else:
            w += z * qd
            v += np.cross(z, p - J[:, j, :3, 3]) * qd
    return np.hstack([v, w])


def test_twists_are_the_former_formulas_bit_for_bit():
    """On random robots of three module sets (coordinate axes, unaligned and reversed axes, prismatic joints) and
    random, huge and non-finite configurations: every entry equal, signs of zeros and NaNs included."""
    rng = np.random.default_rng(7)
    checked = 0
    for name in (IMPROV, "robodesign_arm", PRIMITIVES):
        ms = load_module_set(name)
        for _ in range(6):
            try:
                asm = Assembly.from_order(ms, random_serial_order(ms, rng, dof=int(rng.integers(1, 8))))
            except AssemblyError:  # (no order of that many joints in the set)
                continue
            robot = Robot(ms, asm, base_pose=np.eye(4))
            if _chain_axes(robot) is None:
                continue
            n = 60
            q = rng.uniform(-4, 4, (n, robot.dof)) * 10.0 ** rng.integers(-3, 4, (n, 1))
            dq = rng.normal(0, 2, (n, robot.dof))
            dq[rng.random((n, robot.dof)) < 0.2] = 0.0
            q[3, 0], q[5, -1], dq[7, 0], q[9] = np.inf, np.nan, np.inf, 1e300
            with np.errstate(invalid="ignore", over="ignore"):
                tq = TrajectoryQuantities(robot, np.arange(n) * 0.01, q, dq, np.zeros_like(q))
                got, want = tq.tcp_twists, _former_twists(tq)
            assert _same_numbers(got, want)
            checked += 1
    assert checked >= 12


def test_compiled_twists_are_the_numpy_path_bit_for_bit():
    """The compiled twists (judge.interval_kernel.tcp_twists) against the numpy path on random robots of three module
    sets and random, huge and non-finite velocities and configurations: every entry equal, signs of zeros and NaNs
    included; a chain whose rotations hold a non-finite entry is left to numpy (None)."""
    from robodesign.judge import interval_kernel
    from robodesign.judge.quantities import _twists_compiled
    assert interval_kernel.warm_up()
    rng = np.random.default_rng(11)
    compiled = fell_back = 0
    for name in (IMPROV, "robodesign_arm", PRIMITIVES):
        ms = load_module_set(name)
        for _ in range(10):
            try:
                asm = Assembly.from_order(ms, random_serial_order(ms, rng, dof=int(rng.integers(1, 8))))
            except AssemblyError:
                continue
            robot = Robot(ms, asm, base_pose=np.eye(4))
            axes = _chain_axes(robot)
            if axes is None:
                continue
            n = int(rng.integers(1, 80))
            q = rng.uniform(-4, 4, (n, robot.dof)) * 10.0 ** rng.integers(-3, 4, (n, 1))
            dq = rng.normal(0, 2, (n, robot.dof)) * 10.0 ** rng.integers(-3, 4, (n, 1))
            dq[rng.random((n, robot.dof)) < 0.2] = 0.0
            dq[rng.random((n, robot.dof)) < 0.1] = -0.0
            dq[rng.integers(0, n)] = rng.choice([np.inf, -np.inf, np.nan, 1e300], robot.dof)
            with np.errstate(invalid="ignore", over="ignore"):
                tq = TrajectoryQuantities(robot, np.arange(n) * 0.01, q, dq, np.zeros_like(q))
                J = tq.joint_poses
                got, want = _twists_compiled(J, tq.tcp_poses, tq.dq, axes), tq._tcp_twists_numpy(J, axes)
                if got is None:
                    continue
                assert _same_numbers(got, want)
                compiled += 1
                q[rng.integers(0, n), 0] = rng.choice([np.inf, np.nan])  # a rotation entry no finite number
                tq = TrajectoryQuantities(robot, np.arange(n) * 0.01, q, dq, np.zeros_like(q))
                if not np.isfinite(tq.joint_poses[:, [j for j, *_ in axes], :3, :3]).all():
                    assert _twists_compiled(tq.joint_poses, tq.tcp_poses, tq.dq, axes) is None
                    fell_back += 1
                    assert _same_numbers(tq.tcp_twists, _former_twists(tq))
    assert compiled >= 12 and fell_back >= 5


def _same_numbers(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal shapes, NaN at the same entries, every other entry equal byte for byte (the sign of a zero included). A
    NaN's sign bit is left out: which operand's NaN an addition passes on is the compiler's choice, and no reader of
    the twists sees it (|x|, norms and comparisons ignore it; Python prints nan)."""
    nan = np.isnan(a)
    return a.shape == b.shape and np.array_equal(nan, np.isnan(b)) and a[~nan].tobytes() == b[~nan].tobytes()
