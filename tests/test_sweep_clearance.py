"""The robot–obstacle clearance bounds of the judge's sweep (robodesign.model.sweep_clearance) against coal's exact
distances, on the judged motion of a solved IMPROV arm in PTP_3 (the CNC mesh), on random configurations and on
configurations nudged into the mesh; the steps they certify against exact distances inside each step; and the
sweep with and without them: the same collision events (between the samples too), fewer queries. The self pairs'
bounds (their spheres) likewise."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from test_sweep import random_q

from robodesign.formats.solution import SolutionTrajectory
from robodesign.judge import checker
from robodesign.judge.quantities import TrajectoryQuantities
from robodesign.model import sweep, sweep_clearance, sweep_kernel
from robodesign.model.cell import solution_robot
from robodesign.model.collision_cull import SLACK

pytestmark = pytest.mark.skipif(not sweep_kernel.available(), reason="numba unavailable or ROBODESIGN_JIT=0")


@pytest.fixture(scope="module")
def ptp3(ptp3_solved):
    assert sweep_kernel.warm_up()
    task, ms, solution = ptp3_solved
    return task, ms, solution, solution_robot(task, solution, ms)


def _env_pairs(chk):
    return [c for c in range(len(chk.pairs)) if chk.is_env[c]]


def _exact(robot, chk, Q, cols):
    """(len(Q), len(cols)) coal's distances, pinocchio's placements (as the sweep queries them)."""
    gm, gd = robot.geom_model, pin.GeometryData(robot.geom_model)
    out = np.empty((len(Q), len(cols)))
    for k, q in enumerate(Q):
        pin.updateGeometryPlacements(robot.model, robot.data, gm, gd, q)
        out[k] = [pin.computeDistance(gm, gd, chk.pairs[c]).min_distance for c in cols]
    return out


def _bounds(robot, chk, Q, cols):
    """(len(Q), len(cols)) the clearance bounds of the pairs at the rows of Q (their geometries' poses from batched
    FK, as the sweep has them): robot–obstacle pairs' from the distance fields, self pairs' from the spheres."""
    chk._posed.segments(Q, np.abs(np.diff(Q, axis=0)), chk.W, chk._owner)
    TG = chk._posed.poses()
    obst = np.array([chk._obst[c] for c in cols])
    geo = np.array([chk._mov[c] for c in cols], dtype=np.int64)
    other = np.array([chk._ref[c] for c in cols], dtype=np.int64)
    out = np.empty((len(Q), len(cols)))
    for ob in np.unique(obst):
        mine = obst == ob
        out[:, mine] = (sweep_clearance.clearance_bounds(robot, TG, geo[mine], int(ob), chk._spheres) if ob >= 0
                        else sweep_clearance.self_bounds(TG, geo[mine], other[mine], chk._spheres))
    return out


def _into_obstacle(robot, Q, k):
    """Configurations of sample k of Q moved along one joint: (the first that collides with an obstacle, the last
    free one before it and the first free one after the colliding run), or None."""
    for j in range(robot.dof):
        for sign in (1.0, -1.0):
            ts = sign * np.linspace(0.0, 1.5, 61)
            hits = []
            for t in ts:
                q = Q[k].copy()
                q[j] += t
                hits.append(robot.collides_with_obstacles(q))
            hits = np.array(hits)
            if hits[0] or not hits.any():
                continue
            i = int(np.argmax(hits))
            after = np.flatnonzero(~hits[i:])
            if len(after):
                qs = [Q[k].copy() for _ in range(3)]
                for q, t in zip(qs, (ts[i], ts[i - 1], ts[i + after[0]])):
                    q[j] += t
                return qs
    return None


def test_bounds_are_below_exact_distances(ptp3):
    task, ms, sol, robot = ptp3
    chk = sweep.SweepChecker(robot, posed_arms=True)
    cols = _env_pairs(chk)
    assert cols and chk._spheres is not None
    rng = np.random.default_rng(3)
    Q = np.vstack([sol.trajectory.q, random_q(robot, rng, 150)])
    hit = _into_obstacle(robot, np.asarray(sol.trajectory.q), len(sol.trajectory.q) // 2)
    assert hit is not None
    Q = np.vstack([Q, hit])
    lb, d = _bounds(robot, chk, Q, cols), _exact(robot, chk, Q, cols)
    assert np.all(lb <= d - SLACK + 1e-9)  # the bound keeps SLACK below the exact distance
    assert np.any(d <= 0) and np.all(lb[d <= 0] < 0)  # pairs in contact are never cleared
    near = d[: len(sol.trajectory.q)]  # on the solution's samples the bounds are close to the distances
    assert np.median(lb[: len(near)] / near) > 0.7


def test_self_bounds_are_below_exact_distances(ptp3):
    task, ms, sol, robot = ptp3
    chk = sweep.SweepChecker(robot, posed_arms=True)
    cols = [c for c in range(len(chk.pairs)) if not chk.is_env[c]]
    rng = np.random.default_rng(4)
    Q = np.vstack([sol.trajectory.q[::5], random_q(robot, rng, 100)])
    lb, d = _bounds(robot, chk, Q, cols), _exact(robot, chk, Q, cols)
    assert np.all(lb <= d - SLACK + 1e-9)
    assert np.any(d <= 0) and np.all(lb[d <= 0] < 0)
    assert np.mean(lb > 0) > 0.5  # most pairs of the arm are cleared by their spheres


def test_bounds_of_poses_that_are_no_numbers(ptp3):
    """A pose that is no number gives −inf (never a cell of the grid); one a googol metres away its box distance."""
    task, ms, sol, robot = ptp3
    chk = sweep.SweepChecker(robot, posed_arms=True)
    cols = _env_pairs(chk)
    Q = np.asarray(sol.trajectory.q[:3])
    _bounds(robot, chk, Q, cols)
    TG = chk._posed.poses().copy()
    TG[0] = np.nan
    TG[1, :, :, 3] = 1e300
    TG[2, :, 0, 3] = np.inf
    geo = np.array([chk._mov[c] for c in cols], dtype=np.int64)
    lb = sweep_clearance.clearance_bounds(robot, TG, geo, chk._obst[cols[0]], chk._spheres)
    assert np.all(lb[0] == -np.inf) and np.all(lb[2] == -np.inf)
    assert np.all(lb[1] > 1e299)


def test_certified_steps_are_free_inside(ptp3):
    """Every step the bounds certify on the judged motion: the exact distance at points inside the step keeps more
    than 4·tolerance above the margin."""
    task, ms, sol, robot = ptp3
    tq = TrajectoryQuantities.from_solution(robot, sol, task)
    Q = np.asarray(sol.trajectory.q)
    dQ = np.maximum(tq.motion.path_bound(), np.abs(np.diff(Q, axis=0)))
    chk = sweep.SweepChecker(robot, posed_arms=True)
    sched = chk._posed.segments(Q, dQ, chk.W, chk._owner)
    ext = 4 * chk.tolerance
    skip = sweep_clearance.open_steps(chk, chk._posed.poses(), sched, dQ, ext)
    P = len(chk.pairs)
    assert skip.shape == (P, len(Q) - 1) and np.all(skip >= np.arange(len(Q) - 1))
    certified = 0
    for k in range(0, len(Q) - 1, 7):
        steps = [c for c in range(P) if skip[c, k] > k]
        certified += len(steps)
        pts = [tq.motion.at(k, s) for s in np.linspace(0, 1, 9)]
        d = _exact(robot, chk, pts, steps)
        assert np.all(d - chk.margins[steps] > ext)
    env = _env_pairs(chk)
    assert np.all(skip[env, 0] == len(Q) - 1)  # the mesh pairs: certified from the first sample to the end
    assert certified > 0.8 * P * len(range(0, len(Q) - 1, 7))


def _events(chk, Q, **kw):
    return [(e.sample, e.s, e.first, e.second, e.distance, e.environment) for e in chk.check(Q, first_only=False, **kw)]


def _both_ways(robot, monkeypatch, Q, **kw):
    """(events, mesh queries, all queries) of the judge's sweep with the clearance bounds, and without (every step
    to coal)."""
    out = []
    for use in (True, False):
        if not use:
            monkeypatch.setattr(sweep, "open_steps", lambda *a, **k: None)
        chk = sweep.SweepChecker(robot, posed_arms=True)
        env = [0]
        real = chk.distances

        def counted(q, cols, real=real, env=env, chk=chk):
            env[0] += sum(bool(chk.is_env[c]) for c in cols)
            return real(q, cols)
        chk.distances = counted
        out.append((_events(chk, Q, **kw), env[0], chk.queries))
    monkeypatch.undo()
    return out


def test_same_events_fewer_mesh_queries(ptp3, monkeypatch):
    task, ms, sol, robot = ptp3
    tq = TrajectoryQuantities.from_solution(robot, sol, task)
    Q = np.asarray(sol.trajectory.q)
    m = tq.motion
    (a, na, qa), (b, nb, qb) = _both_ways(robot, monkeypatch, Q, path=m.path_bound(), at=m.at)
    assert a == b == [] and na < nb / 4 and qa < 0.6 * qb
    # a sample nudged into the mesh: contacts on the way into it (found inside the step before) and out of it
    hit = _into_obstacle(robot, Q, len(Q) // 2)
    Qn = Q.copy()
    Qn[len(Q) // 2] = hit[0]
    (a, na, qa), (b, nb, qb) = _both_ways(robot, monkeypatch, Qn)
    assert a == b and any(e[5] and e[1] > 0 for e in a)
    assert na < nb and qa < qb
    # two free samples with the mesh between them: a contact found between the samples only
    Q2 = np.array([hit[1], hit[2]])
    (a, *_), (b, *_) = _both_ways(robot, monkeypatch, Q2)
    assert a == b and any(e[5] and 0 < e[1] < 1 for e in a) and not any(e[1] == 0 and e[5] for e in a)


def test_judge_verdicts_with_and_without_the_bounds(ptp3, monkeypatch):
    """The full check of the solution and of mutations (shifted: contacts between samples; nudged into the mesh):
    the same verdict, violations and costs."""
    task, ms, sol, robot = ptp3
    tr = sol.trajectory
    q = tr.q.copy()
    q[tr.n // 2] = _into_obstacle(robot, np.asarray(tr.q), tr.n // 2)[0]
    for s in (sol, sol.with_(trajectory=SolutionTrajectory(tr.t, tr.q + 0.05, tr.dq, tr.ddq, dict(tr.goal2time))),
              sol.with_(trajectory=SolutionTrajectory(tr.t, q, tr.dq, tr.ddq, dict(tr.goal2time)))):
        v1 = checker.check(task, s, ms)
        with monkeypatch.context() as mp:
            mp.setattr(sweep, "open_steps", lambda *a, **k: None)
            v2 = checker.check(task, s, ms)
        assert v1.valid == v2.valid and v1.costs == v2.costs
        assert [x.to_json() for x in v1.violations] == [x.to_json() for x in v2.violations]
    assert not v1.valid and any(x.constraint == "collisionFree" for x in v1.violations)
