"""The robot build (model.robot_build): bit for bit the model of a plain walk that makes every product where it is
needed and adds every frame as it comes (pinocchio's own zero-inertia sums), and tables that cannot go stale."""
import dataclasses
from collections import deque

import numpy as np
import pinocchio as pin
import pytest

from robodesign import Assembly, Robot, load_module_set
from robodesign.core.spatial import inv
from robodesign.formats.assembly import random_serial_order
from robodesign.formats.geometry import coal_shapes
from robodesign.model import robot_build

from conftest import IMPROV


def _reference(ms, asm):
    """The model, collision objects (name, joint, placement) and TCP placement of ``asm`` by a plain walk: pinocchio
    objects made on the spot, each product ``M @ pose`` made alone, every body and connector frame added when its body
    is met (with pinocchio's default, the frame's zero inertia appended)."""
    model, labels, counts = pin.Model(), [], {}
    for mid in asm.module_ids:
        labels.append(mid if mid not in counts else f"{mid}-{counts[mid]}")
        counts[mid] = counts.get(mid, 0) + 1
    conn = {}
    for a, ca, b, cb in asm.connections:
        conn[(a, ca)], conn[(b, cb)] = (b, cb), (a, ca)
    base = ms[asm.module_ids[asm.base[0]]].connector(asm.base[1])
    queue, seen, jframe, geoms, free = deque([(asm.base[0], base.body_id, 0, base.entry_pose)]), set(), {0: 0}, [], []
    while queue:
        i, bid, jid, M = queue.popleft()
        if (i, bid) in seen:
            continue
        seen.add((i, bid))
        mod = ms[asm.module_ids[i]]
        body, name = mod.body(bid), f"{labels[i]}.{bid}"
        if body.mass > 0:
            model.appendBodyToJoint(jid, pin.Inertia(body.mass, np.asarray(body.com, float),
                                                     np.asarray(body.inertia, float)), pin.SE3(M))
        bf = model.addFrame(pin.Frame(name, jid, jframe[jid], pin.SE3(M), pin.FrameType.BODY))
        for c in body.connectors:
            model.addFrame(pin.Frame(f"{name}.{c.id}", jid, bf, pin.SE3(M @ c.pose), pin.FrameType.OP_FRAME))
            other = conn.get((i, c.id))
            if other is not None:
                c2 = ms[asm.module_ids[other[0]]].connector(other[1])
                if (other[0], c2.body_id) not in seen:
                    queue.append((other[0], c2.body_id, jid, (M @ c.pose) @ c2.entry_pose))
            elif (i, c.id) != asm.base:
                free.append((jid, M, c))
        for gi, g in enumerate(body.collision):
            P = M @ g.pose
            geoms += [(f"{name}.c{gi}" + (f".{si}" if si else ""), jid, P) for si, _ in enumerate(coal_shapes(g))]
        for jt in mod.joints:
            if jt.parent == bid:
                other, rev, P, Q = jt.child, False, jt.pose_parent, jt.pose_child
            elif jt.child == bid:
                other, rev, P, Q = jt.parent, True, inv(jt.pose_child), inv(jt.pose_parent)
            else:
                continue
            if (i, other) in seen:
                continue
            placement = M @ P
            if jt.type == "fixed":
                queue.append((i, other, jid, placement @ Q))
                continue
            if jt.type == "revolute":
                jm = pin.JointModelRevoluteUnaligned(0.0, 0.0, -1.0) if rev else pin.JointModelRZ()
            else:
                jm = pin.JointModelPrismaticUnaligned(0.0, 0.0, -1.0) if rev else pin.JointModelPZ()
            new = model.addJoint(jid, jm, pin.SE3(placement), f"{labels[i]}.{jt.id}")
            jframe[new] = model.addJointFrame(new, -1)
            queue.append((i, other, new, Q))
    eefs = [f for f in free if f[2].type == "eef"]
    tj, M, c = eefs[0] if len(eefs) == 1 else free[-1]
    Mc = M @ c.pose
    model.addFrame(pin.Frame("TCP", tj, jframe[tj], pin.SE3(Mc), pin.FrameType.OP_FRAME))
    return model, geoms, Mc


def _same(a, b) -> bool:
    return np.asarray(a).tobytes() == np.asarray(b).tobytes()   # (bit for bit, signs of zeros too)


def _assert_equal_to_reference(robot: Robot, ms, asm):
    ref, geoms, Mc = _reference(ms, asm)
    m = robot.add_frames()
    assert list(m.names) == list(ref.names) and list(m.parents) == list(ref.parents)
    assert [j.shortname() for j in m.joints] == [j.shortname() for j in ref.joints]
    for a, b in zip(m.jointPlacements, ref.jointPlacements):
        assert _same(a.homogeneous, b.homogeneous)
    for a, b in zip(m.inertias, ref.inertias):   # the zero inertias of the frames included
        assert a.mass == b.mass and _same(a.lever, b.lever) and _same(a.inertia, b.inertia)
    frames = {f.name: f for f in ref.frames}
    assert sorted(f.name for f in m.frames) == sorted(frames)
    for f in m.frames:
        g = frames[f.name]
        assert (f.parentJoint, f.type, m.frames[f.parentFrame].name) == (g.parentJoint, g.type,
                                                                         ref.frames[g.parentFrame].name)
        assert _same(f.placement.homogeneous, g.placement.homogeneous) and _same(f.inertia.lever, g.inertia.lever)
    assert _same(m.frames[robot.tcp_frame].placement.homogeneous, Mc)
    objs = robot.geom_model.geometryObjects
    assert len(objs) == len(geoms) == robot.n_collision_geometries
    for o, (name, jid, P) in zip(objs, geoms):
        assert (o.name, o.parentJoint) == (name, jid) and _same(o.placement.homogeneous, P)


@pytest.mark.parametrize("modules, dofs", [("robodesign_arm", (3, 6, 6, 7)), (IMPROV, (6, 6, 6))])
def test_the_build_is_the_plain_walk_bit_for_bit(modules, dofs):
    ms = load_module_set(modules)
    rng = np.random.default_rng(7)
    for dof in dofs:
        order = random_serial_order(ms, rng, dof=dof)
        asm = Assembly.from_order(ms, order)
        _assert_equal_to_reference(Robot(ms, asm), ms, asm)


def _heavier(ms, module_id: str):
    """A copy of module set ``ms`` whose module ``module_id`` (same ID) has other numbers: its last body 1.5 times as
    heavy, its first collision geometry and its joints' child poses moved."""
    mod = ms[module_id]
    shift = np.eye(4)
    shift[:3, 3] = [0.01, -0.02, 0.03]
    bodies = list(mod.bodies)
    b = bodies[-1]
    coll = tuple(dataclasses.replace(g, pose=shift @ g.pose) if k == 0 else g for k, g in enumerate(b.collision))
    bodies[-1] = dataclasses.replace(b, mass=1.5 * b.mass, collision=coll)
    joints = tuple(dataclasses.replace(j, pose_child=shift @ j.pose_child) for j in mod.joints)
    new = dataclasses.replace(mod, bodies=tuple(bodies), joints=joints)
    return dataclasses.replace(ms, modules={**ms.modules, module_id: new})


def test_tables_are_per_module_object_and_cannot_go_stale():
    """Two module sets with the same module IDs but other numbers build different robots, each that of its own
    specs (the plain walk's); building one does not change what the other builds."""
    ms = load_module_set("robodesign_arm")
    rng = np.random.default_rng(3)
    order = random_serial_order(ms, rng, dof=6)
    jm = next(mid for mid in order if ms[mid].dof == 1 and ms[mid].kind == "joint")
    other = _heavier(ms, jm)
    T = np.eye(4)
    T[:3, 3] = [0.2, -0.1, 0.3]
    a1 = Robot(ms, Assembly.from_order(ms, order), base_pose=T)
    b = Robot(other, Assembly.from_order(other, order), base_pose=T)
    a2 = Robot(ms, Assembly.from_order(ms, order), base_pose=T)
    assert robot_build.module_table(ms[jm], False) is not robot_build.module_table(other[jm], False)
    assert b.mass > a1.mass
    assert not all(_same(x.homogeneous, y.homogeneous) for x, y in zip(a1.model.jointPlacements,
                                                                       b.model.jointPlacements))
    assert a1.model == a2.model and b.model != a1.model   # (pinocchio compares every field)
    for r, s in ((a1, ms), (b, other)):
        asm = Assembly.from_order(s, order)
        _assert_equal_to_reference(Robot(s, asm), s, asm)
        fresh = Robot(s, asm)
        fresh.set_base_pose(T)
        assert fresh.model == r.model


def test_base_pose_and_frames_as_a_new_robot():
    """A robot placed at construction, placed again, or placed after add_frames: the same model and objects."""
    ms = load_module_set("robodesign_arm")
    order = random_serial_order(ms, np.random.default_rng(11), dof=6)
    T = np.array([[0.0, -1.0, 0.0, 0.5], [1.0, 0.0, 0.0, -0.25], [0.0, 0.0, 1.0, 0.125], [0.0, 0.0, 0.0, 1.0]])
    a = Robot.from_order(ms, order, base_pose=T)
    b = Robot.from_order(ms, order)
    b.set_base_pose(np.eye(4) * 2.0)
    b.set_base_pose(T)
    assert a.model == b.model
    a.add_frames()
    c = Robot.from_order(ms, order)
    c.add_frames()
    c.set_base_pose(T)
    assert a.model == c.model
    assert [(k, i, M.tobytes()) for k, i, M in a._root_items] == [(k, i, M.tobytes()) for k, i, M in c._root_items]
    with pytest.raises(Exception, match="finite 4x4"):
        a.set_base_pose(np.full((4, 4), np.nan))
