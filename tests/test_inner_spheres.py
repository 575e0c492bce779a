"""model/inner_spheres.py and the culler's proofs of collision (issue 25): every inner sphere of the IMPROV,
primitive-module and random primitive shapes lies inside its shape (coal's signed distance from the centre to the
shape), and on the PTP_3 arm and random IMPROV and primitive arms (seeded) every pair the compiled bounds prove
colliding is one coal finds colliding (at other margins too), and the culler's verdicts are coal's over every pair,
with proofs taken on a good share of the colliding states."""
import coal
import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV, PRIMITIVES, TASKS

from robodesign.formats.assembly import Assembly, random_serial_order
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.model import geometry_kernel
from robodesign.model.cell import build_robot
from robodesign.model.collision_cull import SLACK, culler_of
from robodesign.model.inner_spheres import MAX_SPHERES, inner_spheres, placed_inner_spheres
from robodesign.model.robot import Robot
from robodesign.solvers.schedule import static_cell

GOOD = ("1", "21", "4", "22", "5", "23", "12")


def depth_inside(shape, point) -> float:
    """How deep ``point`` lies inside ``shape`` (coal: minus the signed distance of a point-like sphere there)."""
    req, res = coal.DistanceRequest(), coal.DistanceResult()
    dot = coal.Sphere(1e-9)
    d = coal.distance(dot, coal.Transform3s(np.eye(3), np.asarray(point, dtype=float)), shape, coal.Transform3s(),
                      req, res)
    return -(d + 1e-9)


def module_shapes():
    """Every collision shape of the IMPROV and primitive module sets (one robot per module of each)."""
    shapes = {}
    for path, dofs in ((IMPROV, (6, 7)), (PRIMITIVES, (3, 8))):
        ms = load_module_set(path)
        rng = np.random.default_rng(0)
        for _ in range(12):
            robot = Robot.from_order(ms, random_serial_order(ms, rng, dof=int(rng.integers(*dofs))))
            for o in list(robot.geom_model.geometryObjects)[:robot.n_collision_geometries]:
                shapes[id(o.geometry)] = o.geometry
    return list(shapes.values())


def random_primitives(n, seed):
    """Random coal spheres, cylinders, capsules and boxes (sizes 1 cm – 30 cm)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        a, b = rng.uniform(0.01, 0.3, 2)
        out += [coal.Sphere(a), coal.Cylinder(a, 2 * b), coal.Capsule(a, 2 * b), coal.Box(*rng.uniform(0.01, 0.3, 3))]
    return out


def test_inner_spheres_lie_inside_their_shapes():
    kinds = set()
    for shape in module_shapes() + random_primitives(25, 1):
        C, r = inner_spheres(shape)
        assert len(r) <= MAX_SPHERES and C.shape == (len(r), 3)
        kind = type(shape).__name__
        if kind in ("Sphere", "Cylinder", "Capsule", "Box") or kind.startswith("Convex"):
            assert len(r) >= 1, kind
            kinds.add(kind)
        for c, rc in zip(C, r):
            assert rc > 0 and depth_inside(shape, c) >= rc - 1e-6, (kind, c, rc)
    assert {"Sphere", "Cylinder", "Capsule", "Box"} <= kinds and any(k.startswith("Convex") for k in kinds)


def test_placed_spheres_are_the_shapes_spheres_in_the_joint_frame():
    rng = np.random.default_rng(2)
    shapes = random_primitives(3, 3)
    placed = [(s, pin.SE3.Random().rotation, rng.normal(size=3)) for s in shapes]
    start, C, r = placed_inner_spheres([s for s, _, _ in placed], [R for _, R, _ in placed], [t for _, _, t in placed])
    assert start[0] == 0 and start[-1] == len(r) == len(C)
    for g, (shape, R, t) in enumerate(placed):
        c0, r0 = inner_spheres(shape)
        np.testing.assert_array_equal(r[start[g]:start[g + 1]], r0)
        np.testing.assert_allclose(C[start[g]:start[g + 1]], c0 @ R.T + t, rtol=0, atol=1e-15)


def pair_collides(robot, k, q, margin=None) -> bool:
    """Coal's verdict on pair ``k`` alone at ``q`` (pinocchio's query on fresh data), with the robot's security
    margins or ``margin``."""
    gd = pin.GeometryData(robot.geom_model)
    for req, own in zip(gd.collisionRequests, robot.geom_data.collisionRequests):
        req.security_margin = own.security_margin if margin is None else margin
    pin.updateGeometryPlacements(robot.model, robot.data, robot.geom_model, gd, q)
    return bool(pin.computeCollision(robot.geom_model, gd, k))


def check_proofs(robot, n, seed):
    """(proofs taken, colliding states): on ``n`` random states and their near neighbours, each proven pair collides
    (coal) and the culled verdicts equal coal's over every pair."""
    rng = np.random.default_rng(seed)
    Q = np.array([robot.random_configuration(rng) for _ in range(n)])
    Q = np.vstack([Q, Q + rng.normal(0.0, 0.05, Q.shape)])
    c = culler_of(robot)
    if c._one is None:
        c._one = c._kernel_args()
    args, *_ = c._one
    proofs = colliding = 0
    for q in Q:
        n_surv, _, proven = geometry_kernel.survivors(q, *args)
        if proven >= 0:
            assert proven in args[-2][:n_surv].tolist()
            assert pair_collides(robot, proven, q)
            proofs += 1
        truth = bool(pin.computeCollisions(robot.model, robot.data, robot.geom_model, robot.geom_data, q, True))
        assert c.in_collision(q) == truth
        colliding += truth
    return proofs, colliding


def ptp3_robot():
    """The good PTP_3 arm in its cell (the CNC mesh as obstacle)."""
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    return build_robot(static_cell(task), ms, Assembly.from_order(ms, GOOD), task.nominal_base_pose)


@pytest.mark.skipif(not geometry_kernel.available(), reason="numba unavailable or ROBODESIGN_JIT=0")
@pytest.mark.parametrize("margin", [-0.004, 0.0, 0.01])
def test_the_kernels_proofs_hold_at_other_self_pair_margins(margin):
    """The self pairs' margins are coal's default (0) in robodesign; the kernel's proof limit (margin − slack) is
    checked at other margins too, against coal's verdict with that security margin."""
    assert geometry_kernel.warm_up() and geometry_kernel.ready()
    robot = ptp3_robot()
    c = culler_of(robot)
    args = list(c._kernel_args()[0])
    assert np.array_equal(args[15], c.self_proof) and np.all(c.self_proof == -SLACK)
    args[10] = args[10] + margin    # the survival limits (radii + margin + slack)
    args[15] = args[15] + margin    # the proof limits (margin − slack)
    rng = np.random.default_rng(7)
    proofs = 0
    for _ in range(300):
        q = robot.random_configuration(rng)
        n, _, proven = geometry_kernel.survivors(q, *args)
        if proven >= 0:
            assert pair_collides(robot, proven, q, margin)
            proofs += 1
    assert proofs > 20


@pytest.mark.skipif(not geometry_kernel.available(), reason="numba unavailable or ROBODESIGN_JIT=0")
def test_proofs_are_coals_verdicts_on_ptp3_and_random_arms():
    assert geometry_kernel.warm_up() and geometry_kernel.ready()
    robots = [ptp3_robot()]
    rng = np.random.default_rng(5)
    for path, dofs in ((IMPROV, (6, 7)), (PRIMITIVES, (3, 8))):
        ms = load_module_set(path)
        robots += [Robot.from_order(ms, random_serial_order(ms, rng, dof=int(rng.integers(*dofs)))) for _ in range(4)]
    proofs = colliding = 0
    for i, robot in enumerate(robots):
        p, c = check_proofs(robot, 150, 10 + i)
        proofs += p
        colliding += c
    assert proofs > 0.2 * colliding > 0
