"""Symbolic CasADi RNEA / drivetrain torque / FK against pinocchio and Robot, on real module sets."""

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from conftest import COBRA as _COBRA

from robodesign import Assembly, Robot, load_module_set
from robodesign.solvers.casadi_dynamics import (casadi_drivetrain_torque, casadi_fk, casadi_rnea)

COBRA = _COBRA / "modules"
TOL = 1e-9

IMPROV_ORDERS = [
    ["1", "21", "4", "22", "5", "23", "12"],
    ["1", "21", "4", "21", "23", "12"],
    ["1", "21", "14", "22", "6", "23", "13"],
    ["1", "22", "5", "23", "12"],
]


@pytest.fixture(scope="module")
def improv():
    return load_module_set(COBRA / "IMPROV")


@pytest.fixture(scope="module")
def prims():
    return load_module_set(COBRA / "geometric_primitive_modules")


def _samples(robot, rng, n=20):
    for _ in range(n):
        q = rng.uniform(-np.pi, np.pi, robot.dof)
        for j, info in enumerate(robot.joint_infos):
            if info.type == "prismatic":
                q[j] = rng.uniform(robot.q_lower[j], robot.q_upper[j])
        yield q, rng.uniform(-2.0, 2.0, robot.dof), rng.uniform(-5.0, 5.0, robot.dof)


def _check_robot(robot, rng):
    rnea = casadi_rnea(robot)
    rnea_arm = casadi_rnea(robot, include_armature=True)
    dtt = casadi_drivetrain_torque(robot)
    fk = casadi_fk(robot)
    other = robot.model.nframes // 2
    fk_other = casadi_fk(robot, other)
    data = robot.model.createData()
    for q, dq, ddq in _samples(robot, rng):
        np.testing.assert_allclose(rnea(q, dq, ddq).full().ravel(), robot.rnea(q, dq, ddq), rtol=0, atol=TOL)
        np.testing.assert_allclose(rnea_arm(q, dq, ddq).full().ravel(), pin.rnea(robot.model, data, q, dq, ddq),
                                   rtol=0, atol=TOL)
        np.testing.assert_allclose(dtt(q, dq, ddq).full().ravel(), robot.drivetrain_torques(q, dq, ddq)[0],
                                   rtol=0, atol=TOL)
        for f, fid in ((fk, None), (fk_other, other)):
            p, R = f(q)
            T = robot.fk(q, fid)
            np.testing.assert_allclose(p.full().ravel(), T[:3, 3], rtol=0, atol=TOL)
            np.testing.assert_allclose(R.full(), T[:3, :3], rtol=0, atol=TOL)


@pytest.mark.parametrize("order", IMPROV_ORDERS, ids=lambda o: "-".join(o))
def test_improv_assemblies_match_pinocchio(improv, order):
    Assembly.from_order(improv, order)  # a valid serial order
    robot = Robot.from_order(improv, order)
    assert np.any(robot.friction_viscous > 0) and np.any(robot.model.armature > 0)
    _check_robot(robot, np.random.default_rng(len(order)))


def test_nondefault_gravity_and_base_pose(improv):
    robot = Robot.from_order(improv, IMPROV_ORDERS[0])
    robot.set_gravity([1.5, -2.0, -3.7])
    T = np.eye(4)
    T[:3, :3] = pin.rpy.rpyToMatrix(0.3, -0.2, 1.1)
    T[:3, 3] = [0.4, -0.1, 0.25]
    robot.set_base_pose(T)
    _check_robot(robot, np.random.default_rng(7))


def test_prismatic_primitive_assembly(prims):
    order = ["base", "J2", "i_30", "J1", "l_15", "J2", "eef"]
    Assembly.from_order(prims, order)
    robot = Robot.from_order(prims, order)
    assert [j.type for j in robot.joint_infos] == ["revolute", "prismatic", "revolute"]
    assert "JointModelPZ" in [j.shortname() for j in robot.model.joints]
    # the primitive set has no drivetrain parameters: give it some so those terms are exercised too
    robot.friction_viscous = np.array([0.7, 3.0, 0.2])
    robot.friction_coulomb = np.array([1.1, 0.4, 2.0])
    robot.model.armature = np.array([0.3, 0.05, 0.8])
    robot.set_gravity([0.0, 3.0, -9.0])
    _check_robot(robot, np.random.default_rng(3))


def test_unaligned_joints_on_a_tree():
    """RevoluteUnaligned / PrismaticUnaligned (what reversed modules become) and X/Y joints, branching."""
    rng = np.random.default_rng(11)
    model = pin.Model()

    def se3():
        return pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3) * 0.3)

    def axis():
        v = rng.normal(size=3)
        return v / np.linalg.norm(v)

    joints = [pin.JointModelRevoluteUnaligned(*axis()), pin.JointModelPrismaticUnaligned(*axis()),
              pin.JointModelRevoluteUnaligned(0.0, 0.0, -1.0), pin.JointModelPrismaticUnaligned(0.0, 0.0, -1.0),
              pin.JointModelRX(), pin.JointModelPY(), pin.JointModelRY(), pin.JointModelPX()]
    parents = [0, 1, 2, 2, 1, 5, 0, 7]
    for k, (jm, par) in enumerate(zip(joints, parents)):
        jid = model.addJoint(par, jm, se3(), f"j{k}")
        model.appendBodyToJoint(jid, pin.Inertia.Random(), pin.SE3.Identity())
    fid = model.addFrame(pin.Frame("tool", 6, 0, se3(), pin.FrameType.OP_FRAME))
    model.gravity = pin.Motion(np.array([0.5, 2.0, -7.0, 0.0, 0.0, 0.0]))
    model.armature = rng.uniform(0.0, 1.0, model.nv)
    data = model.createData()
    f_arm = casadi_rnea(model, include_armature=True)
    f_link = casadi_rnea(model)
    fk = casadi_fk(model, fid)
    for _ in range(20):
        q, dq, ddq = rng.uniform(-3, 3, (3, model.nv))
        tau = pin.rnea(model, data, q, dq, ddq)
        np.testing.assert_allclose(f_arm(q, dq, ddq).full().ravel(), tau, rtol=0, atol=TOL)
        np.testing.assert_allclose(f_link(q, dq, ddq).full().ravel(), tau - model.armature * ddq, rtol=0, atol=TOL)
        pin.framesForwardKinematics(model, data, q)
        p, R = fk(q)
        np.testing.assert_allclose(p.full().ravel(), data.oMf[fid].translation, rtol=0, atol=TOL)
        np.testing.assert_allclose(R.full(), data.oMf[fid].rotation, rtol=0, atol=TOL)


def test_functions_are_sx_and_usable_in_an_expanded_nlp(improv):
    robot = Robot.from_order(improv, IMPROV_ORDERS[3])
    f = casadi_drivetrain_torque(robot)
    assert f.is_a("SXFunction")
    assert casadi_fk(robot).is_a("SXFunction")
    # hold a pose statically: find q̈ = 0, q̇ = 0 torques via an expanded NLP = gravity torque
    q0 = np.array([0.2, -0.4, 0.9, 0.1])
    opti = ca.Opti()
    tau = opti.variable(robot.dof)
    opti.minimize(ca.sumsqr(tau - f(q0, np.zeros(robot.dof), np.zeros(robot.dof))))
    opti.solver("ipopt", {"expand": True, "print_time": False, "ipopt": {"print_level": 0, "sb": "yes"}})
    sol = opti.solve()
    np.testing.assert_allclose(sol.value(tau), robot.gravity_torque(q0), atol=1e-6)


def test_unsupported_joint_raises():
    model = pin.Model()
    jid = model.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "ball")
    model.appendBodyToJoint(jid, pin.Inertia.Random(), pin.SE3.Identity())
    with pytest.raises(NotImplementedError):
        casadi_rnea(model)
