"""Torques certified on the judged motion between samples (issue 22; judge.interval_rnea, judge.arc_torques;
docs/checker.md "Torques between samples").

The enclosures are checked against pinocchio on dense samples of random arcs (every joint type robodesign
builds, gravity, a TCP wrench); the certification decides both ways on random two-arc steps of an arm with
friction; a torque that peaks between two samples (the arm swinging through its largest gravity load) is
INVALID even when it exceeds the limit by 1e-8 and the samples are within it, and the solver's trajectories
with active torque limits stay certified.
"""
import numpy as np
import pytest
from conftest import IMPROV, PRIMITIVES
from scipy.optimize import minimize_scalar

import robodesign.judge.checker as checker
import robodesign.judge.robots as judge_robots
from robodesign import Robot, load_module_set
from robodesign.formats.solution import SolutionTrajectory
from robodesign.judge.arc_torques import certify_arc_torques
from robodesign.judge.interval_rnea import IntervalDynamics
from robodesign.judge.motion import StepMotion
from robodesign.judge.quantities import TrajectoryQuantities
from robodesign.model.cell import solution_robot
from robodesign.solvers.timing import time_parameterize

ARM = ["1", "21", "4", "22", "5", "23", "12"]


@pytest.fixture(scope="module")
def robots(tmp_path_factory):
    from test_urdf import reversed_robot
    imp = load_module_set(IMPROV)
    prim = load_module_set(PRIMITIVES)
    from robodesign.core.spatial import homogeneous, rpy_to_matrix
    rs = [Robot.from_order(imp, ARM),
          Robot.from_order(imp, ["1", "22", "5", "23", "15", "29", "101"],
                           base_pose=homogeneous(rpy_to_matrix(0.3, -0.2, 1.0), [1.0, 2.0, 0.5])),
          Robot.from_order(prim, ["base", "J2", "i_30", "J1", "l_15", "J2", "eef"]),
          reversed_robot(tmp_path_factory.mktemp("rev"))]
    shorts = {r.model.joints[j].shortname() for r in rs for j in range(1, r.model.njoints)}
    assert {"JointModelRZ", "JointModelPZ", "JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned"} <= shorts
    return rs


def test_interval_dynamics_encloses_torque_and_rate(robots):
    """For random arcs (q = q0 + v0·t + a·t²/2 over δ), the enclosure holds RNEA and its rate at 81 instants
    (rate by central differences of pinocchio's RNEA along the arc); on a zero-width box the midpoint is
    pinocchio's RNEA."""
    rng = np.random.default_rng(5)
    for r in robots:
        dyn = IntervalDynamics(r)
        P, n = 20, r.dof
        for delta in (0.002, 0.02):
            q0, v0, a = rng.uniform(-2, 2, (P, n)), rng.uniform(-1.5, 1.5, (P, n)), rng.uniform(-8, 8, (P, n))
            W = rng.normal(0, 30, (P, 6))
            for wr in (None, W):
                ts = np.linspace(0, delta, 81)
                qs = np.array([q0 + v0 * t + a * t * t / 2 for t in ts])
                vs = np.array([v0 + a * t for t in ts])
                Q = ((qs.max(0) + qs.min(0)) / 2, (qs.max(0) - qs.min(0)) / 2)
                V = ((vs.max(0) + vs.min(0)) / 2, (vs.max(0) - vs.min(0)) / 2)
                T = dyn.link_torques(Q, V, a, wr)
                e = 1e-6
                for i in range(0, len(ts), 8):
                    val = r.link_torques(qs[i], vs[i], a, wr)
                    plus = r.link_torques(qs[i] + vs[i] * e + a * e * e / 2, vs[i] + a * e, a, wr)
                    minus = r.link_torques(qs[i] - vs[i] * e + a * e * e / 2, vs[i] - a * e, a, wr)
                    rate = (plus - minus) / (2 * e)
                    assert np.all(np.abs(val - T.m) <= T.r + 1e-9)
                    assert np.all(np.abs(rate - T.dm) <= T.dr + 1e-5 * (1 + np.abs(rate)))
                assert np.all(T.r > 0) or n == 0
            T0 = dyn.link_torques((q0, 0 * q0), (v0, 0 * v0), a, W)
            np.testing.assert_allclose(T0.m, r.link_torques(q0, v0, a, W), rtol=0, atol=1e-9)
            assert np.all(T0.r == 0)


def _dense_torque(r, m, n=400):
    """τ on the motion of step 0 at n+1 instants and at every joint's switch instant, there with both arcs'
    accelerations (τ jumps where q̈ does)."""
    h = m.h[0, 0]
    out = []
    for s in np.concatenate([np.linspace(0, h, n + 1), m.tau[0]]):
        for arc2 in (False, True):
            on2 = (s > m.tau[0]) | ((s == m.tau[0]) & arc2)
            u = np.where(on2, m.tau[0], s)
            w = np.where(on2, s - m.tau[0], 0.0)
            q = m.q[0] + m.v[0] * u + m.a1[0] * u * u / 2 + (m.v[0] + m.a1[0] * u) * w + m.a2[0] * w * w / 2
            v = m.v[0] + m.a1[0] * u + m.a2[0] * w
            acc = np.where(on2, m.a2[0], m.a1[0])
            out.append((s, r.drivetrain_torques(q[None], v[None], acc[None])[0]))
    return out


def test_certification_decides_both_ways(robots):
    """Random steps of 20 ms (two arcs per joint, the IMPROV arm with its friction): a limit 1e-7 below the
    densely sampled peak of a joint is found violated (a point above it), 0.1 % above it is certified."""
    r = robots[0]
    rng = np.random.default_rng(8)
    found = certified = 0
    for _ in range(12):
        h = 0.02
        q = rng.uniform(-1.5, 1.5, (2, r.dof))
        q[1] = q[0] + rng.uniform(-0.03, 0.03, r.dof)
        v = rng.uniform(-1.2, 1.2, (2, r.dof))
        m = StepMotion.through([0.0, h], q, v)
        dense = _dense_torque(r, m)
        peak = np.max([np.abs(t) for _, t in dense], axis=0)
        j = int(rng.integers(r.dof))
        lim = np.full(r.dof, 1e9)
        lim[j] = peak[j] * (1 - 1e-7)
        rep = certify_arc_torques(r, m, np.zeros((2, 6)), np.array([0]), lim)
        assert [v.joint for v in rep.violations] == [j] and rep.violations[0].certified_over
        assert abs(rep.violations[0].value) > lim[j]
        found += 1
        rep = certify_arc_torques(r, m, np.zeros((2, 6)), np.array([0]), peak * 1.001)
        assert rep.violations == []
        certified += 1
    assert found == certified == 12


@pytest.fixture(scope="module")
def ptp3(ptp3_solved):
    return ptp3_solved


def _swing(task, ms, sol, frac):
    """Joint 1 swings at 0.9 rad/s through its largest gravity torque, which it passes at fraction ``frac`` of
    the step from sample 10 to 11 (other joints still): samples every task.dt, constant velocity (the file's
    dq, ddq = 0 are the motion exactly). Returns (solution, peak |τ_1| between the samples, largest |τ_1| at
    the samples)."""
    robot = solution_robot(task, sol, ms)
    q_base = sol.trajectory.q[0].copy()
    w, dt = 0.9, task.dt

    def tau1(x):
        q = q_base.copy()
        q[1] = x
        v = np.zeros_like(q)
        v[1] = w
        return robot.drivetrain_torques(q[None], v[None], np.zeros((1, robot.dof)))[0, 1]
    xs = np.linspace(-np.pi, np.pi, 721)
    x0 = xs[int(np.argmax([abs(tau1(x)) for x in xs]))]
    x_peak = minimize_scalar(lambda x: -abs(tau1(x)), bounds=(x0 - 0.01, x0 + 0.01), method="bounded",
                             options={"xatol": 1e-12}).x
    t = dt * np.arange(21)
    t_peak = t[10] + frac * dt
    q = np.repeat(q_base[None], len(t), axis=0)
    q[:, 1] = x_peak + w * (t - t_peak)
    dq = np.zeros_like(q)
    dq[:, 1] = w
    s = sol.with_(trajectory=SolutionTrajectory(t, q, dq, np.zeros_like(q), {g: float(t[-1]) for g in
                                                                           sol.trajectory.goal2time}))
    return s, abs(tau1(x_peak)), max(abs(tau1(x)) for x in q[:, 1])


def _tau_violations(task, ms, sol, monkeypatch, limit):
    def weaker(task_, sol_, ms_):   # a robot of this check alone (never kept: judge.robots would lend it again)
        r = solution_robot(task_, sol_, ms_)
        r.tau_max = r.tau_max.copy()
        r.tau_max[1] = limit
        return r
    monkeypatch.setattr(judge_robots, "take", weaker)
    monkeypatch.setattr(judge_robots, "give_back", lambda task_, robot: None)
    v = checker.check(task, sol, ms, checker.CheckSettings(all_costs=False))
    return [x for x in v.violations if x.constraint == "joint.tau"]


def test_torque_peak_between_samples_is_invalid(ptp3, monkeypatch):
    """The gap: torques were checked only at samples. Joint 1 passes its largest gravity load in the middle of
    a step; with the limit halfway between the samples' largest |τ_1| and that peak, every sample is within
    the limit (with every acceleration the judge considers) and the motion is not: INVALID, naming joint 1, the
    step, the time and the value."""
    task, ms, sol = ptp3
    s, peak, at_samples = _swing(task, ms, sol, 0.5)
    assert peak > at_samples * (1 + 1e-6)
    limit = (peak + at_samples) / 2
    bad = _tau_violations(task, ms, s, monkeypatch, limit)
    assert len(bad) == 1, [str(x) for x in bad]
    v = bad[0]
    assert v.joint == 1 and v.sample == 10 and "between samples 10 and 11" in v.message
    assert s.trajectory.t[10] < v.time < s.trajectory.t[11]
    assert limit < abs(v.value) <= peak * (1 + 1e-12) and v.bound == limit
    assert f"{abs(v.value):.6g} between samples 10 and 11" in v.message
    # a limit just above the peak: valid (no torque violation at all)
    assert _tau_violations(task, ms, s, monkeypatch, peak * (1 + 1e-7)) == []


@pytest.mark.parametrize("frac", [0.137, 0.5, 0.861])
@pytest.mark.parametrize("excess", [5e-7, 3e-8, 3e-9])
def test_no_torque_excess_fits_between_samples(ptp3, monkeypatch, frac, excess):
    """A search for a cheat: the peak anywhere in the step, the limit below it by a relative 5e-7 … 3e-9 (the
    samples stay within it): always INVALID (the judge's only slack is LIMIT_RTOL = 1e-9)."""
    task, ms, sol = ptp3
    s, peak, at_samples = _swing(task, ms, sol, frac)
    limit = peak * (1 - excess)
    assert limit > at_samples * (1 + 1e-9)  # the samples pass
    bad = _tau_violations(task, ms, s, monkeypatch, limit)
    assert [(x.joint, x.sample) for x in bad] == [(1, 10)], [str(x) for x in bad]
    assert s.trajectory.t[10] <= bad[0].time <= s.trajectory.t[11]


@pytest.mark.parametrize("method,pair,scale", [("ruckig", (1, 3), 0.5), ("toppra", (2, 4), 0.4),
                                               ("ruckig", (2, 4), 0.3)])
def test_solver_trajectories_with_active_torque_limits_are_certified(method, pair, scale):
    """tests/test_timing.py's torque-limited moves (|τ| up to 0.998·τ_max at the samples): the torque on the
    judged motion is certified within the limit over every step."""
    from test_timing import PATH
    r = Robot.from_order(load_module_set(IMPROV), ARM)
    r.tau_max = r.tau_max * scale
    tr = time_parameterize(r, PATH[list(pair)], method=method)
    tq = TrajectoryQuantities(r, tr.t, tr.q, tr.dq, tr.ddq)
    assert max(np.max(np.abs(t) / r.tau_max) for t in tq.motion_torques) > 0.99  # the limit is active
    rep = certify_arc_torques(r, tq.motion, tq.external_wrenches, np.arange(tq.n - 1), r.tau_max * (1 + 1e-9),
                              sample_torques=tq.motion_torques)
    assert rep.violations == []


def test_non_finite_torque_is_reported_without_splitting(robots):
    """A huge position (1e308: the torque is nan) is a violation of its steps at once, not 2^12 splits."""
    r = robots[0]
    t = 0.01 * np.arange(4)
    q = np.zeros((4, r.dof))
    q[2, 0] = 1e308
    with np.errstate(all="ignore"):
        m = StepMotion.through(t, q, np.zeros_like(q))
        rep = certify_arc_torques(r, m, np.zeros((4, 6)), np.arange(3), r.tau_max)
    assert {v.step for v in rep.violations} == {1, 2} and not any(v.certified_over for v in rep.violations)
    assert all(not np.isfinite(v.value) for v in rep.violations) and rep.depth == 0


def test_refinement_work_is_bounded(ptp3, monkeypatch):
    """Near a peak the pieces are split until they decide (a limit 1e-7 above the peak: certified after a few
    levels); the number of pieces bounded one by one is capped (PIECES_PER_STEP): past it, what is undecided is
    reported as not certified, never accepted."""
    import robodesign.judge.arc_torques as at
    task, ms, sol = ptp3
    s, peak, _ = _swing(task, ms, sol, 0.3)
    robot = solution_robot(task, s, ms)
    tr = s.trajectory
    tq = TrajectoryQuantities(robot, tr.t, tr.q, tr.dq, tr.ddq)
    lim = np.full(robot.dof, 1e9)
    lim[1] = peak * (1 + 1e-7)
    steps = np.arange(tq.n - 1)
    rep = certify_arc_torques(robot, tq.motion, np.zeros((tq.n, 6)), steps, lim)
    assert rep.violations == [] and 1 <= rep.depth < at.MAX_DEPTH and rep.pieces <= at.PIECES_PER_STEP * len(steps)
    monkeypatch.setattr(at, "PIECES_PER_STEP", 0)
    rep = certify_arc_torques(robot, tq.motion, np.zeros((tq.n, 6)), steps, lim)
    assert [(v.step, v.joint, v.certified_over) for v in rep.violations] == [(10, 1, False)]
    assert abs(rep.violations[0].value) > lim[1]  # the bound that could not be brought under the limit


def test_mass_matrix_bound_holds_over_the_box(robots):
    """IntervalDynamics.mass_matrix_bound (what bounds the torque's jumps where an acceleration switches) holds
    |M(q)| (link side: pinocchio's CRBA minus the armature) at 30 points of each random box."""
    import pinocchio as pin
    rng = np.random.default_rng(9)
    for r in robots:
        dyn = IntervalDynamics(r)
        P, n = 10, r.dof
        lo = rng.uniform(-2, 2, (P, n))
        hi = lo + rng.uniform(0, 0.3, (P, n))
        B = dyn.mass_matrix_bound(((lo + hi) / 2, (hi - lo) / 2))
        for p in range(P):
            for _ in range(30):
                q = rng.uniform(lo[p], hi[p])
                M = pin.crba(r.model, r.data, q)
                M = np.triu(M) + np.triu(M, 1).T - np.diag(r.model.armature)
                assert np.all(np.abs(M) <= B[p] + 1e-9)
        assert np.all(B <= 1e3)  # and is a bound, not infinity


def test_wrench_inside_a_follow_window_is_certified_with_it(robots):
    """A TCP wrench on samples 2…5 (a follow goal's window) applies inside the steps 2→3 … 4→5, not in the steps
    entering or leaving the window. Certification against a limit 1e-7 below the dense peak of |τ| (computed under
    that rule) finds it; 0.1 % above it certifies every step."""
    r = robots[0]
    rng = np.random.default_rng(4)
    n, h = 8, 0.01
    t = h * np.arange(n)
    q = np.cumsum(rng.uniform(-0.01, 0.01, (n, r.dof)), axis=0) + rng.uniform(-1, 1, r.dof)
    v = rng.uniform(-0.8, 0.8, (n, r.dof))
    m = StepMotion.through(t, q, v)
    W = np.zeros((n, 6))
    W[2:6] = [40.0, -25.0, 60.0, 3.0, -2.0, 5.0]
    peak = np.zeros(r.dof)
    for k in range(n - 1):
        wk = W[k] if np.all(W[k] == W[k + 1]) else np.zeros(6)
        one = StepMotion.through(t[k:k + 2] - t[k], q[k:k + 2], m.v[k:k + 2])
        for s in np.concatenate([np.linspace(0, h, 61), one.tau[0]]):
            for arc2 in (False, True):
                on2 = (s > one.tau[0]) | ((s == one.tau[0]) & arc2)
                u = np.where(on2, one.tau[0], s)
                w = np.where(on2, s - one.tau[0], 0.0)
                qq = q[k] + one.v[0] * u + one.a1[0] * u * u / 2 + (one.v[0] + one.a1[0] * u) * w + one.a2[0] * w * w / 2
                vv = one.v[0] + one.a1[0] * u + one.a2[0] * w
                acc = np.where(on2, one.a2[0], one.a1[0])
                tau = r.drivetrain_torques(qq[None], vv[None], acc[None], wk[None] if np.any(wk) else None)[0]
                peak = np.maximum(peak, np.abs(tau))
    rep = certify_arc_torques(r, m, W, np.arange(n - 1), peak * 1.001)
    assert rep.violations == []
    j = int(np.argmax(peak / r.tau_max))
    lim = np.full(r.dof, 1e9)
    lim[j] = peak[j] * (1 - 1e-7)
    rep = certify_arc_torques(r, m, W, np.arange(n - 1), lim)
    assert {v.joint for v in rep.violations} == {j} and all(v.certified_over for v in rep.violations)
