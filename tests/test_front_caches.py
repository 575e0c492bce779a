"""The candidate front end's caches and shortcuts (issue 25), against what they replace, with real values: the
self-collision pairs set in one call are the pairs of the former pair-by-pair loop; a robot taken back from a
cell's :class:`RobotPool` (or adopted from the search space's spares) answers as a freshly built one; the pool
keeps assemblies, module sets and cells apart; a solve that reuses robots gives the result of one that builds;
the base contacts (on a probe or the full scratch space) are those of the former loop and leave the same
collision state; sample_base draws and returns what it did; Assembly.from_order's memo keys by set and order."""
import dataclasses

import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV, PRIMITIVES, TASKS

from robodesign import load_module_set
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate, SearchSpace
from robodesign.design.solve import _POOLS, robot_pool, solve
from robodesign.formats.assembly import Assembly
from robodesign.model.cell import RobotPool, build_robot
from robodesign.model.robot import Robot
from robodesign.solvers.schedule import static_cell

PTP3 = TASKS / "simple" / "PTP_3.json"
GOOD = ("1", "21", "4", "22", "5", "23", "12")


def _pairs_pair_by_pair(robot: Robot) -> list:
    """The self-collision pairs as the pair-by-pair loop of earlier releases chose them."""
    model, objs = robot.model, robot.geom_model.geometryObjects
    mode, parents = robot.module_set.ignore_collisions, model.parents
    direct = set()
    for i, mid in enumerate(robot.assembly.module_ids):
        for jt in robot.module_set[mid].joints:
            direct.add(frozenset(((i, jt.parent), (i, jt.child))))
    out = []
    n = robot.n_collision_geometries
    for a in range(n):
        for b in range(a + 1, n):
            ja, jb = objs[a].parentJoint, objs[b].parentJoint
            if ja == jb or mode == "rigid_via_joint" and (parents[ja] == jb or parents[jb] == ja):
                continue
            if mode == "via_joint" and frozenset((robot._geom_body[a], robot._geom_body[b])) in direct:
                continue
            out.append((a, b))
    return out


@pytest.mark.parametrize("folder", [IMPROV, PRIMITIVES, "robodesign_arm"])
@pytest.mark.parametrize("mode", [None, "rigid_via_joint", "via_joint"])
def test_self_collision_pairs_are_those_of_the_pair_by_pair_loop(folder, mode):
    base = load_module_set(folder)
    ms = base if mode is None else dataclasses.replace(base, ignore_collisions=mode)  # the cached set unchanged
    space = SearchSpace(base, min_dof=6, max_dof=7)
    rng = np.random.default_rng(3)
    for _ in range(8):
        robot = Robot.from_order(ms, space.random_order(rng))
        got = [(cp.first, cp.second) for cp in robot.geom_model.collisionPairs]
        assert got == _pairs_pair_by_pair(robot) and got


def _answers(robot: Robot, rng) -> list:
    """What the pipeline asks a robot: reach bound, FK, collisions at random configurations, base contacts,
    distances, the Jacobian's rank."""
    qs = [robot.random_configuration(rng) for _ in range(12)]
    o, R = robot.reach_bound()
    return [o.tolist(), R, robot.base_collisions(), robot.generic_rank(),
            [robot.fk(q).tolist() for q in qs], [robot.in_collision(q) for q in qs],
            [robot.colliding_pairs(q) for q in qs], [robot.min_distances(q) for q in qs],
            [robot.gravity_torque(q).tolist() for q in qs]]


@pytest.fixture(scope="module")
def ptp3():
    return Problem.build(PTP3, IMPROV, "cyc")


def test_a_robot_taken_back_answers_as_a_fresh_build(ptp3):
    ms, cell = ptp3.module_set, static_cell(ptp3.task)
    pool = RobotPool(cell)
    rng = np.random.default_rng(5)
    orders = [GOOD] + [ptp3.space.random_order(rng) for _ in range(3)]
    bases = [[ptp3.base_pose(Candidate(o, ptp3.space.base_bounds.sample(rng))) for o in orders] for _ in range(3)]
    seen = set()
    for k in range(3):
        for o, T in zip(orders, bases[k]):
            asm = Assembly.from_order(ms, o)
            robot = pool.take(ms, asm, T)
            reused = id(robot) in seen
            seen.add(id(robot))
            fresh = build_robot(cell, ms, asm, T)
            assert robot.assembly == asm and np.array_equal(robot.base_pose, T)
            assert _answers(robot, np.random.default_rng(k)) == _answers(fresh, np.random.default_rng(k))
            assert reused == (k > 0)  # every later round takes the robot of its order back
            pool.give_back(robot)


def test_the_pool_keeps_assemblies_cells_and_sizes_apart(ptp3):
    ms = ptp3.module_set
    a, b = Assembly.from_order(ms, GOOD), Assembly.from_order(ms, ("1", "21", "4", "22", "5", "23", "13"))
    pool = RobotPool(static_cell(ptp3.task), size=2)
    T = ptp3.task.nominal_base_pose
    ra = pool.take(ms, a, T)
    pool.give_back(ra)
    rb = pool.take(ms, b, T)  # another order: not the robot of the first
    assert rb is not ra and rb.assembly == b
    assert pool.take(ms, a, T) is ra  # lent once: taken, it is no longer in the pool
    assert pool.take(ms, a, T) is not ra
    pool.give_back(ra)
    pool.give_back(rb)
    pool.give_back(Robot(ms, b))
    assert pool.take(ms, a, T) is not ra  # size 2: the least recently given back went first
    other = load_module_set(IMPROV)  # the same modules, another set object: never shares a robot
    pool.give_back(rb)
    assert pool.take(other, b, T).module_set is other
    # one pool per task; its obstacles are the task's static cell
    task2 = Problem.build(TASKS / "simple" / "PTP_1.json", IMPROV, "cyc").task
    assert robot_pool(ptp3.task) is robot_pool(ptp3.task) and robot_pool(task2) is not robot_pool(ptp3.task)
    assert [o.name for o in robot_pool(ptp3.task).obstacles] == [o.name for o in build_robot(
        static_cell(ptp3.task), ms, a, T).obstacles]
    # without obstacles: the robot is the bare one
    bare = RobotPool(None).take(ms, a, T)
    assert bare.obstacles == [] and len(bare.geom_model.collisionPairs) == bare.n_self_collision_pairs


def test_a_solve_that_reuses_robots_gives_the_result_of_one_that_builds(ptp3):
    ev = Evaluator(EvaluatorSpec(ptp3, seed=0))
    rng = np.random.default_rng(2)
    orders = [GOOD, ptp3.space.random_order(rng)]
    cands = [Candidate(o, ptp3.space.base_bounds.sample(rng)) for _ in range(2) for o in orders]

    def verdicts(clear_each):
        out = []
        for c in cands:
            if clear_each:
                _POOLS.clear()
            e = ev.evaluate(c)
            out.append((e.stage, e.goals_reached, e.feasible, e.cost, e.score, e.shortfall, e.message,
                        None if e.solution is None else e.solution["trajectory"]))
        return out
    _POOLS.clear()
    assert verdicts(clear_each=False) == verdicts(clear_each=True)
    assert len(robot_pool(ptp3.task)._free) >= 1


def test_a_solve_gives_its_robot_back():
    from robodesign.design.solve import SolveSettings
    problem = Problem.build(PTP3, IMPROV, "cyc")
    pool = robot_pool(problem.task)
    before = pool._count
    res = solve(problem.task, problem.module_set, list(GOOD), settings=SolveSettings(stop_after="reach"))
    assert res.stage == "done" and pool._count == before + 1
    assert isinstance(pool.take(problem.module_set, Assembly.from_order(problem.module_set, GOOD),
                                problem.task.nominal_base_pose).geom_data, pin.GeometryData)


def _base_collisions_pair_by_pair(robot: Robot) -> list:
    """The base stage's contacts as the loop over every robot–obstacle pair of earlier releases found them."""
    if not robot.obstacles:
        return []
    objs, pairs = robot.geom_model.geometryObjects, robot.geom_model.collisionPairs
    pin.updateGeometryPlacements(robot.model, robot.data, robot.geom_model, robot.geom_data, np.zeros(robot.dof))
    return [(objs[pairs[k].first].name, objs[pairs[k].second].name)
            for k in range(robot.n_self_collision_pairs, len(pairs))
            if objs[pairs[k].first].parentJoint == 0 and pin.computeCollision(robot.geom_model, robot.geom_data, k)]


@pytest.fixture(scope="module")
def whitman(tmp_path_factory):
    from robodesign.generate.registry import generate
    files = generate("whitman2020", tmp_path_factory.mktemp("whitman"), 1, 0,
                     {"goals": 5, "obstacles": 5, "base": "xyz_any_rot"})
    return Problem.build(files[0], "robodesign_arm", "cyc")


def test_base_contacts_are_those_of_the_pair_by_pair_loop(whitman):
    from robodesign.model.robot import Obstacle
    ms, cell = whitman.module_set, static_cell(whitman.task)
    rng = np.random.default_rng(7)
    hits = 0
    for _ in range(40):
        c = whitman.space.random_candidate(rng)
        T = whitman.base_pose(c)
        robot = build_robot(cell, ms, Assembly.from_order(ms, c.order), T)
        # obstacles around the base too, so that some designs touch one with their fixed part
        extra = [Obstacle(f"near{k}", o.shape, T @ np.array([[1, 0, 0, 0.1 * k], [0, 1, 0, 0], [0, 0, 1, 0.05],
                                                                [0, 0, 0, 1.0]])) for k, o in enumerate(robot.obstacles[:2])]
        robot.set_obstacles(robot.obstacles + extra, safety_margin=robot.safety_margin)
        got = robot.base_collisions()
        robot._geom_data = None  # the reference on a fresh scratch space
        assert got == _base_collisions_pair_by_pair(robot)
        hits += bool(got)
    assert hits > 0


@pytest.mark.parametrize("which", ["whitman", "ptp3"])
def test_base_pairs_the_bounds_clear_are_farther_than_the_margin(which, whitman, ptp3):
    """The base stage asks coal only about the pairs the culler's bounds keep: every pair it clears is farther
    from its obstacle than the margin (coal's distance), every pair in contact is kept, and the answer is the
    pair-by-pair loop's, among boxes (whitman) and near the CNC machine's mesh (PTP_3), with obstacles moved to
    the base and margins up to 5 cm."""
    import coal
    from robodesign.model.robot import Obstacle
    problem = whitman if which == "whitman" else ptp3
    ms, cell = problem.module_set, static_cell(problem.task)
    rng = np.random.default_rng(11)
    cleared = kept = hits = 0
    for i in range(30):
        c = problem.space.random_candidate(rng)
        T = problem.base_pose(c)
        robot = build_robot(cell, ms, Assembly.from_order(ms, c.order), T)
        # every obstacle shape once more, its box's centre moved to within 40 cm of the base
        extra = []
        for k, o in enumerate(robot.obstacles):
            o.shape.computeLocalAABB()
            centre = 0.5 * (np.asarray(o.shape.aabb_local.min_) + np.asarray(o.shape.aabb_local.max_))
            P = np.array(o.pose, dtype=float)
            P[:3, 3] = T[:3, 3] + rng.uniform([-0.4, -0.4, -0.2], [0.4, 0.4, 0.3]) - P[:3, :3] @ centre
            extra.append(Obstacle(f"near{k}", o.shape, P))
        margin = [0.0, 0.01, 0.05][i % 3]
        robot.set_obstacles(robot.obstacles + extra, safety_margin=margin)
        if i % 5 == 4:   # an obstacle moved onto the base after the geometry was made
            robot.geom_model
            robot.move_obstacle(0, T)
        elif i % 5 == 3:  # a geometry set from outside, with an obstacle on the base
            robot.base_collisions()
            geom = robot.geom_model.copy()
            geom.geometryObjects[robot.obstacle_geometry_ids[0]].placement = pin.SE3(T)
            robot.geom_model = geom
        near = set(robot._base_pairs_near())
        n = robot.n_collision_geometries
        objs = robot.geom_model.geometryObjects
        root = [k for k in range(n) if objs[k].parentJoint == 0]
        for j, ob in enumerate(robot.obstacle_geometry_ids):
            for a in root:
                A, B = objs[a], objs[ob]
                d = coal.distance(A.geometry, coal.Transform3s(A.placement.rotation, A.placement.translation),
                                  B.geometry, coal.Transform3s(B.placement.rotation, B.placement.translation),
                                  coal.DistanceRequest(), coal.DistanceResult())
                if (j, a) in near:
                    kept += 1
                else:
                    cleared += 1
                    assert d > margin, (i, j, a, d, margin)
        got = robot.base_collisions()
        robot._geom_data = None  # the reference on a fresh scratch space
        assert got == _base_collisions_pair_by_pair(robot)
        assert {(objs[a].name, objs[ob].name) for j, a in near for ob in [robot.obstacle_geometry_ids[j]]} >= set(got)
        hits += bool(got)
    assert hits > 0 and cleared > kept > 0, (hits, cleared, kept)


def test_a_pool_adopts_the_robot_a_search_space_built_for_its_kinematics(whitman):
    from robodesign.model import cell as cell_mod
    ms, cell = whitman.module_set, static_cell(whitman.task)
    rng = np.random.default_rng(8)
    order = whitman.space.random_order(rng)
    whitman.space._cache("_memo_reach").clear()
    whitman.space.rank_deficit(order)  # builds the order's robot once: kept as a spare
    asm = Assembly.from_order(ms, order)
    spare = cell_mod._SPARE.get((id(ms), asm.key()))
    assert spare is not None and spare.assembly == asm
    c = Candidate(tuple(order), whitman.space.sample_base(rng, order))
    T = whitman.base_pose(c)
    robot = RobotPool(cell).take(ms, asm, T)
    assert robot is spare and (id(ms), asm.key()) not in cell_mod._SPARE  # adopted once
    fresh = build_robot(cell, ms, asm, T)
    assert np.array_equal(robot.model.gravity.vector, fresh.model.gravity.vector)
    assert _answers(robot, np.random.default_rng(1)) == _answers(fresh, np.random.default_rng(1))
    assert RobotPool(cell).take(ms, asm, T) is not spare  # another pool builds its own


def _clear_as_before(space, params) -> bool:
    """SearchSpace._clear as earlier releases wrote it: every primitive obstacle's exact test."""
    from robodesign.formats.geometry import contains_point
    p = space.base_bounds.pose(params)[:3, 3]
    return not any(g.kind != "mesh" and contains_point(g, p) for g in space.obstacles)


def _sample_base_as_before(space, rng, order, tries=64):
    """SearchSpace.sample_base as earlier releases wrote it (clearance tested before the shortfall)."""
    from robodesign.core.spatial import rot_z
    bb, free = space.base_bounds, space.base_bounds.free
    order = tuple(str(m) for m in order)
    o_local, R = space._order_reach(order)
    G = space._goal_array()
    inv = np.linalg.inv(bb.nominal)
    best, best_s = None, float("inf")
    for k in range(tries):
        if k % 2 == 0:
            full = [float(rng.uniform(bb.lower[i], bb.upper[i])) for i in range(4)]
            g = G[int(rng.integers(len(G))), :3]
            v = rng.normal(size=3)
            v *= rng.uniform(0.2, 0.75) * min(R, 10.0) / max(float(np.linalg.norm(v)), 1e-12)
            t = (inv @ np.append(g + v, 1.0))[:3] - rot_z(full[3]) @ o_local
            for i in range(3):
                if i in free:
                    full[i] = float(t[i])
            params = tuple(full[i] for i in free)
        else:
            params = tuple(float(rng.uniform(bb.lower[i], bb.upper[i])) for i in free)
        if not bb.valid(params) or not _clear_as_before(space, params):
            continue
        s = space._shortfall(order, params)
        if s == 0.0:
            return params
        if s < best_s:
            best, best_s = params, s
    return best if best is not None else bb.sample(rng)


def test_robots_of_a_cell_share_their_obstacle_bounds_and_a_moved_obstacle_gets_its_own(whitman):
    from robodesign.model.collision_cull import ObstacleBounds, distance_field
    ms, pool = whitman.module_set, RobotPool(static_cell(whitman.task))   # (the cell's obstacles made once)
    rng = np.random.default_rng(2)
    robots = []
    for _ in range(3):
        c = whitman.space.random_candidate(rng)
        robots.append(pool.take(ms, Assembly.from_order(ms, c.order), whitman.base_pose(c)))
        robots[-1].base_collisions()
    assert robots[0]._obstacle_bounds is robots[1]._obstacle_bounds is robots[2]._obstacle_bounds
    moved = np.array(robots[2].obstacles[0].pose, dtype=float)
    moved[:3, 3] += (0.3, -0.2, 0.1)
    robots[2].move_obstacle(0, moved)
    robots[2].base_collisions()
    mine = robots[2]._obstacle_bounds
    assert mine is not robots[0]._obstacle_bounds
    fresh = ObstacleBounds([distance_field(ob.shape, moved if j == 0 else ob.pose)
                            for j, ob in enumerate(robots[2].obstacles)])
    for name in ("R_inv", "t", "lo", "hi"):
        assert np.array_equal(getattr(mine, name), getattr(fresh, name))
    assert not np.array_equal(mine.t, robots[0]._obstacle_bounds.t)


def test_sample_base_draws_and_returns_what_it_did(whitman):
    space = whitman.space
    rng = np.random.default_rng(4)
    for _ in range(30):
        order = space.random_order(rng)
        seed = int(rng.integers(1 << 30))
        a, b = np.random.default_rng(seed), np.random.default_rng(seed)
        assert space.sample_base(a, order, tries=16) == _sample_base_as_before(space, b, order, tries=16)
        assert a.random() == b.random()  # the same draws


def test_base_positions_clear_of_the_obstacles_are_those_of_every_exact_test(whitman):
    """_clear skips the exact test of an obstacle whose bounding sphere (radius scaled by the pose's largest
    singular value) is far: the verdicts of points on, just inside and just outside each surface, and of random
    points, are those of the exact tests, for rotated, scaled and sheared poses too."""
    from robodesign.core.spatial import homogeneous, rot_z
    from robodesign.formats.geometry import GeometrySpec, contains_point
    rng = np.random.default_rng(7)
    rot = homogeneous(rot_z(0.7) @ np.array([[1, 0, 0], [0, 0.6, -0.8], [0, 0.8, 0.6]]), (0.4, -0.3, 0.2))
    sheared = rot @ np.diag([1.3, 0.7, 1.0, 1.0]) @ homogeneous(np.array([[1, 0.4, 0], [0, 1, 0], [0, 0, 1.0]]))
    obstacles = tuple(GeometrySpec(kind, T, size) for T in (np.eye(4), rot, sheared)
                      for kind, size in (("box", (0.5, 0.3, 0.2)), ("cylinder", (0.25, 0.4)), ("sphere", (0.3,))))
    nominal = homogeneous(np.eye(3), (0.1, 0.0, 0.0))
    space = dataclasses.replace(whitman.space, obstacles=obstacles,
                                base_bounds=dataclasses.replace(whitman.space.base_bounds, nominal=nominal,
                                                                lower=(-1.0, -1.0, -1.0, 0.0), upper=(1.0, 1.0, 1.0, 0.0)))
    points = [rng.uniform(-1.0, 1.0, 3) for _ in range(3000)]
    for g in obstacles:   # on the surface of each shape, and 1e-9 m in and out along the direction from its centre
        for _ in range(150):
            u = rng.normal(size=3)
            u /= np.linalg.norm(u)
            if g.kind == "box":
                local = u / np.max(np.abs(u) / (0.5 * np.asarray(g.size)))
            elif g.kind == "cylinder":
                local = u * min(g.size[0] / max(np.hypot(u[0], u[1]), 1e-12), 0.5 * g.size[1] / max(abs(u[2]), 1e-12))
            else:
                local = u * g.size[0]
            for f in (1.0 - 1e-9, 1.0, 1.0 + 1e-9):
                points.append((g.pose @ np.append(local * f, 1.0))[:3])
    inside = 0
    for p in points:
        params = tuple(float(v) for v in p - nominal[:3, 3])
        exact = not any(contains_point(g, space.base_bounds.pose(params)[:3, 3]) for g in obstacles)
        assert space._clear(params) == exact
        inside += not exact
    assert 300 < inside < len(points) - 300   # both verdicts are tested, many times
    assert [r2 is not None for _, _, r2 in space._obstacle_spheres()] == [True] * 9
    # the sheared box's bound: half its diagonal, scaled by its pose's largest singular value (+1e-6 m)
    s_max = np.linalg.svd(sheared[:3, :3], compute_uv=False)[0]
    assert space._obstacle_spheres()[6][2] == pytest.approx((s_max * (0.5 * np.sqrt(0.38) + 1e-6)) ** 2, rel=1e-12)


def test_the_reach_shortfall_in_floats_is_numpys_bit_for_bit():
    from robodesign.design.base_bounds import beyond_reach as _beyond
    rng = np.random.default_rng(11)
    for n in (1, 2, 3, 5, 8):
        for _ in range(400):
            G = np.column_stack([rng.normal(0, 1.5, (n, 3)), rng.uniform(0, 0.2, n)])
            R = float(rng.uniform(0.1, 2.5))
            pose = np.eye(4)
            pose[:3, :3] = np.linalg.qr(rng.normal(size=(3, 3)))[0]
            pose[:3, 3] = rng.normal(0, 1, 3)
            o_h = np.append(rng.normal(0, 0.3, 3), 1.0)
            d = np.linalg.norm(G[:, :3] - (pose @ o_h)[:3], axis=1) - G[:, 3] - R
            rows = tuple(tuple(float(v) for v in r) for r in G)
            assert _beyond(rows, R, pose, o_h) == float(max(0.0, d.max()))
    G[0, 0] = np.nan   # numpy's max is NaN, and max(0.0, NaN) is 0.0
    assert _beyond(tuple(tuple(float(v) for v in r) for r in G), 0.0, pose, o_h) == 0.0


def test_a_base_pose_is_the_nominal_pose_times_the_offset_bit_for_bit(whitman):
    from robodesign.core.spatial import homogeneous, rot_z
    bb = dataclasses.replace(whitman.space.base_bounds, nominal=homogeneous(rot_z(0.3), (0.2, -0.1, 0.05)),
                             lower=(-1.0, -1.0, -0.5, -3.0), upper=(1.0, 1.0, 0.5, 3.0))
    rng = np.random.default_rng(3)
    for _ in range(200):
        p = tuple(rng.uniform(-1, 1, 4))
        assert np.array_equal(bb.pose(p), bb.nominal @ homogeneous(rot_z(p[3]), p[:3]))


def test_the_reach_stage_measures_each_goal_pose_from_the_first_joint(whitman):
    """solve's reach stage on its per-task goal points: the shortfall and the reason are those of every goal pose's
    distance from the reach bound's centre, minus the bound and the pose's position slack."""
    from robodesign.design.goal_planner import goal_poses, position_slack
    from robodesign.design.solve import goal_points
    task, space = whitman.task, whitman.space
    assert [(g.id, tuple(p)) for g, p, _ in goal_points(task)] == \
        [(g.id, tuple(pose.nominal[:3, 3])) for g in task.goals for pose in goal_poses(g)]
    rng = np.random.default_rng(5)
    failed = 0
    for _ in range(60):
        c = space.random_candidate(rng)
        robot = Robot.from_order(whitman.module_set, c.order, base_pose=whitman.base_pose(c))
        o, R = robot.reach_bound()
        misses = [float(np.linalg.norm(pose.nominal[:3, 3] - o)) - R - position_slack(pose)
                  for g in task.goals for pose in goal_poses(g)]
        if max(misses) <= 0:
            continue   # (it would go on to the IK)
        res = solve(task, whitman.module_set, c.order, whitman.base_pose(c))
        assert res.stage in ("base", "reach")
        if res.stage == "reach":
            failed += 1
            assert res.shortfall == max(misses)
            worst = int(np.argmax(misses))
            gid = [g.id for g in task.goals for _ in goal_poses(g)][worst]
            assert res.stages[-1].message.startswith(f"goal {gid} is ")
    assert failed >= 5


def test_assembly_of_an_order_is_remembered_per_set_and_order():
    from robodesign.core.errors import AssemblyError
    ms = load_module_set(IMPROV)
    a = Assembly.from_order(ms, list(GOOD))
    assert Assembly.from_order(ms, GOOD) is a and a == Assembly._from_order(ms, GOOD)
    other = dataclasses.replace(ms)  # an equal set, another object: its own entry
    b = Assembly.from_order(other, GOOD)
    assert b == a and b is not a and Assembly.from_order(other, GOOD) is b
    shorter = Assembly.from_order(ms, GOOD[:-1] + ("13",))
    assert shorter.module_ids[-1] == "13" and shorter != a
    for _ in range(2):  # a failure is not remembered: it raises every time
        with pytest.raises(AssemblyError):
            Assembly.from_order(ms, ("1", "12", "4"))


def _guesses(gd) -> list:
    """The state a collision or distance query leaves in the requests."""
    return [(tuple(r.cached_gjk_guess), tuple(r.cached_support_func_guess), r.distance_upper_bound)
            for r in gd.collisionRequests] + \
        [(tuple(r.cached_gjk_guess), tuple(r.cached_support_func_guess)) for r in gd.distanceRequests]


def test_base_contacts_on_a_probe_leave_the_state_a_full_scratch_space_would(whitman):
    """The base stage queries its pairs on a probe before the robot has a collision scratch space: the answers,
    and the GJK guesses the later queries start from, are those of the queries on the full scratch space."""
    from robodesign.model.robot import Obstacle
    ms, cell = whitman.module_set, static_cell(whitman.task)
    rng = np.random.default_rng(9)
    hits = 0
    for _ in range(25):
        c = whitman.space.random_candidate(rng)
        T = whitman.base_pose(c)
        asm = Assembly.from_order(ms, c.order)
        robots = [build_robot(cell, ms, asm, T) for _ in range(2)]
        for r in robots:
            near = [Obstacle(f"near{k}", o.shape, T @ np.array([[1, 0, 0, 0.1 * k], [0, 1, 0, 0], [0, 0, 1, 0.05],
                                                                   [0, 0, 0, 1.0]])) for k, o in enumerate(r.obstacles[:2])]
            r.set_obstacles(r.obstacles + near, safety_margin=0.01)
        full, probed = robots
        full.geom_data  # the full scratch space first: no probe
        a = full.base_collisions()
        b = probed.base_collisions()
        assert probed._geom_data is None and (probed._base_probe is not None) == bool(probed._base_pairs_near())
        assert a == b
        hits += bool(a)
        for ra, rb in zip(full.geom_data.collisionRequests, probed.geom_data.collisionRequests):
            assert (ra.security_margin, ra.enable_contact, ra.distance_upper_bound, ra.break_distance) == \
                   (rb.security_margin, rb.enable_contact, rb.distance_upper_bound, rb.break_distance)
        assert _guesses(full.geom_data) == _guesses(probed.geom_data)
        qs = [full.random_configuration(rng) for _ in range(6)]
        assert [full.colliding_pairs(q) for q in qs] == [probed.colliding_pairs(q) for q in qs]
        assert _guesses(full.geom_data) == _guesses(probed.geom_data)
    assert hits > 0


def test_a_new_base_pose_starts_the_collision_queries_afresh(ptp3):
    ms, cell = ptp3.module_set, static_cell(ptp3.task)
    asm = Assembly.from_order(ms, GOOD)
    T0, T1 = ptp3.task.nominal_base_pose, ptp3.base_pose(Candidate(GOOD, ptp3.space.base_bounds.sample(
        np.random.default_rng(1))))
    used = build_robot(cell, ms, asm, T0)
    rng = np.random.default_rng(2)
    for _ in range(10):
        used.min_distances(used.random_configuration(rng))
    used.set_base_pose(T1)
    fresh = build_robot(cell, ms, asm, T1)
    assert _guesses(used.geom_data) == _guesses(fresh.geom_data)
    assert _answers(used, np.random.default_rng(3)) == _answers(fresh, np.random.default_rng(3))


def _geometry(robot: Robot) -> tuple:
    gm = robot.geom_model
    return ([(o.name, o.parentJoint, o.parentFrame, o.placement.homogeneous.tolist(), type(o.geometry).__name__,
              o.geometry.aabb_local.min_.tolist(), o.geometry.aabb_local.max_.tolist())
             for o in gm.geometryObjects], [(cp.first, cp.second) for cp in gm.collisionPairs])


def test_the_geometry_made_on_first_use_is_the_one_made_at_once(whitman):
    """The collision geometry is made when first asked for: before or after the base pose and the obstacles are
    set, the objects (names, joints, frames, exact placements, shapes) and pairs are the same."""
    from robodesign.model.robot import Obstacle
    ms = whitman.module_set
    rng = np.random.default_rng(10)
    obstacles = [Obstacle(f"o{k}", o.shape, o.pose) for k, o in enumerate(RobotPool(static_cell(whitman.task)).obstacles)]
    for _ in range(6):
        c = whitman.space.random_candidate(rng)
        asm, T = Assembly.from_order(ms, c.order), whitman.base_pose(c)
        early = Robot(ms, asm)
        early.geom_model  # made before the base pose and the obstacles
        late = Robot(ms, asm)
        for r in (early, late):
            r.set_base_pose(T)
            r.set_obstacles(obstacles, safety_margin=0.02)
        assert late._geom_model is None and late.n_collision_geometries == early.n_collision_geometries
        assert _geometry(late) == _geometry(early)
        assert late.n_self_collision_pairs == early.n_self_collision_pairs
        # moved obstacles and a second set of obstacles: the same in both
        for r in (early, late):
            r.move_obstacle(0, T)
            r.set_obstacles(obstacles[:2], safety_margin=0.0)
        assert _geometry(late) == _geometry(early)
        # never placed: the objects at the identity base pose
        assert _geometry(Robot(ms, asm))[0] == _geometry(Robot(ms, asm, base_pose=np.eye(4)))[0]
