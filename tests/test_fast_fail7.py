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
