"""Forward kinematics batched over samples (Robot.fk_batch, Robot.joint_poses_batch) against pinocchio's
per-sample forward kinematics: IMPROV arms on a rotated, shifted base, a primitive arm with prismatic joints
and an arm with joints about −z; both ways, the compiled loops (robodesign.model.geometry_kernel) and numpy's
pass."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV, PRIMITIVES

from robodesign.core.errors import InputError
from robodesign.core.spatial import homogeneous, rpy_to_matrix
from robodesign.formats.module_io import load_module_set
from robodesign.model.robot import Robot, fk_batch

BASE = homogeneous(rpy_to_matrix(0.3, -0.2, 1.0), [1.0, 2.0, 0.5])


@pytest.fixture(autouse=True)
def both_ways(geometry_paths):
    """Every test both ways (conftest.geometry_paths: the compiled kernels, and numpy's pass)."""
    return geometry_paths


@pytest.fixture(scope="module")
def robots(tmp_path_factory):
    from test_urdf import reversed_robot
    imp = load_module_set(IMPROV)
    prim = load_module_set(PRIMITIVES)
    rs = [Robot.from_order(imp, ["1", "21", "4", "22", "5", "23", "12"]),
          Robot.from_order(imp, ["1", "22", "5", "23", "15", "29", "101"], base_pose=BASE),
          Robot.from_order(prim, ["base", "J2", "i_30", "J1", "l_15", "J2", "eef"]),
          reversed_robot(tmp_path_factory.mktemp("rev"))]
    shorts = {r.model.joints[j].shortname() for r in rs for j in range(1, r.model.njoints)}
    assert {"JointModelRZ", "JointModelPZ", "JointModelRevoluteUnaligned"} <= shorts  # every branch of the pass
    return rs


def samples(robot, n, seed):
    rng = np.random.default_rng(seed)
    return np.array([robot.random_configuration(rng) for _ in range(n)])


def test_tcp_poses_equal_pinocchio(robots):
    for k, robot in enumerate(robots):
        Q = samples(robot, 64, k)
        F = robot.fk_batch(Q)
        assert F.shape == (64, 4, 4)
        ref = np.array([robot.fk(q) for q in Q])
        assert np.max(np.abs(F - ref)) < 1e-12
        assert np.array_equal(F[:, 3], np.tile([0.0, 0.0, 0.0, 1.0], (64, 1)))


def test_any_frame_and_every_joint(robots):
    robot = robots[1]
    robot.add_frames()   # every body and connector frame too
    Q = samples(robot, 16, 7)
    J = robot.joint_poses_batch(Q)
    assert J.shape == (16, robot.model.njoints, 4, 4)
    for i, q in enumerate(Q):
        pin.framesForwardKinematics(robot.model, robot.data, q)
        for j in range(robot.model.njoints):
            assert np.max(np.abs(J[i, j] - robot.data.oMi[j].homogeneous)) < 1e-12
        for f in range(robot.model.nframes):
            want = robot.data.oMf[f].homogeneous
            assert np.max(np.abs(fk_batch(robot, Q[i:i + 1], f)[0] - want)) < 1e-12


def test_base_pose_change_and_input_checks(robots):
    robot = Robot.from_order(load_module_set(IMPROV), ["1", "21", "4", "22", "5", "23", "12"])
    Q = samples(robot, 8, 3)
    before = robot.fk_batch(Q)
    robot.set_base_pose(BASE)                       # the cached chain follows the base
    after = robot.fk_batch(Q)
    assert np.max(np.abs(after - BASE @ before)) < 1e-12
    assert robot.fk_batch(Q[0]).shape == (1, 4, 4)  # one configuration
    with pytest.raises(InputError):
        robot.fk_batch(np.zeros((3, robot.dof + 1)))


def test_plus_z_test_equals_numpy_allclose():
    """batch_fk._is_plus_z decides as ``np.allclose(ax, (0, 0, 1), atol=0)`` did: on exact, signed-zero, non-finite
    and random axes, and on the neighbours of its tolerance's bounds."""
    from robodesign.model.batch_fk import _is_plus_z
    rng = np.random.default_rng(7)
    edge = [1.0 + 1e-5, 1.0 - 1e-5, np.nextafter(1.0 + 1e-5, 2.0), np.nextafter(1.0 - 1e-5, 0.0),
            np.nextafter(1.0 + 1e-5, 0.0), np.nextafter(1.0 - 1e-5, 2.0), 1.0, -1.0, 0.0, -0.0]
    small = [0.0, -0.0, 5e-324, -5e-324, 1e-12, np.nan, np.inf, -np.inf]
    axes = [(x, y, z) for x in small for y in small[:3] for z in edge + small]
    axes += [tuple(float(v) for v in a) for a in rng.normal(size=(300, 3))]
    axes += [(0.0, 0.0, float(z)) for z in 1.0 + rng.normal(0.0, 2e-5, 300)]
    for ax in axes:
        assert _is_plus_z(ax) == bool(np.allclose(ax, (0.0, 0.0, 1.0), atol=0.0)), ax
