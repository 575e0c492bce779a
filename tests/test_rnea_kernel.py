"""The compiled RNEA (robodesign.model.rnea_kernel) against pinocchio's rnea, one call per sample: the same torques
bit for bit on random IMPROV and geometric-primitive arms at random base poses and gravities, on random trees of
every covered joint type, with and without armature; models it does not cover keep pinocchio."""
import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV, PRIMITIVES

from robodesign import Robot, load_module_set
from robodesign.core.spatial import homogeneous, rpy_to_matrix
from robodesign.design.search_space import SearchSpace
from robodesign.model import rnea_batch, rnea_kernel

COVERED = ("RX", "RY", "RZ", "PX", "PY", "PZ")


@pytest.fixture(scope="module", autouse=True)
def compiled():
    assert rnea_kernel.warm_up()


def _samples(rng, n, nv):
    """(Q, V, A) (n, nv): moderate and large values, zero rows, a −0.0."""
    Q, V, A = (rng.uniform(-3, 3, (n, nv)) for _ in range(3))
    Q[::7] *= 300.0
    V[1::5] *= 1e3
    A[2::6] *= -1e4
    V[::4] = 0.0
    A[3::5] = 0.0
    A[0, 0] = -0.0
    return Q, V, A


def _pinocchio(model, Q, V, A):
    data = model.createData()
    return np.array([pin.rnea(model, data, Q[k], V[k], A[k]) for k in range(len(Q))])


def _assert_same(model, rng, n=60):
    """The kernel's torques and pinocchio's, compared as bytes, with the model's armature and without."""
    Q, V, A = _samples(rng, n, model.nv)
    packed = rnea_kernel.pack(model)
    assert packed is not None
    assert rnea_kernel.rnea(*packed, Q, V, A).tobytes() == _pinocchio(model, Q, V, A).tobytes()
    bare = pin.Model(model)
    bare.armature = np.zeros(model.nv)
    assert rnea_kernel.rnea(*rnea_kernel.pack(model, armature=False), Q, V, A).tobytes() == \
        _pinocchio(bare, Q, V, A).tobytes()


def _random_gravity(rng):
    if rng.random() < 0.5:
        return pin.Motion(np.array([0.0, 0.0, -9.81]), np.zeros(3))
    return pin.Motion(rng.normal(0.0, 5.0, 3), rng.normal(0.0, 1.0, 3) * (rng.random() < 0.3))


@pytest.mark.parametrize("folder", [IMPROV, PRIMITIVES])
def test_random_arms_give_pinocchios_torques_bit_for_bit(folder):
    ms, rng = load_module_set(folder), np.random.default_rng(11)
    space, covered = SearchSpace(ms), 0
    for _ in range(40):
        pose = homogeneous(rpy_to_matrix(*rng.uniform(-np.pi, np.pi, 3)), rng.uniform(-2, 2, 3))
        model = Robot.from_order(ms, list(space.random_order(rng)), base_pose=pose).model
        model.gravity = _random_gravity(rng)
        if rnea_kernel.pack(model) is None:
            continue
        covered += 1
        _assert_same(model, rng)
    assert covered >= 20


def _random_tree(rng, n):
    """A pinocchio model of n joints of the covered types on a random tree, random placements and inertias."""
    model = pin.Model()
    for k in range(1, n + 1):
        jm = getattr(pin, "JointModel" + COVERED[rng.integers(len(COVERED))])()
        R = pin.utils.rpyToMatrix(*rng.uniform(-np.pi, np.pi, 3))
        j = model.addJoint(int(rng.integers(k)), jm, pin.SE3(R, rng.normal(0, 0.4, 3)), f"j{k}")
        L = rng.normal(0, 1, (3, 3))
        model.appendBodyToJoint(j, pin.Inertia(rng.uniform(0.1, 5), rng.normal(0, 0.2, 3), L @ L.T + np.eye(3) * 0.01),
                                pin.SE3.Identity())
    model.armature = rng.uniform(0, 2, model.nv) * (rng.random(model.nv) < 0.7)
    model.gravity = _random_gravity(rng)
    return model


def test_random_trees_of_every_covered_joint_give_pinocchios_torques_bit_for_bit():
    rng = np.random.default_rng(5)
    for n in (1, 2, 3, 6, 7, 9, 12) * 4:
        _assert_same(_random_tree(rng, n), rng, n=25)


def test_an_uncovered_joint_keeps_pinocchio():
    """A reversed module's RevoluteUnaligned joint: no arrays, and rnea_rows gives pinocchio's torques."""
    rng = np.random.default_rng(2)
    model = _random_tree(rng, 4)
    model.addJoint(2, pin.JointModelRevoluteUnaligned(0.0, 0.0, -1.0), pin.SE3.Random(), "rev")
    model.armature = np.zeros(model.nv)
    assert rnea_kernel.pack(model) is None
    Q, V, A = _samples(rng, rnea_batch.KERNEL_ROWS + 20, model.nv)
    assert rnea_batch.rnea_rows(model, Q, V, A).tobytes() == _pinocchio(model, Q, V, A).tobytes()


def _fail(*args, **kwargs):
    raise AssertionError("the other path ran")


def test_rnea_rows_runs_the_kernel_from_kernel_rows_samples_on(monkeypatch):
    """On a covered arm: the kernel from KERNEL_ROWS samples on (no pool asked), pinocchio's pool below (the
    kernel not called); both pinocchio's torques bit for bit."""
    ms, rng = load_module_set(IMPROV), np.random.default_rng(8)
    model = Robot.from_order(ms, ["1", "21", "4", "22", "5", "23", "12"]).model
    many = _samples(rng, rnea_batch.KERNEL_ROWS, model.nv)
    few = tuple(x[:rnea_batch.KERNEL_ROWS - 1] for x in many)
    for link_side in (False, True):
        bare = pin.Model(model)
        if link_side:
            bare.armature = np.zeros(model.nv)
        with monkeypatch.context() as m:
            m.setattr(rnea_batch, "_pool", _fail)
            assert rnea_batch.rnea_rows(model, *many, link_side=link_side).tobytes() == \
                _pinocchio(bare, *many).tobytes()
        with monkeypatch.context() as m:
            m.setattr(rnea_kernel, "rnea", _fail)
            assert rnea_batch.rnea_rows(model, *few, link_side=link_side).tobytes() == \
                _pinocchio(bare, *few).tobytes()


def test_a_kernel_that_differs_from_this_pinocchio_keeps_pinocchio(monkeypatch):
    """Where the kernel's torques differ from this pinocchio's in one last bit (another build: fused multiply-adds),
    the packed model is not used: rnea_rows gives pinocchio's torques, and the kernel is not asked again."""
    ms, rng = load_module_set(IMPROV), np.random.default_rng(9)
    robot = Robot.from_order(ms, ["1", "21", "4", "22", "5", "23", "12"])
    robot.set_base_pose(homogeneous(rpy_to_matrix(0.1, -0.2, 0.3), [0.3, 0.1, 0.2]))   # a model of its own
    model = robot.model
    Q, V, A = _samples(rng, rnea_batch.KERNEL_ROWS + 5, model.nv)
    exact = rnea_kernel.rnea
    asked = []

    def off_by_one_bit(*args):
        asked.append(len(args[-1]))
        tau = exact(*args)
        tau[0, 0] = np.nextafter(tau[0, 0], np.inf)
        return tau

    monkeypatch.setattr(rnea_kernel, "rnea", off_by_one_bit)
    for link_side in (False, True):
        bare = pin.Model(model)
        if link_side:
            bare.armature = np.zeros(model.nv)
        assert rnea_batch.rnea_rows(model, Q, V, A, link_side=link_side).tobytes() == \
            _pinocchio(bare, Q, V, A).tobytes()
    assert asked == [3, 3]   # the self-check's samples only, once per side
    assert rnea_batch._packed(model, False) is None and rnea_batch._packed(model, True) is None
