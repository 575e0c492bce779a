"""The walk's remembered products (model.robot_build._products, _placed): robots built from a warm memory, a cold
one, and one cleared mid-walk are bit for bit the plain walk of tests/test_robot_build (every product made on the
spot), on many random orders (joint placements included: the remembered pin.SE3 of each); the remembered products
are shared read-only and are what ``M @ P`` gives alone."""
import numpy as np
import pinocchio as pin
import pytest

from robodesign import Assembly, Robot, load_module_set
from robodesign.formats.assembly import random_serial_order
from robodesign.model import robot_build

from conftest import IMPROV
from test_robot_build import _assert_equal_to_reference, _same


def _orders(ms, seed: int, n: int, dofs=(3, 5, 6, 7)):
    rng = np.random.default_rng(seed)
    return [random_serial_order(ms, rng, dof=dofs[k % len(dofs)]) for k in range(n)]


@pytest.mark.parametrize("modules, dofs", [("robodesign_arm", (3, 5, 6, 7)), (IMPROV, (6,))])
def test_builds_from_a_warm_memory_are_the_plain_walk(modules, dofs):
    ms = load_module_set(modules)
    for memo in (robot_build._PRODUCTS, robot_build._PLACED, robot_build._JOINT_SE3):
        memo.clear()
    orders = _orders(ms, 11, 24, dofs)
    for order in orders + orders[::-1]:   # (the second time round every product is remembered)
        asm = Assembly.from_order(ms, order)
        _assert_equal_to_reference(Robot(ms, asm), ms, asm)
    assert len(robot_build._PRODUCTS) > 24 and len(robot_build._PLACED) > 0 and len(robot_build._JOINT_SE3) > 0


def test_a_memory_cleared_mid_walk_gives_the_plain_walk(monkeypatch):
    ms = load_module_set("robodesign_arm")
    monkeypatch.setattr(robot_build, "_PRODUCTS_MAX", 3)   # (cleared several times in every walk)
    for order in _orders(ms, 12, 16):
        asm = Assembly.from_order(ms, order)
        for _ in range(2):
            _assert_equal_to_reference(Robot(ms, asm), ms, asm)
    assert max(len(robot_build._PRODUCTS), len(robot_build._PLACED), len(robot_build._JOINT_SE3)) <= 3


def test_remembered_products_are_shared_read_only_and_each_plain_product():
    ms = load_module_set("robodesign_arm")
    order = _orders(ms, 13, 1, dofs=(6,))[0]
    asm = Assembly.from_order(ms, order)
    a, b = robot_build.walk(ms, asm, False), robot_build.walk(ms, asm, False)
    assert len(a.geoms) == len(b.geoms) > 0
    for oa, ob in zip(a.joint_ops, b.joint_ops):             # the joints' placements: one pin.SE3 each, shared
        assert oa[2] is ob[2] and isinstance(oa[2], pin.SE3)
    for ga, gb in zip(a.geoms, b.geoms):
        Ps = ga[3]
        assert Ps is gb[3]                                    # the same objects, not made again
        for P in (Ps,) if isinstance(Ps, np.ndarray) else Ps:
            assert not P.flags.writeable
            with pytest.raises(ValueError):
                P[0, 0] = 1.0
    rng = np.random.default_rng(14)   # each product of a stack is M @ P made alone
    recs = [r for t in robot_build._tables(ms, asm.module_ids, False) for r in t.bodies if r[9] is not None]
    for rec in rng.choice(len(recs), size=min(8, len(recs)), replace=False):
        rec = recs[rec]
        M = rng.normal(size=(4, 4))
        Ps = robot_build._products(next(robot_build._TOKENS), rec, M)
        for P, pose in zip(Ps, rec[10]):
            assert _same(P, M @ pose)


def test_gravity_motions_remembered_per_tuple_are_the_plain_ones():
    """A robot's gravity (at construction and by set_gravity) is bit for bit pinocchio's motion made of it on the
    spot, for tuples met again, equal tuples of other zero signs, lists and numpy floats."""
    from robodesign.model import robot as robot_mod
    ms = load_module_set("robodesign_arm")
    asm = Assembly.from_order(ms, _orders(ms, 15, 1, dofs=(6,))[0])
    rng = np.random.default_rng(16)
    gs = [(0.0, 0.0, -9.81), (-0.0, 0.0, -9.81), (0.0, -0.0, -9.81), [0.0, 0.0, -9.81], (np.float64(1.5), 0.0, -9.0)]
    gs += [tuple(float(x) for x in rng.normal(size=3)) for _ in range(20)]
    for g in gs + gs[::-1]:
        plain = pin.Motion(np.array([*g, 0.0, 0.0, 0.0], dtype=float)).vector
        robot = Robot(ms, asm, gravity=g)
        assert _same(robot.kinematic_model.gravity.vector, plain)
        robot.set_gravity(gs[3])
        robot.set_gravity(g)
        assert _same(robot.model.gravity.vector, plain)
    kept = [g for g in gs if type(g) is tuple and all(type(x) is float for x in g)]
    assert all(robot_mod._GRAVITIES[id(g)][0] is g for g in kept)
    assert id(gs[3]) not in robot_mod._GRAVITIES and id(gs[4]) not in robot_mod._GRAVITIES
