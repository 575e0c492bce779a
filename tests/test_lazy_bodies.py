"""A robot's bodies are added to its pinocchio model at the first ask for ``Robot.model`` (robot_build.add_bodies):
the robot's own kinematics before that ask reads ``kinematic_model`` (the same object, without the bodies' inertias)
and gives the numbers of a robot whose model was asked first, and the model asked later is the plain walk's bit for
bit (test_robot_build's reference: pinocchio adding each body, frame and the TCP with its zero inertia as it comes)."""
import copy

import coal
import numpy as np
import pinocchio as pin

from robodesign import Assembly, Robot, load_module_set
from robodesign.formats.assembly import random_serial_order
from robodesign.model.cell import RobotPool, build_robot
from robodesign.model.robot import Obstacle

from conftest import IMPROV
from test_build_caches import _random_pose
from test_robot_build import _reference, _same


def _pairs(modules: str, n: int, seed: int):
    """``n`` random robots of ``modules`` at random base poses, each with a twin whose model was asked first."""
    ms = load_module_set(modules)
    rng = np.random.default_rng(seed)
    for _ in range(n):
        asm = Assembly.from_order(ms, random_serial_order(ms, rng, dof=int(rng.integers(3, 8)) if modules != IMPROV
                                                          else 6))
        T = _random_pose(rng)
        twin = Robot(ms, asm, base_pose=T)
        twin.model   # noqa: B018 - the ask that adds the bodies
        yield ms, asm, Robot(ms, asm, base_pose=T), twin, rng


def _kinematics(robot: Robot, rng) -> list:
    """What a design that fails before its dynamics asks of its robot: the reach bound, the generic rank, the base's
    collisions with a box near it, forward kinematics, Jacobians and self-collision at random configurations."""
    robot.set_obstacles([Obstacle("box", coal.Box(0.3, 0.3, 0.3), robot.base_pose.copy())])
    out = [robot.reach_bound(), robot.generic_rank(), robot.base_collisions()]
    for _ in range(3):
        q = robot.random_configuration(rng)
        out += [robot.fk(q), robot.jacobian(q), robot.in_self_collision(q)]
    return out


def _equal(a, b) -> bool:
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(_equal(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray):
        return _same(a, b)
    return a == b


def test_kinematics_before_the_bodies_are_those_after():
    """On 48 random robots (two module sets): the kinematic queries leave the bodies unadded and answer bit for bit
    as the twin whose model was asked first, with the same scratch space (pinocchio compares every field)."""
    for modules in ("robodesign_arm", IMPROV):
        for _, _, robot, twin, rng in _pairs(modules, 24, 11):
            state = rng.bit_generator.state
            got = _kinematics(robot, rng)
            rng.bit_generator.state = state
            assert robot._bodies_of is not None   # (no kinematic query asked for the model)
            assert _equal(got, _kinematics(twin, rng))
            assert robot.data == twin.data and robot.kinematic_model is robot.model
            assert robot._bodies_of is None and robot.model == twin.model


def test_the_model_asked_later_is_the_plain_walks():
    """On 40 random robots: the model asked after the kinematics has the plain walk's inertias (bit for bit, signs of
    zeros too) and joints, and its dynamics (RNEA with armature, gravity torques, mass matrix) are the twin's."""
    for modules in ("robodesign_arm", IMPROV):
        for ms, asm, robot, twin, rng in _pairs(modules, 20, 23):
            _kinematics(robot, rng)
            ref, _, _ = _reference(ms, asm)
            m = robot.model
            assert m.njoints == ref.njoints and list(m.names) == list(ref.names)
            for a, b in zip(m.inertias, ref.inertias):
                assert a.mass == b.mass and _same(a.lever, b.lever) and _same(a.inertia, b.inertia)
            q, dq, ddq = (robot.random_configuration(rng) for _ in range(3))
            assert _same(robot.gravity_torque(q), twin.gravity_torque(q))
            assert _same(robot.drivetrain_torques(q[None], dq[None], ddq[None]),
                         twin.drivetrain_torques(q[None], dq[None], ddq[None]))
            assert _same(robot.mass_matrix(q), twin.mass_matrix(q))


def test_a_pool_robot_taken_back_is_a_fresh_build():
    """A pool robot of each of 12 random assemblies, taken, used for its kinematics, given back and taken at another
    base pose, has the model and scratch space of a fresh ``build_robot`` there, and its gravity torques."""
    ms = load_module_set("robodesign_arm")
    rng = np.random.default_rng(31)
    pool = RobotPool(None)
    for _ in range(12):
        asm = Assembly.from_order(ms, random_serial_order(ms, rng, dof=int(rng.integers(3, 8))))
        robot = pool.take(ms, asm, _random_pose(rng))
        assert robot.reach_bound()[1] > 0 and robot.generic_rank() >= 0
        pool.give_back(robot)
        T = _random_pose(rng)
        again, fresh = pool.take(ms, asm, T), build_robot(None, ms, asm, T)
        assert again is robot and again.model == fresh.model and again.data == fresh.data
        q = again.random_configuration(rng)
        assert _same(again.gravity_torque(q), fresh.gravity_torque(q))
        assert isinstance(again.model, pin.Model)


def test_a_shallow_copy_shares_the_one_addition():
    """A shallow copy of a robot made before its model was asked for (as test_topp_kernel's scaled robots are)
    shares the model: asked through the copy, then through the original, the bodies are added once, and both have
    the twin's model and gravity torques."""
    for ms, asm, robot, twin, rng in _pairs("robodesign_arm", 8, 41):
        other = copy.copy(robot)
        assert other.model == twin.model and robot.model == twin.model and robot.model is other.model
        q = robot.random_configuration(rng)
        assert _same(robot.gravity_torque(q), twin.gravity_torque(q))
