"""IntervalDynamics of a robot whose module set and assembly were read before (judge/interval_rnea.py _TREES, issue
25): every field and every kernel argument equals, byte for byte, a full read of the robot's model, over seeded
random base poses, gravities and several assemblies; and the enclosures of link_torques on random boxes are equal."""
from __future__ import annotations

import make_tasks as mt  # assets/tasks, on the path by conftest
import numpy as np
import pytest
from conftest import IMPROV

from robodesign import load_module_set
from robodesign.judge import interval_rnea
from robodesign.judge.interval_rnea import IntervalDynamics
from robodesign.model.robot import Robot

_ORDERS = [(IMPROV, ("1", "21", "4", "22", "5", "23", "12")), (IMPROV, ("1", "21", "5", "22", "4", "23", "12")),
           (IMPROV, ("1", "4", "22", "5", "23", "12")), ("robodesign_arm", tuple(mt.DEFAULT_ORDER))]
_FIELDS = ("dof", "parents", "kinds", "signs", "R", "p", "mass", "lever", "inertia", "gravity", "tcp_joint",
           "tcp_offset")


def _pose(rng) -> np.ndarray:
    """A random base pose (a rotation by random angles about x, y, z and a translation)."""
    T = np.eye(4)
    for axis, angle in enumerate(rng.uniform(-np.pi, np.pi, 3)):
        c, s = np.cos(angle), np.sin(angle)
        i, j = [k for k in range(3) if k != axis]
        Rk = np.eye(3)
        Rk[i, i], Rk[i, j], Rk[j, i], Rk[j, j] = c, -s, s, c
        T[:3, :3] = Rk @ T[:3, :3]
    T[:3, 3] = rng.uniform(-1.0, 1.0, 3)
    return T


def _bytes(x):
    """A field as comparable bytes (lists of arrays item by item)."""
    if isinstance(x, list):
        return [np.asarray(v).tobytes() + str(np.asarray(v).dtype).encode() for v in x]
    return np.asarray(x).tobytes()


def _fresh(robot) -> IntervalDynamics:
    """IntervalDynamics by a full read of the robot's model (no kept tree)."""
    saved = dict(interval_rnea._TREES)
    interval_rnea._TREES.clear()
    try:
        return IntervalDynamics(robot)
    finally:
        interval_rnea._TREES.clear()
        interval_rnea._TREES.update(saved)


@pytest.mark.parametrize("name,order", _ORDERS)
def test_a_kept_tree_reads_as_a_full_read(name, order):
    ms = load_module_set(name)
    rng = np.random.default_rng(len(order) * 7 + int(order[2]))   # (seeded per assembly)
    interval_rnea._TREES.clear()
    IntervalDynamics(Robot.from_order(ms, order, base_pose=_pose(rng)))   # the kept tree, another base pose
    adopted = 0
    for _ in range(8):
        g = rng.normal(0.0, 9.81, 3) if rng.random() < 0.5 else (0.0, 0.0, -9.81)
        robot = Robot.from_order(ms, order, base_pose=_pose(rng), gravity=g)
        assert interval_rnea._TREES[(id(ms), robot.assembly.key())][0] is ms
        a, b = IntervalDynamics(robot), _fresh(robot)
        adopted += a.parents is not b.parents
        for f in _FIELDS:
            assert _bytes(getattr(a, f)) == _bytes(getattr(b, f)), f
        for x, y in zip(a._kernel_args, b._kernel_args):
            assert x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()
        P, n = 5, robot.dof
        Q = (rng.uniform(-3, 3, (P, n)), rng.uniform(0, 0.2, (P, n)))
        V = (rng.uniform(-1, 1, (P, n)), rng.uniform(0, 0.1, (P, n)))
        acc = (rng.uniform(-2, 2, (P, n)), np.zeros((P, n)))
        ta, tb = a.link_torques(Q, V, acc), b.link_torques(Q, V, acc)
        for f in ("m", "r", "dm", "dr"):
            assert getattr(ta, f).tobytes() == getattr(tb, f).tobytes()
    assert adopted == 8
    interval_rnea._TREES.clear()
