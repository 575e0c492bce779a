"""The checker's one vectorised pass (issue 25): batched TCP poses and twists equal pinocchio's per sample, the
motion's torques share their RNEA rows without changing a number, a SweepChecker's subset reports exactly the
full checker's events of its pairs, and the lever arms of the motion's own poses (SweepChecker(posed_arms=True))
bound every pair's motion over each step, never exceed the static bounds, and find the same contacts with fewer
distance queries."""
import numpy as np
import pytest
from conftest import COBRA as SHARED
from conftest import ROOT
from test_sweep import improv_robot, in_cell, pair_distances, random_q

from robodesign.design.problem import Problem
from robodesign.judge.quantities import TrajectoryQuantities
from robodesign.model.sweep import SweepChecker

IMPROV = SHARED / "modules" / "IMPROV"
BUILTIN = ROOT / "assets" / "modules" / "robodesign_arm"
PTP3 = SHARED / "tasks" / "simple" / "PTP_3.json"


def smooth_motion(robot, rng, n=40, h=0.05):
    """A smooth motion between two random configurations: t, q, dq, ddq (n samples)."""
    a, b = random_q(robot, rng, 2)
    t = np.arange(n) * h
    q = a + np.outer(0.5 - 0.5 * np.cos(np.pi * t / t[-1]), b - a)
    dq = np.gradient(q, t, axis=0)
    return t, q, dq, np.gradient(dq, t, axis=0)


@pytest.mark.parametrize("module_set,seed", [(IMPROV, 4), (BUILTIN, 5)])
def test_batched_tcp_poses_and_twists_are_pinocchio_s(module_set, seed):
    p = Problem.build(str(PTP3), str(module_set), "cyc")
    rng = np.random.default_rng(seed)
    for _ in range(3):
        r = in_cell(p, p.space.random_order(rng))
        t, q, dq, ddq = smooth_motion(r, rng)
        tq = TrajectoryQuantities(r, t, q, dq, ddq)
        assert np.max(np.abs(tq.tcp_poses - np.array([r.fk(x).copy() for x in q]))) < 1e-12
        assert np.max(np.abs(tq.tcp_twists - tq._tcp_twists_per_sample())) < 1e-12


def test_motion_torques_share_rows_exactly():
    """Every torque the judge reads is the robot's own RNEA of its rows, bit for bit."""
    p = Problem.build(str(PTP3), str(IMPROV), "cyc")
    rng = np.random.default_rng(6)
    r = in_cell(p, p.space.random_order(rng))
    t, q, dq, ddq = smooth_motion(r, rng)
    tq = TrajectoryQuantities(r, t, q, dq, ddq)
    before, after = tq.one_sided_accelerations
    v = tq.velocities
    assert np.array_equal(tq.motion_torques[0], r.drivetrain_torques(q, v, before))
    assert np.array_equal(tq.motion_torques[1], r.drivetrain_torques(q, v, after))
    assert np.array_equal(tq.motion_link_torques, r.link_torques(q, v, tq.motion_accelerations))
    assert np.array_equal(tq.motion_drivetrain_torques, r.drivetrain_torques(q, v, tq.motion_accelerations))
    assert np.array_equal(tq.torques, r.drivetrain_torques(q, dq, ddq))


def test_subset_reports_the_full_checkers_events():
    robot, _ = improv_robot()
    rng = np.random.default_rng(7)
    Q = random_q(robot, rng, 1)[0] + np.outer(np.linspace(0, 1, 30), 3.0 * rng.normal(size=robot.dof))
    full = SweepChecker(robot).check(Q, first_only=False)
    assert full  # the motion does collide
    n_self = robot.n_self_collision_pairs
    chk = SweepChecker(robot)
    parts = (chk.subset(range(n_self)).check(Q, first_only=False)
             + chk.subset(range(n_self, len(chk.pairs))).check(Q, first_only=False))
    assert sorted(parts, key=lambda e: (e.sample, e.s)) == full


@pytest.mark.parametrize("module_set,seed", [(IMPROV, 8), (BUILTIN, 9)])
def test_posed_arms_bound_each_step_densely(module_set, seed):
    """For every pair of random robots along motions through several samples: the distance changes over step k
    by at most the posed bound times the fraction of the step (dense samples, exact distances, the slack of
    tests/test_sweep.py for GJK's tolerance), and the posed bound never exceeds the static one."""
    p = Problem.build(str(PTP3), str(module_set), "cyc")
    rng = np.random.default_rng(seed)
    s = np.linspace(0.0, 1.0, 101)
    checked = 0
    for _ in range(2):
        r = in_cell(p, p.space.random_order(rng))
        chk = SweepChecker(r, posed_arms=True)
        Q = random_q(r, rng, 4)
        Q[1:] = Q[:-1] + 0.4 * (Q[1:] - Q[:-1])
        dQ = np.abs(np.diff(Q, axis=0))
        sched = chk._posed.segments(Q, dQ, chk.W, chk._owner)
        assert np.all(sched <= dQ @ chk.W + 1e-12)
        for k in range(len(Q) - 1):
            D = np.array([pair_distances(r, chk.pairs, Q[k] + x * (Q[k + 1] - Q[k])) for x in s])
            apart = (D[:-1] > 0) & (D[1:] > 0)
            slope = np.max(np.where(apart, np.abs(np.diff(D, axis=0)), 0.0), axis=0) / (s[1] - s[0])
            assert np.all(slope <= sched[k] + 1e-3), [(chk.pair_names[c], slope[c], sched[k, c])
                                                      for c in np.nonzero(slope > sched[k] + 1e-3)[0]]
            checked += int(np.sum(apart.all(axis=0)))
    assert checked > 100


def test_posed_arms_same_contacts_fewer_queries():
    """Two colliding motions of an IMPROV arm in PTP_3 (large and small steps): the same contacts (pair and step; the
    instant inside a grazing contact may move by tolerance / approach rate, as GJK's warm start follows the
    queries made before) with fewer distance queries."""
    robot, _ = improv_robot()
    rng = np.random.default_rng(10)
    for scale in (3.0, 0.3):
        Q = random_q(robot, rng, 1)[0] + np.outer(np.linspace(0, 1, 60), scale * rng.normal(size=robot.dof))
        static, posed = SweepChecker(robot), SweepChecker(robot, posed_arms=True)
        a, b = static.check(Q, first_only=False), posed.check(Q, first_only=False)
        assert [(e.sample, e.first, e.second, e.environment) for e in a] == \
            [(e.sample, e.first, e.second, e.environment) for e in b]
        for e in b:  # the instant found is a contact to the sweep's tolerance (where inside it depends on GJK)
            q = Q[e.sample] + e.s * (Q[e.sample + 1] - Q[e.sample]) if e.s > 0 else Q[e.sample]
            c = posed.pair_names.index((e.first, e.second))
            assert pair_distances(robot, [posed.pairs[c]], q)[0] <= 1e-5
        assert posed.queries < static.queries
