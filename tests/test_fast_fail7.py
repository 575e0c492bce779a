"""A candidate that fails at IK, third pass (issue 25): each cheap path gives what the path it skips gives.

* ``robot._certainly_full_rank``: a Cholesky factor of the Jacobian's Gram matrix shows a full rank without the SVD;
  it never claims a full rank where numpy's SVD and ``_rank`` give less, on many random matrices made to be rank
  deficient, nearly so, badly scaled or generic; ``Robot.generic_rank`` with it equals the SVD-only rank and leaves
  the same scratch space, on random robots of three module sets.
* ``RobotGeometry.base_collisions`` on a probe: the contacts of plain coal queries of every pair of an object fixed
  to the world and an obstacle, without making the self-pair map.
"""
import numpy as np
import pinocchio as pin
import pytest

from robodesign.design.problem import Problem
from robodesign.formats.assembly import Assembly
from robodesign.model import robot as robot_module
from robodesign.model.cell import build_robot
from robodesign.solvers.schedule import static_cell
from robodesign.model.robot import _certainly_full_rank, _rank

from test_fast_fail import SETS, _old_generic_rank, _outcome, _scratch, _twins


def _svd_rank(J: np.ndarray, rtol: float) -> int:
    return _rank(np.linalg.svd(J, compute_uv=False), rtol)


def _matrices(rng, n: int):
    """Random matrices (1–8 rows and columns): generic, of a lower rank (a product through a narrower inner side),
    nearly of a lower rank (one singular value at 1e-12 … 1e-3 of the largest), with rows scaled by up to 1e±6."""
    for _ in range(n):
        r, c = int(rng.integers(1, 9)), int(rng.integers(1, 9))
        kind = rng.integers(4)
        if kind == 0:
            J = rng.normal(size=(r, c))
        elif kind == 1:
            J = rng.normal(size=(r, int(rng.integers(1, max(2, min(r, c))))))
            J = J @ rng.normal(size=(J.shape[1], c))
        else:
            U, _ = np.linalg.qr(rng.normal(size=(r, r)))
            V, _ = np.linalg.qr(rng.normal(size=(c, c)))
            s = np.sort(rng.uniform(0.1, 10.0, min(r, c)))[::-1]
            s[-1] = s[0] * 10.0 ** rng.uniform(-12, -3)
            J = U[:, :len(s)] @ np.diag(s) @ V[:len(s)]
            if kind == 3:
                J = J * 10.0 ** rng.uniform(-6, 6, (r, 1))
        yield J


def test_certificate_never_claims_a_rank_the_svd_does_not_give():
    rng = np.random.default_rng(25)
    certified = deficient = 0
    for J in _matrices(rng, 4000):
        for rtol in (1e-8, 1e-12, 0.0, 1e-6):
            if _certainly_full_rank(J, rtol):
                certified += 1
                assert _svd_rank(J, rtol) == min(J.shape), (J, rtol)
            else:
                deficient += _svd_rank(J, rtol) < min(J.shape)
    assert certified > 4000 and deficient > 1000   # (both kinds met)
    # a rank one short by rounding only, zero, non-finite, a vector, large tolerances: never certified
    J = rng.normal(size=(6, 5)) @ rng.normal(size=(5, 7))
    assert _svd_rank(J, 1e-8) == 5 and not _certainly_full_rank(J, 1e-8)
    for bad in (np.zeros((6, 7)), np.full((6, 7), np.nan), np.full((6, 7), np.inf), np.ones(6)):
        assert not _certainly_full_rank(bad, 1e-8)
    assert not _certainly_full_rank(np.eye(6), 1e-5)


@pytest.mark.parametrize("modules,seed", SETS)
def test_generic_rank_with_the_certificate_equals_the_svd_alone(modules, seed, monkeypatch):
    """The rank and the scratch space after, with and without the certificate, and as the former one-by-one loop."""
    got, ref = [], []
    for new, old in _twins(modules, seed + 40, 40):
        for rtol in (1e-8, 1e-10):
            new._generic_rank = None
            got.append((_outcome(lambda: new.generic_rank(4, rtol)), _scratch(new)))
            with monkeypatch.context() as m:
                m.setattr(robot_module, "_certainly_full_rank", lambda J, rtol: False)
                new._generic_rank = None
                ref.append((_outcome(lambda: new.generic_rank(4, rtol)), _scratch(new)))
            assert got[-1][0] == _outcome(lambda: _old_generic_rank(old, 4, rtol)) and got[-1][1] == _scratch(old)
    assert got == ref
    assert len({r for r, _ in got if isinstance(r, int)}) >= 2


def _plain_base_collisions(robot):
    """Every pair of an object fixed to the world and an obstacle asked of coal on the full geometry at q = 0."""
    gm, gd = robot.geom_model, robot.geom_data
    pin.updateGeometryPlacements(robot.kinematic_model, robot.data, gm, gd, np.zeros(robot.dof))
    root = [k for k, _, _ in robot._root_geoms]
    objs, out = gm.geometryObjects, []
    for k, cp in enumerate(gm.collisionPairs):
        a, b = sorted((cp.first, cp.second))
        if a in root and b in robot.obstacle_geometry_ids and pin.computeCollision(gm, gd, k):
            out.append((objs[a].name, objs[b].name))
    return sorted(out)


def test_base_collisions_on_a_probe_equal_plain_queries_without_the_self_pairs():
    """whitman2020's profile task: random candidates, the robots moved to the obstacles too (so that some touch)."""
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "experiments"))
    from profile_evaluator import family_tasks
    problem = Problem.build(family_tasks("whitman2020_g5o5", 1, 0)[0], "robodesign_arm", "cyc")
    cell, ms = static_cell(problem.task), problem.module_set
    centres = [ob.pose[:3, 3] for ob in build_robot(cell, ms, Assembly.from_order(
        ms, problem.space.random_candidate(np.random.default_rng(0)).order), np.eye(4)).obstacles]
    rng = np.random.default_rng(3)
    hits = 0
    for k in range(60):
        c = problem.space.random_candidate(rng)
        T = problem.base_pose(c)
        if k % 2:
            T = T.copy()
            T[:3, 3] = centres[k % len(centres)] + rng.uniform(-0.2, 0.2, 3)
        asm = Assembly.from_order(ms, c.order)
        probed, plain = build_robot(cell, ms, asm, T), build_robot(cell, ms, asm, T)
        got = sorted(probed.base_collisions())
        assert probed._self_map is None and probed._geom_data is None
        assert got == _plain_base_collisions(plain)
        hits += bool(got)
    assert hits >= 5


def _old_unreachable(cb, gm) -> str:
    """ChainBounds._unreachable as it was, every term made afresh."""
    from robodesign.solvers.ik import _circle_distance
    if gm.unconstrained:
        return ""
    if gm.position_lower_bound(cb.o) > cb.R + 1e-9:
        return "out_of_reach"
    if cb.circle is None:
        return ""
    rp = gm.position_radius()
    if not np.isfinite(rp):
        return ""
    N = gm.goal.nominal
    pn = np.asarray(N[:3, 3], float)
    c, a, rho = cb.circle
    if _circle_distance(pn, c, a, rho) - rp > cb.R1 + 1e-9:
        return "out_of_reach"
    rs = gm.rotation_slack(cb.c_tcp)
    if np.isfinite(rs):
        w = pn - np.asarray(N[:3, :3], float) @ cb.c_tcp
        if _circle_distance(w, c, a, rho) - (rp + rs) > cb.R2 + 1e-9:
            return "out_of_orientation_reach"
    return ""


def test_chain_bounds_with_kept_goal_terms_equal_the_former_formula():
    """whitman2020 and bpo2024 profile tasks: every goal pose against random candidates' robots (many share their
    tool, so kept terms are met again), at their base poses and at poses moved towards the goals."""
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "experiments"))
    from profile_evaluator import family_tasks
    from robodesign.design.goal_planner import goal_poses
    from robodesign.solvers.ik import ChainBounds, goal_model
    rng = np.random.default_rng(11)
    verdicts = {}
    for fam in ("whitman2020_g5o5", "bpo2024"):
        problem = Problem.build(family_tasks(fam, 1, 0)[0], "robodesign_arm", "cyc")
        ms, poses = problem.module_set, [p for g in problem.task.goals for p in goal_poses(g)]
        for _ in range(40):
            c = problem.space.random_candidate(rng)
            T = problem.base_pose(c)
            robot = build_robot(None, ms, Assembly.from_order(ms, c.order), T)
            for k in range(2):
                if k:
                    T = T.copy()
                    T[:3, 3] = 0.5 * (T[:3, 3] + poses[int(rng.integers(len(poses)))].nominal[:3, 3])
                    robot.set_base_pose(T)
                cb = ChainBounds(robot)
                for p in poses:
                    gm = goal_model(p)
                    got = cb._unreachable(gm)
                    assert got == _old_unreachable(cb, gm)
                    verdicts[got] = verdicts.get(got, 0) + 1
    assert len(verdicts) == 3 and min(verdicts.values()) >= 10, verdicts


def _old_near(bounds, centres, radii, margin):
    """ObstacleBounds.near as it was: the box bound (numpy) for every pair, then the fields'."""
    from robodesign.model.collision_cull import SLACK
    limit = np.asarray(radii, dtype=float) + (float(margin) + SLACK)
    x = np.einsum("oij,omj->omi", bounds.R_inv, np.asarray(centres, dtype=float)[None] - bounds.t)
    e = np.maximum(np.maximum(bounds.lo - x, x - bounds.hi), 0.0)
    near = np.sqrt(np.einsum("omi,omi->om", e, e)) <= limit
    for o in np.flatnonzero(near.any(axis=1)).tolist():
        bounds.fields[o].field_near(np.asarray(centres, dtype=float), limit, near[o])
    return near


def test_box_screen_clears_only_spheres_the_bounds_clear():
    """Random cells of boxes, cylinders and spheres (rotations exact, or rounded to 3 decimals as a file may give
    them), random spheres from far off to inside: where the screen clears every sphere, ``near`` (as it was) keeps
    none; both answers of the screen are met."""
    import coal
    from robodesign.model.box_screen import all_clear, boxes_of
    from robodesign.model.collision_cull import SLACK, DistanceField, ObstacleBounds
    rng = np.random.default_rng(4)
    clear = kept = 0
    for k in range(150):
        fields = []
        for _ in range(int(rng.integers(1, 6))):
            T = np.eye(4)
            T[:3, :3] = pin.Quaternion(*rng.normal(size=4)).normalized().toRotationMatrix()
            if k % 3 == 0:
                T[:3, :3] = np.round(T[:3, :3], 3)
            T[:3, 3] = rng.uniform(-1.5, 1.5, 3)
            kind = rng.integers(3)
            shape = coal.Box(*rng.uniform(0.05, 1.0, 3)) if kind == 0 else \
                coal.Cylinder(rng.uniform(0.05, 0.3), rng.uniform(0.1, 0.8)) if kind == 1 else coal.Sphere(0.2)
            fields.append(DistanceField(shape, T))
        bounds = ObstacleBounds(fields)
        for _ in range(4):
            m = int(rng.integers(1, 9))
            C = rng.uniform(-1.5, 1.5, (m, 3)) * rng.choice([0.5, 1.0, 3.0])
            r = rng.uniform(0.0, 0.3, m)
            margin = float(rng.choice([0.0, 0.01]))
            want = _old_near(bounds, C, r, margin)
            assert (bounds.near(C, r, margin) == want).all()
            if all_clear(boxes_of(bounds), C, r + (margin + SLACK)):
                clear += 1
                assert not want.any()
            else:
                kept += 1
    assert clear >= 50 and kept >= 50, (clear, kept)
    # NaN is never cleared; an infinite centre is cleared, as near clears it
    boxes = boxes_of(bounds)
    assert not all_clear(boxes, np.array([[np.nan, 0.0, 0.0]]), np.zeros(1))
    assert not all_clear(boxes, np.zeros((1, 3)) + 100.0, np.full(1, np.nan))
    C = np.array([[np.inf, 0.0, 0.0]])
    assert all_clear(boxes, C, np.zeros(1)) and not _old_near(bounds, C, np.zeros(1), 0.0).any()
