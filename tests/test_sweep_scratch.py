"""A SweepChecker's scratch space kept for the next checker (model/sweep_scratch.py, issue 25): after
KeptScratch.lend every distance equals, bit for bit, that of a new pinocchio.GeometryData asked the same queries
in the same order, over seeded random sequences of pairs and configurations; the same sequences in a scratch space
used on without the reset differ (coal's GJK warm start), so the comparison sees the state it removes. And a
SweepChecker in a kept scratch space gives a new one's events and query counts, check after check."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
from test_sweep_clearance import _into_obstacle

from robodesign.model import sweep
from robodesign.model.cell import solution_robot
from robodesign.model.sweep_scratch import KeptScratch


def _queries(robot, gd, seq):
    """min_distance of every (configuration, pair) of ``seq`` asked in ``gd``, as bytes."""
    gm, out = robot.geom_model, []
    for q, pairs in seq:
        pin.updateGeometryPlacements(robot.model, robot.data, gm, gd, q)
        out += [pin.computeDistance(gm, gd, int(p)).min_distance for p in pairs]
    return np.array(out).tobytes()


def _sequence(robot, Q, rng, n_pairs):
    """A random query sequence: configurations near the motion's samples, each with random pairs."""
    seq = []
    for _ in range(12):
        q = Q[rng.integers(len(Q))] + rng.normal(0.0, 0.05, robot.dof)
        seq.append((q, rng.choice(n_pairs, size=int(rng.integers(1, 12)), replace=False)))
    return seq


def test_a_lent_scratch_space_answers_as_a_new_one(ptp3_solved):
    task, ms, sol = ptp3_solved
    robot = solution_robot(task, sol, ms)
    gm, Q = robot.geom_model, np.asarray(sol.trajectory.q)
    n_pairs = len(gm.collisionPairs)
    rng = np.random.default_rng(11)
    kept, used_on = KeptScratch(gm), pin.GeometryData(gm)
    differ = 0
    for _ in range(40):
        seq = _sequence(robot, Q, rng, n_pairs)
        new = _queries(robot, pin.GeometryData(gm), seq)
        gd = kept.lend()
        for q, pairs in seq:
            kept.asked.update(int(p) for p in pairs)
        assert _queries(robot, gd, seq) == new
        differ += _queries(robot, used_on, seq) != new
    assert differ > 0   # without the reset the warm starts show
    new_req, req = pin.GeometryData(gm).distanceRequests, kept.lend().distanceRequests
    for k in range(n_pairs):   # every request as a new one's again
        assert np.array_equal(req[k].cached_gjk_guess, new_req[k].cached_gjk_guess)
        assert np.array_equal(req[k].cached_support_func_guess, new_req[k].cached_support_func_guess)


def test_a_checker_in_a_kept_scratch_space_finds_a_new_ones_events(ptp3_solved):
    task, ms, sol = ptp3_solved
    robot = solution_robot(task, sol, ms)
    Q0 = np.asarray(sol.trajectory.q)
    motions = [Q0]
    for k in (60, 175, 290):
        hit = _into_obstacle(robot, Q0, k)
        if hit is not None:
            Q = Q0.copy()
            Q[k] = hit[0]
            motions.append(Q)
    rng = np.random.default_rng(3)
    motions += [Q0 + rng.normal(0.0, 0.02, Q0.shape) for _ in range(3)]
    kept = KeptScratch(robot.geom_model)
    found = queries = 0
    for i in rng.permutation(np.tile(np.arange(len(motions)), 2)):
        key = lambda es: [(e.sample, e.s, e.first, e.second, e.distance, e.environment) for e in es]  # noqa: E731
        a = sweep.SweepChecker(robot, posed_arms=True, scratch=kept)
        b = sweep.SweepChecker(robot, posed_arms=True)
        n = robot.n_self_collision_pairs
        for cols in (range(n), range(n, len(a.pairs))):   # the judge's two sets, in one scratch space
            sa, sb = a.subset(cols), b.subset(cols)
            ea, eb = sa.check(motions[i], first_only=False), sb.check(motions[i], first_only=False)
            assert key(ea) == key(eb) and sa.queries == sb.queries
            queries += sa.queries
            found += len(ea)
        assert kept.asked
    assert found > 0 and queries > 0 and len(motions) > 4


def test_a_scratch_space_fits_only_its_geometry(ptp3_solved):
    task, ms, sol = ptp3_solved
    robot = solution_robot(task, sol, ms)
    kept = KeptScratch(robot.geom_model)
    assert kept.fits(robot.geom_model)
    assert not kept.fits(robot._robot_only_geom())
    robot.geom_model.addGeometryObject(robot.geom_model.geometryObjects[0])
    assert not kept.fits(robot.geom_model)


def test_one_pairs_distance_is_the_pairs_distances(ptp3_solved):
    """SweepChecker.distance (the advancement's one-pair query) is distances(q, [c]) bit for bit, counts one query,
    and records the pair asked in a kept scratch space as distances does: over a seeded random sequence of
    configurations and pairs in two checkers (the one-pair query in one, distances in the other), both against a
    plain pinocchio.GeometryData asked the same queries."""
    task, ms, sol = ptp3_solved
    robot = solution_robot(task, sol, ms)
    Q = np.asarray(sol.trajectory.q)
    rng = np.random.default_rng(17)
    ka, kb = KeptScratch(robot.geom_model), KeptScratch(robot.geom_model)
    a = sweep.SweepChecker(robot, posed_arms=True, scratch=ka)
    b = sweep.SweepChecker(robot, posed_arms=True, scratch=kb)
    seq = [(q, [int(c)]) for q, cs in _sequence(robot, Q, rng, len(a.pairs)) for c in cs]
    got = np.array([a.distance(q, cs[0]) for q, cs in seq]).tobytes()
    assert got == np.array([b.distances(q, cs)[0] for q, cs in seq]).tobytes()
    plain = _queries(robot, pin.GeometryData(robot.geom_model), [(q, [a.pairs[c] for c in cs]) for q, cs in seq])
    assert got == plain and a.queries == b.queries == len(seq) > 20
    assert ka.asked == kb.asked == {a.pairs[cs[0]] for _, cs in seq}
