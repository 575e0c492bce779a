"""The compiled sweep bounds (robodesign.model.sweep_kernel: posed lever arms, geometry poses, displacement
extensions) against the numpy path they replace: the same numbers bit for bit (issue 25), on the judge's motion of
a solved IMPROV arm in PTP_3 and on random motions; and the displacement extension against exact distances."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from robodesign.judge import checker
from robodesign.judge.quantities import TrajectoryQuantities
from robodesign.model import sweep, sweep_bounds, sweep_kernel
from robodesign.model.cell import solution_robot

pytestmark = pytest.mark.skipif(not sweep_kernel.available(), reason="numba unavailable or ROBODESIGN_JIT=0")
ARM = ["1", "21", "4", "22", "5", "23", "12"]


@pytest.fixture(scope="module")
def ptp3(ptp3_solved):
    task, ms, solution = ptp3_solved
    return task, ms, solution, solution_robot(task, solution, ms)


def _motions(sol, robot, task):
    """(Q, dQ): the judge's motion of the solution (its path bound, as checker._collision_violations passes it) and
    random walks, fast and slow, with a step of zero motion."""
    tq = TrajectoryQuantities.from_solution(robot, sol, task)
    Q = np.asarray(sol.trajectory.q)
    yield Q, np.maximum(tq.motion.path_bound(), np.abs(np.diff(Q, axis=0)))
    rng = np.random.default_rng(5)
    for scale in (0.002, 0.05, 0.6):
        Q = np.cumsum(rng.normal(0, scale, (60, robot.dof)), axis=0)
        Q[30] = Q[29]
        yield Q, np.abs(np.diff(Q, axis=0))


def test_kernel_equals_numpy_path_bit_for_bit(ptp3):
    task, ms, sol, robot = ptp3
    assert sweep_kernel.warm_up() and sweep_kernel.ready()
    chk = sweep.SweepChecker(robot, posed_arms=True)
    pa = chk._posed
    dof, G = pa.R.shape
    assert len(pa.flat) > 0  # arms to tighten: the kernel's path, not only the static arms
    idx = np.where(chk.W > 0, chk._owner, G)
    uniq, inverse = np.unique(idx, axis=1, return_inverse=True)
    uniq, inverse = np.ascontiguousarray(uniq, dtype=np.int64), inverse.reshape(-1).astype(np.int64)
    for Q, dQ in _motions(sol, robot, task):
        J = robot.joint_poses_batch(Q)
        A = pa._arms_numpy(J, dQ)
        B = sweep_kernel.posed_arms(J, *pa._k_tree, np.ascontiguousarray(dQ), *pa._k_drift, 1 + pa.SLACK)
        assert np.array_equal(A, B)
        static = (dQ[:, :, None] * pa.R[None]).reshape(len(dQ), dof * G)
        assert np.all(A <= static) and np.any(A < 0.9 * static)  # tighter than the static arms, never looser
        S = pa._gather_numpy(A, uniq, inverse)
        assert np.array_equal(S, sweep_kernel.gather(A, dof, G, uniq, inverse))
        # the gather is the sum of the owners' arms (the former numpy expression: the same numbers here)
        X3 = np.concatenate([A.reshape(len(A), dof, G), np.zeros((len(A), dof, 1))], axis=2)
        assert np.array_equal(S, X3[:, np.arange(dof)[:, None], uniq].sum(axis=1)[:, inverse])
        assert np.all(S <= dQ @ chk.W * (1 + 1e-12) + 1e-15)
        # the running sums of the schedule: numpy.cumsum's, with a 0 first, per pair
        rows = sweep_kernel.running_sums(S)
        assert np.array_equal(rows, np.concatenate([np.zeros((1, S.shape[1])), np.cumsum(S, axis=0)]).T)
        assert rows.flags.c_contiguous and np.all(np.diff(rows, axis=1) >= 0)


def test_check_is_the_same_with_and_without_the_kernel(ptp3, monkeypatch):
    """The full judge on the solution: the same verdict, violations and distance queries on either path."""
    task, ms, sol, _ = ptp3
    sweep_kernel.warm_up()
    calls = []
    real = sweep_bounds._kernel

    def counted(count=True):
        k = real(count)
        calls.append(k is not None)
        return k
    monkeypatch.setattr(sweep_bounds, "_kernel", counted)
    v1 = checker.check(task, sol, ms)
    assert calls and all(calls)
    monkeypatch.setattr(sweep_bounds, "_kernel", lambda count=True: None)
    v2 = checker.check(task, sol, ms)
    assert v1.valid and v2.valid
    assert [str(x) for x in v1.violations] == [str(x) for x in v2.violations]
    assert v1.costs == v2.costs


def _posed_motion(task, sol, robot):
    """The judge's checker on the solution's motion, its schedule bounds and geometry poses (kernel path)."""
    tq = TrajectoryQuantities.from_solution(robot, sol, task)
    Q = np.asarray(sol.trajectory.q)
    dQ = np.maximum(tq.motion.path_bound(), np.abs(np.diff(Q, axis=0)))
    chk = sweep.SweepChecker(robot, posed_arms=True)
    sched = chk._posed.segments(Q, dQ, chk.W, chk._owner)
    return tq, Q, chk, sched, chk._posed.poses(), sweep_kernel.running_sums(sched)


def test_geometry_poses_and_extend_equal_numpy_path_bit_for_bit(ptp3):
    task, ms, sol, robot = ptp3
    assert sweep_kernel.warm_up()
    tq, Q, chk, sched, TG, rows = _posed_motion(task, sol, robot)
    pa = chk._posed
    J = robot.joint_poses_batch(Q)
    assert np.array_equal(TG, sweep_bounds.geometry_poses_numpy(J, pa.geom_joint, pa.R_g, pa.t_g))
    # the poses are pinocchio's geometry placements (to rounding)
    gm, gd = robot.geom_model, pin.GeometryData(robot.geom_model)
    for k in (0, len(Q) // 2, len(Q) - 1):
        pin.updateGeometryPlacements(robot.model, robot.data, gm, gd, Q[k])
        for g in range(TG.shape[1]):
            np.testing.assert_allclose(TG[k, g], gd.oMg[g].homogeneous[:3], rtol=0, atol=1e-12)
    n, seen = len(Q), set()
    rng = np.random.default_rng(2)
    for c in range(len(chk.pairs)):
        for _ in range(4):
            k = int(rng.integers(0, n - 1))
            start = int(rng.integers(k, n - 1))
            limit = float(rng.choice([1e-4, 0.02, 0.3, 2.0]))
            args = (TG, chk._mov[c], chk._ref[c], pa.box_centre, pa.box_radius, k, start, sched, rows, c, limit)
            a = sweep_bounds.extend_numpy(*args)
            assert a == sweep_kernel.extend(*args, sweep_bounds.BOUND_SLACK)
            assert start <= a <= n - 1
            seen.add((a == start, a == n - 1))
    assert len(seen) == 3  # stopped at once, in between and at the end


def test_extension_is_certified_by_exact_distances(ptp3):
    """Every robot–obstacle pair and every second self pair, from a query at a sample: over the steps the
    displacement extension certifies, the exact distance (at the samples and inside each step, on the judge's
    motion) stays above the clearance at the query less the limit, less GJK's tolerance."""
    task, ms, sol, robot = ptp3
    tq, Q, chk, sched, TG, rows = _posed_motion(task, sol, robot)
    n, extended = len(Q), 0
    for c in list(np.nonzero(chk.is_env)[0]) + list(np.nonzero(~chk.is_env)[0][::2]):
        for k in (0, n // 3, 2 * n // 3):
            d = float(chk.distances(Q[k], [c])[0])
            limit = 0.5 * d
            end = chk._posed.extend(TG, chk._mov[c], chk._ref[c], k, k, sched, rows, int(c), limit)
            extended += end - k
            for i in range(k, min(end, n - 1)):
                for s in (0.0, 0.25, 0.5, 0.75, 1.0):
                    assert chk.distances(tq.motion.at(i, s), [c])[0] >= d - limit - 1e-6, (c, k, i, s)
    assert extended > 3000  # the extension certifies real stretches, not only single steps


def test_certify_equals_numpy_path(ptp3, monkeypatch):
    """The batch certification (the summed bound's reach, then the extension) of the kernel and of numpy, for
    every pair queried at several samples with several clearances, contacts and non-finite ones among them."""
    task, ms, sol, robot = ptp3
    sweep_kernel.warm_up()
    tq, Q, chk, sched, TG, rows = _posed_motion(task, sol, robot)
    pa, n = chk._posed, len(Q)
    mov, ref = np.array(chk._mov), np.array(chk._ref)
    due = list(range(len(chk.pairs)))
    rng = np.random.default_rng(9)
    kinds = set()
    for k in (0, 5, n // 2, n - 2):
        d = rng.choice([-0.01, 0.0, 1e-5, 0.01, 0.05, 0.3, 2.0, np.inf, np.nan], len(due))
        for self_too in (True, False):
            args = (due, d, k, chk.margins, chk.is_env, rows, TG, mov, ref, sched, 4e-6, self_too)
            a = pa.certify(*args)
            with monkeypatch.context() as m:
                m.setattr(sweep_bounds, "_kernel", lambda count=True: None)
                b = pa.certify(*args)
            assert a == b
            kinds |= {-1 if x == -1 else -2 if x == -2 else 0 if x == k else 1 if x < n - 1 else 2 for x in a}
    assert kinds == {-2, -1, 0, 1, 2}


def test_turn_reach_bounds_every_point(ptp3):
    """The turn bound of each IMPROV geometry (PosedArms.box_radius) covers every point of it from the box centre
    (the convex pieces' points, points of the cylinders' rims; a sphere's centre is the box centre: 0), and is
    tighter than the box's half diagonal for the primitives; primitives with an offset centre and a swept radius."""
    import coal
    from robodesign.model.sweep_bounds import _reach
    task, ms, sol, robot = ptp3
    chk = sweep.SweepChecker(robot, posed_arms=True)
    pa = chk._posed
    kinds = set()
    for g, geo in enumerate(sweep._Tree(robot).geom_geometry):
        c, rho, kind = pa.box_centre[g], pa.box_radius[g], type(geo).__name__
        kinds.add(kind)
        if kind == "Convex":
            P = np.asarray(geo.points()).reshape(-1, 3)
            assert np.max(np.linalg.norm(P - c, axis=1)) <= rho <= pa.box_half_diagonal[g]
        elif kind == "Sphere":
            assert rho < 1e-12
        elif kind == "Cylinder":
            a = np.linspace(0, 2 * np.pi, 64)
            rim = np.stack([geo.radius * np.cos(a), geo.radius * np.sin(a), np.full_like(a, geo.halfLength)], axis=1)
            assert np.max(np.linalg.norm(rim - c, axis=1)) <= rho < pa.box_half_diagonal[g]
    assert kinds == {"Convex", "Sphere", "Cylinder"}
    c = np.array([0.01, -0.02, 0.03])
    for shape, far in ((coal.Cylinder(0.1, 0.4), [0.1 * np.cos(2.03), 0.1 * np.sin(2.03), -0.2]),
                       (coal.Cone(0.1, 0.4), [0.1 * np.cos(2.03), 0.1 * np.sin(2.03), -0.2]),
                       (coal.Capsule(0.1, 0.4), [0.0, 0.0, -0.3]), (coal.Sphere(0.1), [0.0, 0.0, 0.0])):
        shape.setSweptSphereRadius(0.01)
        rho = _reach(shape, c)
        assert np.linalg.norm(np.array(far) - c) + (0.01 if type(shape).__name__ != "Sphere" else 0.0) <= rho
    assert _reach(coal.Box(0.1, 0.2, 0.3), c) == np.inf
