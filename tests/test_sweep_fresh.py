"""The sweep's set-up for a new arm with less work (issue 25, eleventh round): the posed bounds' distinct gather
columns found with a dictionary instead of ``numpy.unique(axis=1)`` and the turn reach of each shape kept per shape.
Both give the former numbers bit for bit: the gathered step bounds of random robots (robodesign_arm, IMPROV) on
random motions equal those of the former grouping, by the kernel and by the numpy path, and the kept reach is the
reach computed again."""
from __future__ import annotations

import numpy as np
import pytest
from conftest import IMPROV, TASKS
from test_pair_scratch_collide import random_robots

from robodesign.design.problem import Problem
from robodesign.formats.assembly import Assembly
from robodesign.model import sweep, sweep_bounds, sweep_kernel
from robodesign.model.cell import build_robot
from robodesign.solvers.schedule import static_cell


def _improv_robots(n: int, seed: int):
    """``n`` random IMPROV arms of PTP_3's search space (the fresh arms of bench_paired's ptp3 scenario), at PTP_3's
    base pose in its cell."""
    problem = Problem.build(TASKS / "simple" / "PTP_3.json", IMPROV, "cyc")
    cell, ms = static_cell(problem.task), problem.module_set
    rng = np.random.default_rng(seed)
    for _ in range(n):
        c = problem.space.random_candidate(rng)
        yield build_robot(cell, ms, Assembly.from_order(ms, c.order), problem.base_pose(c))


def _former_grouping(idx: np.ndarray):
    """The grouping PosedArms.segments made before: numpy.unique over the columns."""
    uniq, inverse = np.unique(idx, axis=1, return_inverse=True)
    return np.ascontiguousarray(uniq, dtype=np.int64), inverse.reshape(-1).astype(np.int64)


def test_distinct_columns_group_as_numpy_unique():
    rng = np.random.default_rng(4)
    for _ in range(300):
        dof, P = int(rng.integers(1, 10)), int(rng.integers(0, 80))
        idx = rng.integers(-1, int(rng.integers(1, 6)), (dof, P))
        uniq, inverse = sweep_bounds._distinct_columns(idx)
        assert uniq.dtype == inverse.dtype == np.int64 and uniq.flags.c_contiguous
        assert np.array_equal(uniq[:, inverse], idx) and len(set(map(bytes, uniq.T.copy()))) == uniq.shape[1]
        u0, _ = _former_grouping(idx)
        assert sorted(map(bytes, uniq.T.copy())) == sorted(map(bytes, u0.T.copy()))


@pytest.mark.skipif(not sweep_kernel.available(), reason="numba unavailable or ROBODESIGN_JIT=0")
def test_gathered_bounds_are_the_former_ones_bit_for_bit():
    """On 30 random robots, each on three random motions: the step bounds (kernel and numpy path) with the new
    grouping equal those with numpy.unique's, and SweepChecker's schedule is those numbers."""
    assert sweep_kernel.warm_up()
    rng = np.random.default_rng(8)
    checked = 0
    for robot in [*random_robots(15, 3), *_improv_robots(15, 5)]:
        chk = sweep.SweepChecker(robot, posed_arms=True)
        pa = chk._posed
        dof, G = pa.R.shape
        idx = np.where(chk.W > 0, chk._owner, G)
        new, old = sweep_bounds._distinct_columns(idx), _former_grouping(idx)
        for scale in (0.01, 0.1, 0.8):
            Q = np.cumsum(rng.normal(0, scale, (40, robot.dof)), axis=0)
            dQ = np.abs(np.diff(Q, axis=0))
            X, _ = pa._arms(Q, dQ)
            want = sweep_kernel.gather(X, dof, G, *old)
            assert np.array_equal(sweep_kernel.gather(X, dof, G, *new), want)
            assert np.array_equal(pa._gather_numpy(X, *new), want)
            assert np.array_equal(pa._gather_numpy(X, *old), want)
            sched, _ = pa.schedule(Q, dQ, chk.W, chk._owner)
            assert np.array_equal(sched, want)
            checked += 1
    assert checked == 90


def test_kept_reach_is_the_reach():
    """Every shape of random robots: the kept turn reach equals _reach computed afresh (also on a second ask and for
    another point of the same shape)."""
    asked = 0
    for robot in [*random_robots(5, 7), *_improv_robots(10, 9)]:
        for geo in sweep._Tree(robot).geom_geometry:
            geo.computeLocalAABB()
            bb = geo.aabb_local
            c = (np.asarray(bb.min_, dtype=float) + np.asarray(bb.max_, dtype=float)) / 2
            for point in (c, c + 0.01):
                want = sweep_bounds._reach(geo, point)
                assert sweep_bounds._kept_reach(geo, point) == want == sweep_bounds._kept_reach(geo, point)
                asked += 1
    assert asked > 100


def test_vector_norm_is_numpys_norm():
    """vector_norm (the set-up's norms of placements and box diagonals) is numpy.linalg.norm bit for bit: random
    vectors of 1-9 entries over many magnitudes, strided views, zeros; and the set-up's numbers of random robots are
    the former expressions'."""
    rng = np.random.default_rng(12)
    for _ in range(3000):
        x = rng.normal(0, 1, int(rng.integers(1, 10))) * 10.0 ** rng.integers(-200, 200)
        for v in (x, x[::2], -x, 0 * x):
            with np.errstate(over="ignore"):   # (a huge vector's square overflows in both: inf)
                assert sweep_bounds.vector_norm(v) == float(np.linalg.norm(v))
    for robot in [*random_robots(5, 2), *_improv_robots(10, 6)]:
        tree = sweep._Tree(robot)
        joints, geoms = tree._norms
        assert joints == [float(np.linalg.norm(p.translation)) for p in tree.placements]
        assert geoms == [float(np.linalg.norm(p.translation)) for p in tree.geom_placement]
        pa = sweep.SweepChecker(robot, posed_arms=True)._posed
        boxes = [(np.asarray(g.aabb_local.min_, dtype=float), np.asarray(g.aabb_local.max_, dtype=float))
                 for g in tree.geom_geometry]
        assert pa.box_half_diagonal.tobytes() == np.array([float(np.linalg.norm(hi - lo)) / 2
                                                           for lo, hi in boxes]).tobytes()
