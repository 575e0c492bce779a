"""The collision set-up of a robot made at once (issue 25): the scratch space's requests that
``RobotGeometry._apply_margins`` copies from two templates are those the request-by-request loop sets (every field,
coal's own serialisation), the margins it records are the requests' own, and the collision culler's pairs, margins
and obstacle groups (``collision_cull.pair_ends``, ``pair_margins``) are those read pair by pair from pinocchio's
model and data; with them the culled verdicts and every pair's coal state stay those of the reference."""
import warnings

import coal
import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV, TASKS, boxes_around

from robodesign.formats.assembly import Assembly
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.model.cell import build_robot
from robodesign.model.collision_cull import CollisionCuller, distance_field, pair_ends, pair_margins, tight_sphere
from robodesign.solvers.schedule import static_cell

GOOD = ("1", "21", "4", "22", "5", "23", "12")
FIELDS = ("break_distance", "cached_gjk_guess", "cached_support_func_guess", "distance_upper_bound",
          "enable_cached_gjk_guess", "enable_contact", "enable_distance_lower_bound", "enable_timings",
          "epa_max_iterations", "epa_tolerance", "gjk_convergence_criterion", "gjk_convergence_criterion_type",
          "gjk_initial_guess", "gjk_max_iterations", "gjk_tolerance", "gjk_variant", "num_max_contacts",
          "security_margin")


@pytest.fixture(scope="module")
def robot():
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    return build_robot(static_cell(task), ms, Assembly.from_order(ms, GOOD), task.nominal_base_pose)


def boxes(robot, seed, n=3):
    return boxes_around(robot, seed, n)


def request(req) -> tuple:
    with warnings.catch_warnings():   # (two of the fields are deprecated)
        warnings.simplefilter("ignore", DeprecationWarning)
        return (req.saveToString(),) + tuple(np.asarray(getattr(req, f)).tobytes() if isinstance(
            getattr(req, f), np.ndarray) else str(getattr(req, f)) for f in FIELDS)


def loop_margins(robot, gd) -> None:
    """The reference: every request of a new scratch space set one by one."""
    for k, req in enumerate(gd.collisionRequests):
        req.enable_contact = True
        if k >= robot.n_self_collision_pairs:
            req.security_margin = robot.safety_margin


@pytest.mark.parametrize("margin", [0.0, 0.0125])
def test_requests_made_at_once_are_those_set_one_by_one(robot, margin):
    obstacles, before = list(robot.obstacles), robot.safety_margin
    try:
        robot.set_obstacles(obstacles + boxes(robot, 2), safety_margin=margin)
        gd = robot.geom_data
        ref = pin.GeometryData(robot.geom_model)
        loop_margins(robot, ref)
        assert len(gd.collisionRequests) == len(ref.collisionRequests) > robot.n_self_collision_pairs > 0
        assert [request(r) for r in gd.collisionRequests] == [request(r) for r in ref.collisionRequests]
        # the record the culler bounds with is each request's margin, for this scratch space only
        m = robot.request_margins(gd)
        assert np.array_equal(m, [r.security_margin for r in ref.collisionRequests])
        assert m[-1] == margin and m[0] == 0.0
        assert robot.request_margins(ref) is None
        assert np.array_equal(pair_margins(robot, gd), m)
        assert np.array_equal(pair_margins(object(), ref), m)   # read request by request
    finally:
        robot.set_obstacles(obstacles, safety_margin=before)


def test_a_new_scratch_space_has_its_own_margin_record(robot):
    obstacles, before = list(robot.obstacles), robot.safety_margin
    try:
        robot.set_obstacles(obstacles, safety_margin=0.02)
        gd = robot.geom_data
        assert robot.request_margins(gd)[-1] == 0.02
        robot.set_obstacles(obstacles, safety_margin=0.03)   # a new scratch space: the record is of it alone
        assert robot.request_margins(robot.geom_data)[-1] == 0.03
        assert robot.request_margins(gd) is None and gd.collisionRequests[len(gd.collisionRequests) - 1].security_margin == 0.02
        c = CollisionCuller(robot)
        _, kk, geo, limit = c.obstacles[0]
        assert np.array_equal(limit, c.radius[geo] + 0.03 + 1e-4)
    finally:
        robot.set_obstacles(obstacles, safety_margin=before)


def test_pair_ends_are_the_pairs_of_the_model(robot):
    gm = robot.geom_model
    first, second = pair_ends(gm, robot.n_collision_geometries)
    assert list(zip(first.tolist(), second.tolist())) == [(cp.first, cp.second) for cp in gm.collisionPairs]
    # a model whose pair lists an obstacle first: the bounds take the pair either way round
    g = pin.GeometryModel()
    for i in range(4):
        g.addGeometryObject(pin.GeometryObject(f"g{i}", 0, 0, pin.SE3.Identity(), coal.Sphere(0.1)))
    for a, b in ((0, 1), (3, 0), (1, 2), (2, 3)):
        g.addCollisionPair(pin.CollisionPair(a, b))
    f, s = pair_ends(g, 3)
    assert list(zip(f.tolist(), s.tolist())) == [(0, 1), (0, 3), (1, 2), (2, 3)]
    g.removeCollisionPair(pin.CollisionPair(0, 1))
    f, s = pair_ends(g, 3)
    assert list(zip(f.tolist(), s.tolist())) == [(cp.first, cp.second) if cp.first < cp.second else
                                                 (cp.second, cp.first) for cp in g.collisionPairs]


def reference_culler(robot) -> dict:
    """The culler's arrays read pair by pair (its construction before issue 25's round 5)."""
    gm, gd = robot.geom_model, robot.geom_data
    n_robot = robot.n_collision_geometries
    pairs = [(cp.first, cp.second) for cp in gm.collisionPairs]
    margin = np.array([req.security_margin for req in gd.collisionRequests], dtype=float)
    selfp = [k for k, (a, b) in enumerate(pairs) if a < n_robot and b < n_robot]
    by_ob: dict = {}
    for k, (a, b) in enumerate(pairs):
        if a < n_robot <= b:
            by_ob.setdefault(b, []).append(k)
    objs = gm.geometryObjects
    spheres = [tight_sphere(objs[i].geometry) for i in range(n_robot)]
    local = [np.asarray(objs[i].placement.rotation) @ c + np.asarray(objs[i].placement.translation) for i, (c, _) in
             enumerate(spheres)]
    return {"parent": [int(objs[i].parentJoint) for i in range(n_robot)], "local": np.array(local),
            "radius": np.array([r for _, r in spheres]), "self_k": selfp, "self_a": [pairs[k][0] for k in selfp], "self_b": [pairs[k][1] for k in selfp],
            "active": list(gd.activeCollisionPairs), "margin": margin, "obstacles": [
                (ob, ks, [pairs[k][0] for k in ks]) for ob, ks in by_ob.items()]}


def test_culler_arrays_are_those_read_pair_by_pair(robot):
    obstacles, before = list(robot.obstacles), robot.safety_margin
    try:
        robot.set_obstacles(boxes(robot, 5) + obstacles + boxes(robot, 6, 2), safety_margin=0.01)
        robot.geom_data.deactivateCollisionPair(3)
        c, ref = CollisionCuller(robot), reference_culler(robot)
        assert c.parent.tolist() == ref["parent"] and np.array_equal(c.local, ref["local"])
        assert np.array_equal(c.radius, ref["radius"])
        assert c.self_k.tolist() == ref["self_k"] and c.self_a.tolist() == ref["self_a"]
        # (the pairs this build's earlier cullers proved never to collide start switched off: collision_cull._PROOFS)
        carried = {k for k, ends in (c._known or {}).items()
                   if ref["active"][k] and ends == (c.first[k], c.second[k], ref["margin"][k] + 1e-4, True)}
        assert c.self_b.tolist() == ref["self_b"] and not c.active[3] and c.proven == len(carried)
        assert c.active.tolist() == [a and k not in carried for k, a in enumerate(ref["active"])]
        assert np.array_equal(c.self_limit, c.radius[c.self_a] + c.radius[c.self_b] + ref["margin"][c.self_k] + 1e-4)
        objs = robot.geom_model.geometryObjects
        assert len(c.obstacles) == len(ref["obstacles"]) == len(robot.obstacles)
        for (field, kk, geo, limit), (ob, ks, ga) in zip(c.obstacles, ref["obstacles"]):
            assert field is distance_field(objs[ob].geometry, objs[ob].placement.homogeneous)
            assert kk.tolist() == ks and geo.tolist() == ga
            assert np.array_equal(limit, c.radius[geo] + ref["margin"][kk] + 1e-4)
    finally:
        robot.set_obstacles(obstacles, safety_margin=before)


def test_kept_pairs_make_the_model_fresh_pairs_make(robot):
    """The robot–obstacle pairs added from the process's kept CollisionPair objects: the same pairs, in the same
    order, and the same pair map as pairs made one by one; a longer column later keeps the shorter one's pairs."""
    from robodesign.model.robot_geometry import _pair_column
    obstacles, before = list(robot.obstacles), robot.safety_margin
    try:
        robot.set_obstacles(obstacles + boxes(robot, 7), safety_margin=0.01)
        gm = robot.geom_model
        ref, objs, n = pin.GeometryModel(), gm.geometryObjects, robot.n_collision_geometries
        for i in range(n):
            ref.addGeometryObject(objs[i])
        ref.setCollisionPairs(robot._self_pairs)
        for i in range(n, len(objs)):
            ref.addGeometryObject(objs[i])
        for k in robot.obstacle_geometry_ids:
            for a in range(robot.n_collision_geometries):
                ref.addCollisionPair(pin.CollisionPair(a, k))
        assert [(p.first, p.second) for p in gm.collisionPairs] == [(p.first, p.second) for p in ref.collisionPairs]
        assert np.array_equal(gm.collisionPairMapping, ref.collisionPairMapping)
        k = max(robot.obstacle_geometry_ids) + 5
        short, long = _pair_column(k, 3), _pair_column(k, 7)
        assert [(p.first, p.second) for p in long] == [(a, k) for a in range(7)]
        assert [(p.first, p.second) for p in short] == [(a, k) for a in range(3)] == [
            (p.first, p.second) for p in _pair_column(k, 3)]
    finally:
        robot.set_obstacles(obstacles, safety_margin=before)
