"""What a robot's build keeps or makes faster gives the numbers it made before: the scratch space made in place
(``pin.Data(model)``) is ``model.createData()``'s, and the root objects' bounding spheres kept per shapes and
placements are those the formula makes for each robot (``base_collisions``' bounds)."""
import dataclasses

import coal
import numpy as np
import pinocchio as pin

from robodesign import Assembly, Robot, load_module_set
from robodesign.formats.assembly import random_serial_order
from robodesign.model import robot_geometry
from robodesign.model.collision_cull import bounding_sphere
from robodesign.model.robot import Obstacle

from conftest import IMPROV


def _random_pose(rng) -> np.ndarray:
    """A random rigid pose (rotation from a normalised quaternion, translation in a 1 m box)."""
    T = np.eye(4)
    T[:3, :3] = pin.Quaternion(*rng.normal(size=4)).normalized().toRotationMatrix()
    T[:3, 3] = rng.uniform(-1.0, 1.0, 3)
    return T


def _robots(modules: str, n: int, seed: int):
    ms = load_module_set(modules)
    rng = np.random.default_rng(seed)
    for _ in range(n):
        order = random_serial_order(ms, rng, dof=int(rng.integers(3, 8)) if modules != IMPROV else 6)
        yield ms, order, Robot.from_order(ms, order, base_pose=_random_pose(rng))


def test_scratch_space_is_create_datas():
    """On 40 random robots (two module sets): the Data of a new, a moved and a framed robot equals a new
    ``model.createData()`` (pinocchio compares every field), and the kinematics through it are the same numbers."""
    rng = np.random.default_rng(5)
    for modules in ("robodesign_arm", IMPROV):
        for _, _, robot in _robots(modules, 20, 17):
            assert robot.data == robot.model.createData()
            robot.set_base_pose(_random_pose(rng))
            assert robot.data == robot.model.createData()
            q = robot.random_configuration(rng)
            ref = robot.model.createData()
            pin.framesForwardKinematics(robot.model, ref, q)
            assert robot.fk(q).tobytes() == ref.oMf[robot.tcp_frame].homogeneous.tobytes()
            robot.add_frames()
            assert robot.data == robot.model.createData()


def _spheres_by_formula(robot: Robot):
    """The root objects' sphere centres (base frame) and radii, by the formula, for this robot alone."""
    root = sorted(k for kind, k, _ in robot._root_items if kind == "geom")
    C, r = np.zeros((len(root), 3)), np.zeros(len(root))
    for i, a in enumerate(root):
        _, _, _, P, shape = robot._geom_specs[a]
        c, r[i] = bounding_sphere(shape)
        C[i] = P[:3, :3] @ c + P[:3, 3]
    return root, C, r


def test_root_spheres_kept_are_the_formulas():
    """On 60 random robots (two module sets, many sharing their first modules, so kept spheres are met again): the
    root spheres base_collisions bounds with are bit for bit the formula's, and its answer is that of the same robot
    with its spheres computed afresh (nothing kept)."""
    robot_geometry._SPHERES.clear()
    box = Obstacle("box", coal.Box(0.3, 0.3, 0.3), np.eye(4))
    seen, reused = set(), 0
    for modules in ("robodesign_arm", IMPROV):
        for _, _, robot in _robots(modules, 30, 23):
            robot.set_obstacles([box], safety_margin=0.05)
            got = robot.base_collisions()
            root, C, r = _spheres_by_formula(robot)
            kept = robot._root_spheres
            assert kept is not None and kept[0] == root
            assert kept[1].tobytes() == C.tobytes() and kept[2].tobytes() == r.tobytes()
            reused += id(kept[1]) in seen
            seen.add(id(kept[1]))
            saved = dict(robot_geometry._SPHERES)
            robot_geometry._SPHERES.clear()
            robot._root_spheres = robot._obstacle_bounds = robot._base_probe = None
            assert robot.base_collisions() == got
            robot_geometry._SPHERES.update(saved)
    assert reused > 10


def test_root_spheres_follow_the_shapes_and_placements():
    """A module set whose base module's first collision geometry is moved: robots of it get their own spheres (the
    formula's for them), not those kept for the other set's robot with the same module IDs."""
    ms = load_module_set("robodesign_arm")
    order = random_serial_order(ms, np.random.default_rng(3), dof=6)
    base = ms[order[0]]
    shift = np.eye(4)
    shift[:3, 3] = [0.01, -0.02, 0.03]
    bodies = list(base.bodies)
    k = next(i for i, b in enumerate(bodies) if b.collision)
    coll = tuple(dataclasses.replace(g, pose=shift @ g.pose) if j == 0 else g for j, g in enumerate(bodies[k].collision))
    bodies[k] = dataclasses.replace(bodies[k], collision=coll)
    other = dataclasses.replace(ms, modules={**ms.modules, order[0]: dataclasses.replace(base, bodies=tuple(bodies))})
    robots = [Robot(s, Assembly.from_order(s, order), base_pose=np.eye(4)) for s in (ms, other, ms)]
    for robot in robots:
        robot.set_obstacles([Obstacle("box", coal.Box(0.3, 0.3, 0.3), np.eye(4))])
        robot.base_collisions()
        _, C, r = _spheres_by_formula(robot)
        assert robot._root_spheres[1].tobytes() == C.tobytes() and robot._root_spheres[2].tobytes() == r.tobytes()
    assert robots[0]._root_spheres[1].tobytes() != robots[1]._root_spheres[1].tobytes()
    assert robots[0]._root_spheres[1] is robots[2]._root_spheres[1]


def test_collision_objects_made_on_first_use_are_the_plain_walks():
    """On 24 random robots (two module sets): base_collisions answers without the robot's list of collision objects
    where no root pair is near; made later, the list is the plain walk's (names, joints, placements bit for bit,
    test_robot_build's reference), each object's (instance, body) is the one its name says, and the objects fixed
    to the world are the root ones base_collisions bounded."""
    from test_robot_build import _reference
    far = np.eye(4)
    far[:3, 3] = [50.0, 50.0, 50.0]
    box = Obstacle("far", coal.Box(0.1, 0.1, 0.1), far)
    for modules in ("robodesign_arm", IMPROV):
        for ms, order, robot in _robots(modules, 12, 31):
            robot.set_obstacles([box])
            assert robot.base_collisions() == [] and robot._specs is None and robot._bodies_of_geoms is None
            _, geoms, _ = _reference(ms, robot.assembly)
            specs = robot._geom_specs
            assert len(specs) == len(geoms) == robot.n_collision_geometries == len(robot._geom_body)
            for (name, jid, _, P, _), (rname, rjid, RP) in zip(specs, geoms):
                assert (name, jid) == (rname, rjid) and P.tobytes() == RP.tobytes()
            labels = robot.instance_labels
            assert all(name.startswith(f"{labels[i]}.{bid}.") for (name, *_), (i, bid) in zip(specs, robot._geom_body))
            assert [k for k, s in enumerate(specs) if s[1] == 0] == robot._root_spheres[0]


def _order_reference(ms, order):
    """The serial assembly of ``order`` by the chaining rule step by step, nothing remembered (the module order's
    rule as Assembly.from_order applied it before its steps were kept): (module ids, connections, base) or the
    AssemblyError's message."""
    from robodesign.core.errors import AssemblyError
    from robodesign.formats.assembly import _not_one, chain_pairs, free_connectors
    try:
        for i, mid in enumerate(order):
            if mid not in ms.modules:
                raise AssemblyError("unknown")
        bases = [c for c in ms[order[0]].connectors if c.type == "base"]
        if len(bases) != 1:
            raise AssemblyError("bases")
        free, open_, connections = [free_connectors(ms, order[0])], [], []
        open_ = [0] if free[0] else []
        for i in range(1, len(order)):
            cands = [(k, a, b) for k in open_ for a, b in chain_pairs(ms, order[k], free[k], order[i])]
            if len(cands) != 1:
                _not_one(ms, list(order), i, free, cands)
            k, c_old, c_new = cands[0]
            if k != i - 1:
                raise AssemblyError(f"module {order[i]!r} at position {i} would connect to module {order[k]!r} at "
                                    f"position {k}, not to the previous module {order[i-1]!r}: a module order must "
                                    f"form a chain")
            free[k] = tuple(c for c in free[k] if c != c_old.id)
            if not free[k]:
                open_.remove(k)
            free.append(free_connectors(ms, order[i], used=(c_new.id,)))
            if free[i]:
                open_.append(i)
            connections.append((i, c_new.id, k, c_old.id))
        return tuple(order), tuple(connections), (0, bases[0].id)
    except AssemblyError as e:
        return str(e)


def test_module_orders_by_kept_steps_are_the_rules():
    """On 1,200 orders (two module sets: random valid orders, and each with one module replaced, dropped or two
    swapped, most of which do not assemble): the assembly made of kept steps is the rule's step by step, and an
    order that does not assemble raises the same error."""
    from robodesign.core.errors import AssemblyError
    from robodesign.formats import assembly
    rng = np.random.default_rng(41)
    for modules in ("robodesign_arm", IMPROV):
        ms = load_module_set(modules)
        ids = sorted(ms.modules)
        for n in range(200):
            order = list(random_serial_order(ms, rng, dof=int(rng.integers(3, 8)) if modules != IMPROV else 6))
            replaced, dropped, swapped = list(order), list(order), list(order)
            replaced[int(rng.integers(1, len(order)))] = ids[int(rng.integers(len(ids)))]
            del dropped[int(rng.integers(1, len(order)))]
            a, b = rng.integers(1, len(order), 2)
            swapped[a], swapped[b] = swapped[b], swapped[a]
            for o in (order, replaced, dropped, swapped)[: 4 if n % 2 else 2]:
                if n % 50 == 0:
                    assembly._STEPS.clear()
                want = _order_reference(ms, o)
                try:
                    asm = assembly.Assembly._from_order(ms, o)
                    got = (asm.module_ids, asm.connections, asm.base)
                except AssemblyError as e:
                    got = str(e)
                assert got == want


def test_a_pools_new_robot_has_the_cells_gravity():
    """A robot the pool builds for a cell with a gravity of its own (given at construction now, no longer set after
    it) is build_robot's: the same model (pinocchio compares every field, gravity included) and gravity torques."""
    from robodesign.formats.task_io import load_task
    from robodesign.model.cell import RobotPool, build_robot

    from conftest import TASKS
    task = load_task(TASKS / "simple" / "PTP_3.json")
    task = dataclasses.replace(task, header=dataclasses.replace(task.header, gravity=(0.3, -1.7, -9.7)))
    ms = load_module_set(IMPROV)
    rng = np.random.default_rng(2)
    for _ in range(5):
        asm = Assembly.from_order(ms, random_serial_order(ms, rng, dof=6))
        T = _random_pose(rng)
        robot, fresh = RobotPool(task).take(ms, asm, T), build_robot(task, ms, asm, T)
        assert robot.model == fresh.model and robot.model.gravity.vector.tolist() == [0.3, -1.7, -9.7, 0.0, 0.0, 0.0]
        q = robot.random_configuration(rng)
        assert robot.gravity_torque(q).tobytes() == fresh.gravity_torque(q).tobytes()
