"""The cheap paths of round 10 for a candidate that fails at IK, each equal to what it replaced:

* the reach bound from the walk's numbers (Robot.reach_bound, Robot._first_joint_origin): on many random orders and
  base poses (random ones, and ones with exact zeros, where pinocchio's forward kinematics is still run), (o, R) is
  bit for bit the former computation, which ran pinocchio's forward kinematics at the neutral configuration and read
  the model's joint and frame placements;
* the base stage's screen tests the spheres' AABB first, box by box (box_screen._group, _clear): all_clear answers as the
  one-by-one test did, on random boxes and spheres;
* the evaluator's settings with the candidate's seed (evaluator.with_seed) are ``dataclasses.replace``'s.
"""
import math

import numpy as np
import pinocchio as pin
import pytest

from robodesign import Assembly, Robot, load_module_set
from robodesign.formats.assembly import random_serial_order
from robodesign.model import box_screen, robot_build

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


def _one_by_one(boxes, centres, limit) -> bool:
    """box_screen.all_clear as it was: every sphere against every box."""
    rows = list(zip(centres.tolist(), limit.tolist()))
    for x0, y0, z0, x1, y1, z1, s in boxes:
        for (x, y, z), lim in rows:
            dx = x0 - x if x < x0 else (x - x1 if x > x1 else 0.0)
            dy = y0 - y if y < y0 else (y - y1 if y > y1 else 0.0)
            dz = z0 - z if z < z0 else (z - z1 if z > z1 else 0.0)
            if not s * (dx * dx + dy * dy + dz * dz) ** 0.5 - box_screen.SLACK_M > lim:
                return False
    return True


def test_the_group_screen_answers_as_the_one_by_one_screen():
    """Random boxes (rotated, some rotations rounded; some singular) and sets of spheres from far off to inside, with
    NaN and infinite numbers mixed in: all_clear answers as the one-by-one test, and where the group test clears the
    spheres of a box, each of them passes the one-by-one test against it; both answers of the group test are met."""
    rng = np.random.default_rng(94)
    group_clear = fallback = 0
    for k in range(3000):
        boxes = []
        for _ in range(int(rng.integers(1, 7))):
            R = pin.Quaternion(*rng.normal(size=4)).normalized().toRotationMatrix()
            R = np.round(R, 3) if k % 3 == 0 else R
            R = np.zeros((3, 3)) if k % 97 == 0 else R
            lo = rng.uniform(-0.5, 0.0, 3)
            boxes.append(box_screen.box_aabb(R, rng.uniform(-1.5, 1.5, 3), lo, lo + rng.uniform(0.01, 1.0, 3)))
        m = int(rng.integers(1, 10))
        C = rng.normal(size=3) * rng.choice([0.5, 2.0, 5.0]) + rng.uniform(-0.3, 0.3, (m, 3)) * rng.choice([0.1, 1.0])
        limit = rng.uniform(0.0, 0.3, m)
        if k % 50 == 1:
            C[int(rng.integers(m)), int(rng.integers(3))] = rng.choice([np.nan, np.inf, -np.inf])
        if k % 50 == 2:
            limit[int(rng.integers(m))] = rng.choice([np.nan, np.inf])
        want = _one_by_one(boxes, C, limit)
        assert box_screen.all_clear(boxes, C, limit) == want
        group = box_screen._group(list(zip(C.tolist(), limit.tolist())))
        assert (group is not None) == bool(np.isfinite(C).all() and np.isfinite(limit).all())
        for box in boxes:
            if group is not None and box_screen._clear(box, *group):
                group_clear += 1
                assert _one_by_one([box], C, limit)
            elif _one_by_one([box], C, limit):
                fallback += 1
    assert group_clear > 1000 and fallback > 200, (group_clear, fallback)


def test_with_seed_is_dataclasses_replace():
    """Random settings (every field drawn), seeds: the same type, the same fields in the same order as ``replace``
    gives, the original unchanged; a subclass and an object with an extra attribute go through ``replace``."""
    import dataclasses

    from robodesign.design.evaluator import with_seed
    from robodesign.design.stages import SolveSettings
    rng = np.random.default_rng(95)
    for _ in range(200):
        kw = {}
        for f in dataclasses.fields(SolveSettings):
            v = getattr(SolveSettings(), f.name)
            kw[f.name] = (not v) if isinstance(v, bool) else int(rng.integers(1, 500)) if isinstance(v, int) else \
                float(rng.uniform(0.001, 5.0)) if isinstance(v, float) else v
        s = SolveSettings(**kw)
        before = dict(s.__dict__)
        seed = int(rng.integers(0, 2 ** 32))
        got, want = with_seed(s, seed), dataclasses.replace(s, seed=seed)
        assert type(got) is SolveSettings and list(got.__dict__.items()) == list(want.__dict__.items())
        assert got == want and got is not s and s.__dict__ == before
        assert dataclasses.asdict(got) == dataclasses.asdict(want)

    @dataclasses.dataclass
    class Sub(SolveSettings):
        extra: int = 3

    assert type(with_seed(Sub(extra=4), 9)) is Sub and with_seed(Sub(extra=4), 9).extra == 4
    s = SolveSettings()
    s.note = "kept by neither"
    got = with_seed(s, 5)
    assert got.seed == 5 and not hasattr(got, "note")


@pytest.mark.parametrize("modules, dofs", [("robodesign_arm", (3, 5, 6, 7)), (IMPROV, (6,))])
def test_root_spheres_kept_by_the_walk_key_are_the_plain_ones(modules, dofs, monkeypatch):
    """The base stage's spheres of the objects fixed to the world (kept per the walk's key of the root bodies: their
    placement's token and record), for robots built from a cold memory, a warm one and one cleared mid-walk, at random
    base poses: bit for bit each object's bounding sphere placed by its own placement."""
    from robodesign.model import robot_geometry
    from robodesign.model.collision_cull import bounding_sphere
    ms = load_module_set(modules)
    rng = np.random.default_rng(96)
    robot_geometry._SPHERES.clear()
    orders = [random_serial_order(ms, rng, dof=dofs[k % len(dofs)]) for k in range(16)]
    kept = 0
    for limit in (None, 3):
        if limit is not None:
            monkeypatch.setattr(robot_build, "_PRODUCTS_MAX", limit)
        for order in orders + orders[::-1]:
            robot = Robot(ms, Assembly.from_order(ms, order), base_pose=_random_pose(rng))
            robot.set_obstacles([])
            robot._base_pairs_near()
            root, C, r = robot._root_spheres
            assert root == [g for g, _, _ in robot._root_geoms] and len(root) > 0
            for i, (_, P, shape) in enumerate(robot._root_geoms):
                c, ri = bounding_sphere(shape)
                assert C[i].tobytes() == (P[:3, :3] @ c + P[:3, 3]).tobytes() and r[i] == ri
            kept += C is robot_geometry._SPHERES[robot._root_key][0]
    assert kept == 64 and len(robot_geometry._SPHERES) < 64


@pytest.mark.parametrize("modules, dofs", [("robodesign_arm", (3, 5, 6, 7)), (IMPROV, (6,))])
def test_root_placements_shared_read_only_place_as_copies(modules, dofs):
    """The walk's placements on joint 0 are the remembered products themselves (read-only, shared by robots); placed
    at random base poses, the first joint, the root objects (geometry made before and after the pose) and the frames
    are bit for bit ``pin.SE3(T @ copy)`` of a fresh copy of each."""
    ms = load_module_set(modules)
    rng = np.random.default_rng(97)
    for k in range(12):
        asm = Assembly.from_order(ms, random_serial_order(ms, rng, dof=dofs[k % len(dofs)]))
        for geometry_first in (False, True):
            robot = Robot(ms, asm)
            if geometry_first:
                robot.geom_model
            robot.add_frames()
            T = _random_pose(rng)
            robot.set_base_pose(T)
            gm, m = robot.geom_model, robot.kinematic_model
            kinds = set()
            for kind, idx, M in robot._root_items:
                kinds.add(kind)
                want = pin.SE3(T @ np.array(M)).homogeneous.tobytes()
                got = (m.jointPlacements[idx] if kind == "joint" else m.frames[idx].placement if kind == "frame"
                       else gm.geometryObjects[idx].placement)
                assert got.homogeneous.tobytes() == want
                if kind != "frame":
                    assert not M.flags.writeable
            assert kinds == {"joint", "geom", "frame"}
