"""The planner's static test without RNEA where no configuration can need more torque than the joints have (issue 25,
round 9): ``static_validity.gravity_bound`` bounds |g(q)| over every configuration, and where it is below the
torque limits (less Coulomb friction) the test skips pinocchio's gravity torques, with the same verdicts."""
import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV

from robodesign.formats.assembly import Assembly, random_serial_order
from robodesign.formats.module_io import load_module_set
from robodesign.model.robot import Robot
from robodesign.solvers import static_validity
from robodesign.solvers.static_validity import gravity_bound, static_validator

GOOD = ("1", "21", "4", "22", "5", "23", "12")


def random_robots(n, seed):
    """``n`` random robots: robodesign_arm's random orders (2–7 joints) and every fourth the good IMPROV arm of PTP_3;
    half upright (the root joint's axis along gravity) and half at a random tilt, some with a random gravity
    vector."""
    arm, improv = load_module_set("robodesign_arm"), load_module_set(IMPROV)
    rng = np.random.default_rng(seed)
    for i in range(n):
        ms = improv if i % 4 == 3 else arm
        order = GOOD if ms is improv else random_serial_order(ms, rng, dof=int(rng.integers(2, 8)))
        T = np.eye(4)
        if rng.uniform() < 0.5:
            T[:3, :3] = pin.exp3(rng.normal(0.0, 0.8, 3))
        T[:3, 3] = rng.uniform(-0.5, 0.5, 3)
        robot = Robot(ms, Assembly.from_order(ms, order), base_pose=T)
        if rng.uniform() < 0.25:
            robot.set_gravity(rng.normal(0.0, 6.0, 3))
        yield robot


def configurations(robot, rng, n):
    """``n`` random configurations in [−2π, 2π] per joint (the bound holds everywhere, not only within limits)."""
    return rng.uniform(-2 * np.pi, 2 * np.pi, (n, robot.dof))


def test_the_bound_holds_on_every_configuration():
    """|computeGeneralizedGravity| never exceeds the bound, on 60 random robots × 300 configurations and at each
    joint's worst pose found by a coordinate search from the largest sample; the root joint's bound is small on an
    upright base with gravity along its axis (the refinement is at work)."""
    rng = np.random.default_rng(5)
    upright = 0
    for robot in random_robots(60, 11):
        model, data = robot.model, robot.model.createData()
        bound = gravity_bound(model)
        assert bound is not None   # every joint of these sets is revolute
        Q = configurations(robot, rng, 300)
        G = np.abs(np.array([pin.computeGeneralizedGravity(model, data, q) for q in Q]))
        assert (G <= bound).all()
        for j in range(robot.dof):   # climb toward the worst pose of joint j
            q = Q[int(np.argmax(G[:, j]))].copy()
            for _ in range(3):
                for k in range(robot.dof):
                    grid = np.linspace(-np.pi, np.pi, 73)
                    vals = []
                    for x in grid:
                        q[k] = x
                        vals.append(abs(pin.computeGeneralizedGravity(model, data, q)[j]))
                    q[k] = grid[int(np.argmax(vals))]
            assert abs(pin.computeGeneralizedGravity(model, data, q)[j]) <= bound[j]
        g = model.gravity.linear
        axis = model.jointPlacements[1].rotation[:, 2]
        if np.linalg.norm(np.cross(g, axis)) < 1e-12 * np.linalg.norm(g) and model.joints[1].shortname() == "JointModelRZ":
            upright += 1
            assert bound[0] < 1e-3 * max(bound[1:].max(initial=0.0), 1.0)
    assert upright >= 10


def test_no_bound_without_revolute_joints_only():
    """A model with a prismatic or a free-flyer joint has no bound (the static test keeps its RNEA)."""
    model = pin.buildSampleModelHumanoidRandom()
    assert gravity_bound(model) is None
    model = pin.Model()
    j = model.addJoint(0, pin.JointModelPZ(), pin.SE3.Identity(), "slide")
    model.appendBodyToJoint(j, pin.Inertia.Random(), pin.SE3.Identity())
    assert gravity_bound(model) is None


@pytest.mark.parametrize("seed", [3, 4])
def test_the_verdicts_are_those_of_the_rnea_test(seed, monkeypatch):
    """``ok`` and ``ok.rows`` with the bound give the verdicts of the test that always asks pinocchio (the bound
    disabled), on random robots with their torque limits scaled from 0.05 to 4 times (so that the bound clears some
    and not others), with and without rests; both cases many times, and both verdicts."""
    rng = np.random.default_rng(seed)
    skipped = asked = rejected = 0
    for robot in random_robots(40, seed):
        for scale in (0.05, 0.3, 1.0, 4.0):
            base_tau = robot.tau_max
            robot.tau_max = base_tau * scale
            Q = np.vstack([rng.uniform(robot.q_lower, robot.q_upper, (80, robot.dof)),
                           configurations(robot, rng, 20)])
            rest = [Q[0], Q[1]] if rng.uniform() < 0.5 else []
            fast = static_validator(robot, True, rest)
            with monkeypatch.context() as m:
                m.setattr(static_validity, "gravity_bound", lambda model: None)
                slow = static_validator(robot, True, rest)
            want = np.array([slow(q) for q in Q])
            assert np.array_equal(slow.rows(Q), want)
            assert np.array_equal(fast.rows(Q), want)
            assert np.array_equal(np.array([fast(q) for q in Q]), want)
            bound = gravity_bound(robot.model)
            clears = bool(np.all(bound < np.minimum(robot.tau_max, robot.tau_max - robot.friction_coulomb)))
            skipped += clears
            asked += not clears
            rejected += int((~want).sum())
            robot.tau_max = base_tau
    assert skipped >= 20 and asked >= 20 and rejected >= 100


def test_the_good_ptp3_arm_skips_the_rnea():
    """The known-good IMPROV arm of PTP_3 (upright) needs no gravity torques in the planner's static test."""
    ms = load_module_set(IMPROV)
    robot = Robot(ms, Assembly.from_order(ms, GOOD))
    bound = gravity_bound(robot.model)
    assert np.all(bound < robot.tau_max - robot.friction_coulomb)


def test_the_bound_kept_per_robot_follows_its_base_and_gravity():
    """The static test's bound, whose lever sums are kept per robot, is the bound of the robot's model as it is now
    after each change of base pose or gravity (bytes), on 20 random robots and 5 changes each; and it holds there."""
    from robodesign.solvers.static_validity import _robot_bound
    rng = np.random.default_rng(8)
    for robot in random_robots(20, 21):
        for _ in range(5):
            assert _robot_bound(robot).tobytes() == gravity_bound(robot.model).tobytes()
            T = np.eye(4)
            T[:3, :3] = pin.exp3(rng.normal(0.0, 1.0, 3))
            T[:3, 3] = rng.uniform(-1, 1, 3)
            robot.set_base_pose(T)
            if rng.uniform() < 0.5:
                robot.set_gravity(rng.normal(0.0, 6.0, 3))
            model, data = robot.model, robot.model.createData()
            G = np.abs(np.array([pin.computeGeneralizedGravity(model, data, q)
                                 for q in configurations(robot, rng, 50)]))
            assert (G <= _robot_bound(robot)).all()
