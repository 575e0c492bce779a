"""The hull proofs of collision (model/inner_spheres.hull, geometry_kernel._edge_inside; issue 25): the ends of every
hull edge of the IMPROV and primitive convex shapes lie on their shape (coal) and inside every face plane, the
placed blocks are the hulls in the joints' frames, and on the PTP_3 arm the kernel proves collisions the inner
spheres do not, each one coal's verdict (at other margins too), with the culler's verdicts coal's over every pair."""
import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV, PRIMITIVES
from test_inner_spheres import depth_inside, module_shapes, pair_collides, ptp3_robot, random_primitives

from robodesign.formats.assembly import random_serial_order
from robodesign.formats.module_io import load_module_set
from robodesign.model import geometry_kernel
from robodesign.model.robot import Robot
from robodesign.model.collision_cull import SLACK, culler_of
from robodesign.model.inner_spheres import hull, inner_spheres, placed_inner_spheres

pytestmark = pytest.mark.skipif(not geometry_kernel.available(), reason="numba unavailable or ROBODESIGN_JIT=0")


def test_hull_edges_ends_lie_on_their_shapes_and_inside_every_plane():
    convex = 0
    for shape in module_shapes() + random_primitives(2, 1):
        V, P = hull(shape)
        if not type(shape).__name__.startswith("Convex"):
            assert V.shape == (0, 3) and P.shape == (0, 4)
            continue
        convex += 1
        assert len(V) >= 12 and len(V) % 2 == 0 and len(P) >= 4   # (a tetrahedron's 6 edges at least)
        assert not np.all(V[0::2] == V[1::2], axis=1).any()       # no edge of length 0
        np.testing.assert_allclose(np.linalg.norm(P[:, :3], axis=1), 1.0, atol=1e-12)
        points = np.asarray(shape.points()).reshape(-1, 3)
        assert (points @ P[:, :3].T + P[:, 3]).max() <= 1e-12   # every point of the shape within every plane
        for v in V:
            assert abs(depth_inside(shape, v)) < 1e-6              # an edge's end (a vertex): on the shape's surface
    assert convex >= 5


def test_placed_blocks_are_the_hulls_in_the_joint_frame():
    rng = np.random.default_rng(3)
    shapes = [s for s in module_shapes() if type(s).__name__.startswith("Convex")][:4] + random_primitives(1, 2)
    placed = [(s, pin.SE3.Random().rotation, rng.normal(size=3)) for s in shapes]
    start, rows, values = placed_inner_spheres(*zip(*placed))
    G = len(shapes)
    assert len(start) == 3 * G + 3 and start[0] == 0 and start[-1] == len(rows) == len(values)
    for g, (shape, R, t) in enumerate(placed):
        c0, r0 = inner_spheres(shape)
        V, P = hull(shape)
        np.testing.assert_array_equal(values[start[g]:start[g + 1]], r0)
        np.testing.assert_allclose(rows[start[g]:start[g + 1]], c0 @ R.T + t, rtol=0, atol=1e-15)
        v = slice(start[G + 1 + g], start[G + 2 + g])
        np.testing.assert_allclose(rows[v], V @ R.T + t, rtol=0, atol=1e-15)
        assert not values[v].any()
        p = slice(start[2 * G + 2 + g], start[2 * G + 3 + g])
        x = rng.normal(size=(50, 3))   # a point's plane values are the same in both frames
        np.testing.assert_allclose((x @ R.T + t) @ rows[p].T + values[p], x @ P[:, :3].T + P[:, 3], atol=1e-12)


def _packed(args: list) -> tuple:
    """survivors_packed's arguments before ``last`` (no asks counted)."""
    packed, _ = geometry_kernel.pack(tuple(args))
    return (*packed, np.zeros(0, np.int64), np.zeros(len(args[-2]) + 1, np.int64))


@pytest.mark.parametrize("margin", [-0.004, 0.0, 0.01])
def test_hull_proofs_are_coals_verdicts(margin):
    """Each surviving self pair given as ``last`` in turn: a proof the inner spheres do not give is coal's verdict."""
    assert geometry_kernel.warm_up() and geometry_kernel.ready()
    robot = ptp3_robot()
    c = culler_of(robot)
    args = list(c._kernel_args()[0])
    assert np.all(c.self_proof == -SLACK)
    args[10] = args[10] + margin    # the survival limits (radii + margin + slack)
    args[15] = args[15] + margin    # the proof limits (margin − slack)
    packed = _packed(args)
    out = packed[0][-(len(args[-2]) + len(args[-1])):-len(args[-1])]   # the surviving pairs (a view in the ints)
    rng = np.random.default_rng(9)
    by_hull = 0
    for _ in range(600):
        q = robot.random_configuration(rng)
        n, _, proven, _ = geometry_kernel.survivors_packed(q, *packed, -1)
        assert proven == geometry_kernel.survivors(q, *args)[2]   # no hull tested: the inner spheres' proof
        if proven >= 0:
            continue
        for k in out[:n].tolist():
            if k in c.self_k:
                n2, _, hull_proof, _ = geometry_kernel.survivors_packed(q, *packed, k)
                assert n2 == n and hull_proof in (-1, k)
                if hull_proof == k:
                    assert pair_collides(robot, k, q, margin)
                    by_hull += 1
    assert by_hull >= (3 if margin > 0 else 10), by_hull


def test_culled_verdicts_stay_coals_with_hull_proofs():
    robot = ptp3_robot()
    rng = np.random.default_rng(10)
    c = culler_of(robot)
    Q = np.array([robot.random_configuration(rng) for _ in range(300)])
    colliding = 0
    for q in np.vstack([Q, Q + rng.normal(0.0, 0.03, Q.shape)]):
        truth = bool(pin.computeCollisions(robot.model, robot.data, robot.geom_model, robot.geom_data, q, True))
        assert c.in_collision(q) == truth
        colliding += truth
    assert colliding > 100


def _placed_at_once(shapes, R, t):
    """The placed blocks as they were made before the per-geometry pieces (issue 25, round 11): every row turned by
    one einsum over all geometries, the points moved, the planes' d from all normals at once."""
    G = len(R)
    spheres = [inner_spheres(s) for s in shapes]
    hulls = [hull(s) for s in shapes]
    parts = [c for c, _ in spheres] + [v for v, _ in hulls] + [p[:, :3] for _, p in hulls]
    counts = np.array([len(a) for a in parts], dtype=np.int64)
    owner = np.repeat(np.tile(np.arange(G), 3), counts)
    rows = np.einsum("mij,mj->mi", R[owner], np.concatenate(parts + [np.zeros((0, 3))]))
    start = np.zeros(3 * G + 3, dtype=np.int64)
    ends = np.cumsum(counts)
    for b in range(3):
        start[b * (G + 1)] = ends[b * G - 1] if b and G else 0
        start[b * (G + 1) + 1:(b + 1) * (G + 1)] = ends[b * G:(b + 1) * G]
    n_moved = start[2 * (G + 1)]
    rows[:n_moved] += t[owner[:n_moved]]
    normals, t_p = rows[n_moved:], t[owner[n_moved:]]
    planes_d = np.concatenate([p[:, 3] for _, p in hulls] + [np.zeros(0)]) - (normals * t_p).sum(axis=1)
    values = np.concatenate([r for _, r in spheres] + [np.zeros(start[2 * (G + 1)] - start[G + 1]), planes_d])
    return start, rows, values


def test_placed_blocks_from_pieces_are_bitwise_the_blocks_made_at_once():
    """The blocks put together from the kept per-geometry pieces equal, bit for bit, the blocks made at once over all
    geometries: the shapes and placements of random IMPROV and primitive arms, and random shapes at random
    placements (seeded), each asked twice (the second time from kept pieces)."""
    from robodesign.model.inner_spheres import _placed
    rng = np.random.default_rng(23)
    cases = []
    for path, dofs in ((IMPROV, (6, 7)), (PRIMITIVES, (3, 8))):
        ms = load_module_set(path)
        for _ in range(10):
            robot = Robot.from_order(ms, random_serial_order(ms, rng, dof=int(rng.integers(*dofs))))
            objs = list(robot.geom_model.geometryObjects)[:robot.n_collision_geometries]
            cases.append(([o.geometry for o in objs], np.array([o.placement.rotation for o in objs]),
                          np.array([o.placement.translation for o in objs])))
    pool = module_shapes() + random_primitives(4, 5)
    for _ in range(20):
        shapes = [pool[i] for i in rng.integers(len(pool), size=int(rng.integers(1, 30)))]
        cases.append((shapes, np.array([pin.SE3.Random().rotation for _ in shapes]), rng.normal(size=(len(shapes), 3))))
    for shapes, R, t in cases:
        want = _placed_at_once(shapes, R, t)
        for _ in range(2):
            got = _placed(shapes, R, t)
            for a, b in zip(got, want):
                assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
