"""Batched kinematics of a robot whose module set and assembly were read before (model/batch_fk.py _TREES, issue
25): every list and kernel array equals, byte for byte, a full read of the robot's model, over seeded random base
poses and several assemblies, and so do the joint and TCP poses of random configurations, compiled and numpy."""
from __future__ import annotations

import make_tasks as mt  # assets/tasks, on the path by conftest
import numpy as np
import pytest
from conftest import IMPROV
from test_interval_trees import _pose

from robodesign import load_module_set
from robodesign.model import batch_fk, geometry_kernel
from robodesign.model.robot import Robot

_ORDERS = [(IMPROV, ("1", "21", "4", "22", "5", "23", "12")), (IMPROV, ("1", "21", "5", "22", "4", "23", "12")),
           (IMPROV, ("1", "4", "22", "5", "23", "12")), ("robodesign_arm", tuple(mt.DEFAULT_ORDER))]


def _same(a, b) -> bool:
    """Lists of arrays or arrays: equal dtypes, shapes and bytes; anything else: equal."""
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray):
        return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
    return type(a) is type(b) and a == b


@pytest.mark.parametrize("name,order", _ORDERS)
def test_a_kept_tree_reads_as_a_full_read(name, order, monkeypatch):
    ms = load_module_set(name)
    rng = np.random.default_rng(len(order) * 5 + int(order[2]))   # (seeded per assembly)
    batch_fk._TREES.clear()
    batch_fk.batch_kinematics(Robot.from_order(ms, order, base_pose=_pose(rng)))   # the kept tree
    for i in range(8):
        robot = Robot.from_order(ms, order, base_pose=_pose(rng))
        a, b = batch_fk.batch_kinematics(robot), batch_fk._BatchKinematics(robot.kinematic_model)
        assert a.parents is batch_fk._TREES[(id(ms), robot.assembly.key())][1].parents is not b.parents
        for f in ("parents", "R", "t", "kind", "axis", "iq", "z", "njoints"):
            assert _same(getattr(a, f), getattr(b, f)), f
        assert _same(list(a.arrays()), list(b.arrays())) and a.model is b.model
        Q = rng.uniform(-3, 3, (20, robot.dof))
        compiled = i % 2 == 0 or not geometry_kernel.ready()
        monkeypatch.setattr(geometry_kernel, "ready", (lambda: True) if compiled else (lambda: False))
        assert _same(a.joint_poses(Q), b.joint_poses(Q))
        assert _same(a.frame_poses(Q, robot.tcp_frame), b.frame_poses(Q, robot.tcp_frame))
        monkeypatch.undo()
    batch_fk._TREES.clear()
