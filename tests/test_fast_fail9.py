"""The reach bound from the walk's numbers (Robot.reach_bound, Robot._first_joint_origin): on many random orders and
base poses (random ones, and ones with exact zeros, where pinocchio's forward kinematics is still run), (o, R) is bit
for bit the former computation, which ran pinocchio's forward kinematics at the neutral configuration and read the
model's joint and frame placements."""
import math

import numpy as np
import pinocchio as pin
import pytest

from robodesign import Assembly, Robot, load_module_set
from robodesign.formats.assembly import random_serial_order
from robodesign.model import robot_build

from conftest import IMPROV


def _reference_reach(robot: Robot):
    """(o, R) as reach_bound computed them before: forward kinematics at the neutral configuration on a new scratch
    space, the model's placements read through pinocchio."""
    m = robot.kinematic_model
    d = pin.Data(m)
    pin.forwardKinematics(m, d, pin.neutral(m))
    chain = robot.tcp_chain()
    if not chain:
        return pin.updateFramePlacement(m, d, robot.tcp_frame).translation.copy(), 0.0
    o = d.oMi[chain[0]].translation.copy()
    R = sum(float(np.linalg.norm(m.jointPlacements[b].translation)) for b in chain[1:])
    R += float(np.linalg.norm(m.frames[robot.tcp_frame].placement.translation))
    for j in chain:
        if robot.joint_infos[j - 1].type == "prismatic":
            idx = m.joints[j].idx_q
            lo, hi = m.lowerPositionLimit[idx], m.upperPositionLimit[idx]
            R += max(abs(lo), abs(hi)) if np.isfinite(lo) and np.isfinite(hi) else math.inf
    return o, R


def _random_pose(rng) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = pin.rpy.rpyToMatrix(*rng.uniform(-math.pi, math.pi, 3))
    T[:3, 3] = rng.uniform(-1.0, 1.0, 3)
    return T


def _zero_poses(rng):
    """Base poses whose first joint's origin has exact zeros (±0.0): the identity, and rotations about z with the
    x/y translation zero or −0.0."""
    T = np.eye(4)
    yield T
    for z in (0.0, -0.0):
        T = np.eye(4)
        T[:3, :3] = pin.rpy.rpyToMatrix(0.0, 0.0, float(rng.uniform(-3, 3)))
        T[:3, 3] = (z, -0.0, 0.3)
        yield T


def _same(a, b):
    (oa, Ra), (ob, Rb) = a, b
    assert oa.tobytes() == ob.tobytes() and np.float64(Ra).tobytes() == np.float64(Rb).tobytes()


@pytest.mark.parametrize("modules, dofs", [("robodesign_arm", (2, 3, 5, 6, 7)), (IMPROV, (6,))])
def test_reach_bound_is_the_forward_kinematics_one(modules, dofs):
    ms = load_module_set(modules)
    rng = np.random.default_rng(91)
    fast = slow = 0
    for k in range(30):
        asm = Assembly.from_order(ms, random_serial_order(ms, rng, dof=dofs[k % len(dofs)]))
        robot = Robot(ms, asm)   # (no base pose: the walk's own placement of the first joint)
        _same(robot.reach_bound(), _reference_reach(robot))
        for T in [_random_pose(rng) for _ in range(4)] + list(_zero_poses(rng)):
            for r in (Robot(ms, asm, base_pose=T), robot):
                if r is robot:
                    robot.set_base_pose(T)
                t = r.kinematic_model.jointPlacements[r.tcp_chain()[0]].translation
                if all(x != 0.0 for x in t):
                    fast += 1
                else:
                    slow += 1
                got = r.reach_bound()
                _same(got, _reference_reach(r))
                got[0][0] = 123.0   # (a copy: neither the cached bound nor the model changes)
                _same(r.reach_bound(), _reference_reach(r))
    assert fast > 100 and slow > 10


def test_reach_bound_of_short_chains_and_after_base_pose_changes():
    ms = load_module_set("robodesign_arm")
    rng = np.random.default_rng(92)
    for _ in range(40):
        order = random_serial_order(ms, rng, dof=int(rng.integers(1, 4)))
        robot = Robot(ms, Assembly.from_order(ms, order), base_pose=_random_pose(rng))
        for _ in range(3):   # (the cached bound is dropped with each new base pose)
            _same(robot.reach_bound(), _reference_reach(robot))
            robot.set_base_pose(_random_pose(rng))


def test_the_walk_remembers_each_joint_norm_with_its_placement():
    """The norms the walk keeps are vector_norm of the remembered SE3s' translations, equal to numpy's norm."""
    ms = load_module_set("robodesign_arm")
    rng = np.random.default_rng(93)
    for _ in range(10):
        asm = Assembly.from_order(ms, random_serial_order(ms, rng, dof=6))
        for w in (robot_build.walk(ms, asm, False), robot_build.walk(ms, asm, False)):
            assert len(w.joint_norms) == len(w.joint_ops) == w.model.njoints - 1
            for (_, _, X, _), norm in zip(w.joint_ops, w.joint_norms):
                assert np.float64(norm).tobytes() == np.float64(np.linalg.norm(X.translation)).tobytes()

