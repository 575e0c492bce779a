"""Time parameterization (toppra / ruckig), the JointTrajectory type and the analytic bounds."""
import math

import numpy as np

from conftest import assert_within_limits as check_limits
import pytest

from conftest import COBRA as _COBRA

from robodesign import Robot, load_module_set
from robodesign.solvers.timing import (BlendedPolyline, JointTrajectory, TimingError, jerk_limited_time,
                                       time_optimal_bound, time_parameterize, trapezoid_time)

COBRA = _COBRA / "modules"
ARM = ["1", "21", "4", "22", "5", "23", "12"]
DT = 0.01


@pytest.fixture(scope="module")
def arm():
    return Robot.from_order(load_module_set(COBRA / "IMPROV"), ARM)


@pytest.fixture(scope="module")
def weak_arm():
    """The same arm with halved torque limits: the torque limit becomes the active constraint."""
    r = Robot.from_order(load_module_set(COBRA / "IMPROV"), ARM)
    r.tau_max = r.tau_max * 0.5
    return r


@pytest.fixture(scope="module")
def one_joint():
    r = Robot.from_order(load_module_set(COBRA / "geometric_primitive_modules"), ["base", "J2", "eef"])
    assert r.dof == 1
    r.dq_max = np.array([1.0])
    r.ddq_max = np.array([2.0])
    return r


PATH = np.array([[0.0, -0.5, 1.0, 0.0, 0.5, 0.0],
                 [0.6, -0.2, 0.8, 0.4, 0.2, 0.3],
                 [1.0, 0.3, 0.2, 0.6, -0.3, 0.8],
                 [0.7, 0.6, -0.4, 0.8, -0.6, 1.0],
                 [0.2, 0.4, -0.1, 0.3, -0.2, 0.4]])


def check_sampling(tr, dt=DT):
    assert tr.t[0] == 0.0
    np.testing.assert_allclose(np.diff(tr.t), dt, rtol=0, atol=1e-12)
    rq, rv = tr.consistency_residual()
    assert rq < 1e-10 and rv < 1e-10
    for k in (0, -1):  # rest at both ends, exactly
        assert np.all(tr.dq[k] == 0.0) and np.all(tr.ddq[k] == 0.0)
    if len(tr) > 1:  # one step of pre-roll: the motion starts at the second sample
        assert np.all(tr.q[1] == tr.q[0]) and np.all(tr.dq[1] == 0.0)


def dist_to_samples(tr, p):
    return float(np.min(np.linalg.norm(tr.q - p, axis=1)))


# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["toppra", "ruckig"])
def test_limits_rest_stops_and_waypoints(arm, method):
    tr = time_parameterize(arm, PATH, dt=DT, method=method, stop_at=[2])
    check_sampling(tr)
    check_limits(arm, tr)
    np.testing.assert_array_equal(tr.q[0], PATH[0])
    np.testing.assert_array_equal(tr.q[-1], PATH[-1])
    stops = tr.info["stop_samples"]
    assert stops[0] == 0 and stops[len(PATH) - 1] == len(tr) - 1 and 2 in stops
    for i, k in stops.items():  # at rest exactly on the waypoint
        np.testing.assert_array_equal(tr.q[k], PATH[i])
        assert np.all(tr.dq[k] == 0.0)
    if method == "ruckig":
        assert sorted(stops) == list(range(len(PATH)))  # ruckig stops everywhere
    # passes every waypoint: within the blend bound + half a sample step (+ sampling error)
    vstep = float(np.max(np.linalg.norm(tr.dq, axis=1))) * DT / 2
    bp = BlendedPolyline(PATH[:3], 0.05)
    bound = max(bp.max_waypoint_distance, BlendedPolyline(PATH[2:], 0.05).max_waypoint_distance)
    for p in PATH:
        assert dist_to_samples(tr, p) <= bound + vstep + tr.info["max_path_error"] + 1e-9
    # the cycle time is not below the per-segment lower bounds between stops
    assert tr.duration >= time_optimal_bound(arm, PATH[0], PATH[2]) + time_optimal_bound(arm, PATH[2], PATH[4]) - 1e-9


def test_toppra_respects_active_torque_limits(weak_arm):
    path = PATH[[0, 3]]
    free = time_parameterize(weak_arm, path, torque_limits=False)
    tr = time_parameterize(weak_arm, path)
    assert tr.info["method"] == "toppra"
    check_sampling(tr)
    worst = check_limits(weak_arm, tr)
    assert worst > 0.97  # the torque limit is what limits the motion ...
    assert tr.duration > free.duration + 0.2  # ... and it costs time
    # the unconstrained version does violate the halved limits (so the check above is meaningful)
    tau = weak_arm.drivetrain_torques(free.q, free.dq, free.ddq)
    assert np.max(np.abs(tau) / weak_arm.tau_max) > 1.0


def test_ruckig_torque_check_slows_down(weak_arm):
    tr = time_parameterize(weak_arm, PATH[[0, 3]], method="ruckig")
    check_sampling(tr)
    check_limits(weak_arm, tr)
    assert tr.info["stretch"] > 1.0


def test_gravity_infeasible_path_raises(arm):
    r = Robot(arm.module_set, arm.assembly)
    r.tau_max = r.tau_max * 0.05
    with pytest.raises(TimingError):
        time_parameterize(r, PATH[[0, 3]])


# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("D", [0.1, 0.4, 0.5, 1.0, 2.5])
def test_one_joint_matches_trapezoid(one_joint, D):
    v, a = 1.0, 2.0
    expected = D / v + v / a if D > v * v / a else 2 * math.sqrt(D / a)
    assert trapezoid_time(D, v, a) == pytest.approx(expected)
    path = np.array([[-1.0], [-1.0 + D]])
    tr = time_parameterize(one_joint, path, method="toppra")
    check_sampling(tr)
    check_limits(one_joint, tr)
    # + one dt of pre-roll (rest step at the start) + rounding up to the grid
    assert expected + DT - 1e-9 <= tr.duration <= expected + 2 * DT + 1e-9
    # ruckig with jerk = 10·a: the analytic 7-segment time, rounded up to the sample grid
    j = 10 * a
    tj = jerk_limited_time(D, v, a, j)
    if D >= v * (v / a + a / j):  # cruise phase: closed form
        assert tj == pytest.approx(D / v + v / a + a / j)
    assert tj >= expected
    rk = time_parameterize(one_joint, path, method="ruckig", jerk_factor=10.0)
    check_sampling(rk)
    check_limits(one_joint, rk)
    assert tj + DT - 1e-9 <= rk.duration <= tj + 2 * DT + 1e-9


def test_time_optimal_bound(arm):
    qa, qb = PATH[0], PATH[3]
    per_joint = [trapezoid_time(abs(qb[j] - qa[j]), arm.dq_max[j], arm.ddq_max[j]) for j in range(6)]
    assert time_optimal_bound(arm, qa, qb) == pytest.approx(max(per_joint))
    tr = time_parameterize(arm, PATH[[0, 3]], torque_limits=False)
    assert time_optimal_bound(arm, qa, qb) - 1e-9 <= tr.duration <= time_optimal_bound(arm, qa, qb) + 0.05


def test_blend_deviation_bound():
    W = PATH[:, :3]
    bp = BlendedPolyline(W, 0.2)
    s = np.linspace(0, bp.length, 20001)
    Q = bp(s)

    def dist_polyline(p):
        best = np.inf
        for a, b in zip(W[:-1], W[1:]):
            t = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0, 1)
            best = min(best, np.linalg.norm(a + t * (b - a) - p))
        return best

    dev = max(dist_polyline(p) for p in Q[::20])
    assert dev <= bp.max_deviation + 1e-12
    assert dev > 0.5 * bp.max_deviation  # the bound is tight-ish
    # C1 with unit speed on straight parts, ends on the waypoints
    np.testing.assert_allclose(bp(0.0), W[0])
    np.testing.assert_allclose(bp(bp.length), W[-1])
    d1 = bp(s, 1)
    assert np.max(np.linalg.norm(np.diff(d1, axis=0), axis=1)) < 1e-2


# ------------------------------------------------------------------------------------------------
def test_hold_is_exact(arm):
    tr = time_parameterize(arm, PATH[:2], method="ruckig")
    n = len(tr)
    held = tr.hold(0.255, DT)
    assert len(held) == n + 26  # ceil(0.255/0.01)
    assert held.t[-1] - tr.t[-1] >= 0.255 - 1e-9
    tail = slice(n - 1, None)  # the pause window includes the last sample of the motion
    assert np.all(held.q[tail] == tr.q[-1])
    assert np.all(held.dq[tail] == 0.0) and np.all(held.ddq[tail] == 0.0)
    rq, rv = held.consistency_residual()
    assert rq < 1e-10 and rv < 1e-10
    moving = JointTrajectory(tr.t[:5], tr.q[:5], tr.dq[:5], tr.ddq[:5])
    with pytest.raises(ValueError):
        moving.hold(0.1, DT)


def test_concatenate_shares_the_junction(arm):
    a = time_parameterize(arm, PATH[:2], method="ruckig")
    b = time_parameterize(arm, PATH[1:3], method="ruckig")
    c = a.concatenate(b)
    assert len(c) == len(a) + len(b) - 1
    assert c.duration == pytest.approx(a.duration + b.duration)
    np.testing.assert_array_equal(c.q[len(a) - 1], PATH[1])
    check_sampling(c)
    np.testing.assert_allclose(c.q[len(a) - 1:], b.q)
    with pytest.raises(ValueError):
        a.concatenate(time_parameterize(arm, PATH[2:4], method="ruckig"))


def test_interpolate_follows_the_integration_rule(arm):
    tr = time_parameterize(arm, PATH[:3])
    q, dq, ddq = tr.interpolate(tr.t)
    np.testing.assert_allclose(q, tr.q, atol=1e-12)
    np.testing.assert_allclose(dq, tr.dq, atol=1e-12)
    tm = tr.t[:-1] + 0.5 * DT
    q, dq, _ = tr.interpolate(tm)
    np.testing.assert_allclose(q, tr.q[:-1] + tr.dq[:-1] * DT / 2 + tr.ddq[:-1] * DT ** 2 / 8, atol=1e-12)


def test_duplicate_waypoints_and_single_point(arm):
    tr = time_parameterize(arm, np.vstack([PATH[0], PATH[0], PATH[1], PATH[1]]))
    check_sampling(tr)
    np.testing.assert_array_equal(tr.q[-1], PATH[1])
    still = time_parameterize(arm, PATH[:1])
    assert len(still) == 1 and still.duration == 0.0


@pytest.mark.parametrize("method,pair,scale", [("ruckig", (1, 3), 0.5), ("toppra", (2, 4), 0.4),
                                               ("ruckig", (2, 4), 0.3)])
def test_torques_hold_with_the_accelerations_the_judge_sees_before_each_sample(method, pair, scale):
    """The judge's motion model has two accelerations at a sample: ddq[k] after it and ddq[k-1] before it
    (robodesign.judge.motion). Time scaling that checked only the first gave these moves |τ| up to 1.0052·τ_max
    with the second (measured before the fix), so the checker rejected the solver's own output."""
    from robodesign.judge.quantities import TrajectoryQuantities
    r = Robot.from_order(load_module_set(COBRA / "IMPROV"), ARM)
    r.tau_max = r.tau_max * scale
    tr = time_parameterize(r, PATH[list(pair)], method=method)
    check_sampling(tr)
    assert check_limits(r, tr) > 0.99  # the torque limit is active, and holds on both sides of every sample
    tq = TrajectoryQuantities(r, tr.t, tr.q, tr.dq, tr.ddq)
    for tau in tq.motion_torques:  # the checker's own "before" and "after" torques
        assert np.max(np.abs(tau) / r.tau_max) <= 1 + 1e-9


def test_a_torque_limit_that_slowing_cannot_meet_ends_early(arm, monkeypatch):
    """Gravity alone is within the limit at every sample, gravity plus Coulomb friction while moving is not:
    no slow-down helps. The sample check gives up once slow-downs stop reducing the torque ratio (after two
    doublings of the duration) or the motion would be 100 times slower than its profile, instead of resampling
    60 times (here: to 10⁷ samples when a joint's friction exceeded its limit)."""
    import robodesign.solvers.timing as timing
    r = Robot.from_order(load_module_set(COBRA / "IMPROV"), ARM)
    path = PATH[[0, 3]]
    s = np.linspace(0, 1, 400)[:, None]
    Q = path[0] + s * (path[1] - path[0])
    g = np.max(np.abs(r.drivetrain_torques(Q, np.zeros_like(Q), np.zeros_like(Q))), axis=0)
    r.friction_coulomb = np.maximum(r.friction_coulomb, 0.05 * g + 0.5)
    r.tau_max = g + 0.6 * r.friction_coulomb  # holds every pose of the path at rest, but not while moving
    calls = []
    real = timing._sample
    monkeypatch.setattr(timing, "_sample", lambda *a: calls.append(1) or real(*a))
    with pytest.raises(TimingError, match="slowing down does not bring the torque|slowed down more than 100 times"):
        time_parameterize(r, path, method="ruckig")
    assert len(calls) < 30  # the old check ran all 60 slow-downs


@pytest.mark.parametrize("which", ["arm", "weak_arm"])
def test_converged_torque_passes_are_not_repeated(which, request, monkeypatch):
    """A torque pass whose tangent points equal the previous pass's is not run again: the trajectory is the
    one all passes give (the IMPROV arm: pass 2 repeats pass 1; halved torque limits: the passes differ)."""
    from robodesign.solvers import timing
    robot = request.getfixturevalue(which)
    path = PATH[[0, 3]]
    quick = time_parameterize(robot, path)
    passes = timing._toppra_profile(robot, timing.BlendedPolyline(path, 0.05), timing._finite(robot.dq_max),
                      timing._finite(robot.ddq_max), True, 0.02, 3)[1]["torque_passes"]
    monkeypatch.setattr(timing, "_same_tangents", lambda a, b: False)
    full = time_parameterize(robot, path)
    for a, b in ((quick.t, full.t), (quick.q, full.q), (quick.dq, full.dq), (quick.ddq, full.ddq)):
        assert np.array_equal(a, b)
    assert passes == (2 if which == "arm" else 3)


@pytest.mark.parametrize("which", ["arm", "weak_arm"])
def test_lean_toppra_loop_gives_toppras_numbers(which, request):
    """toppra_loop.rest_to_rest runs toppra's controllable-set and forward passes without its per-stage Python
    overhead: the same path velocities, bit for bit, as toppra's compute_parameterization (free and torque-limited)."""
    from robodesign.solvers import timing
    robot = request.getfixturevalue(which)
    tp = timing._toppra()
    dyn_cls = timing._dynamics_constraint_class()
    path = timing.BlendedPolyline(PATH, 0.05)
    grid = path.gridpoints(0.02)
    terms = timing._PathTerms(robot, path, grid, True)
    vmax, amax = timing._finite(robot.dq_max), timing._finite(robot.ddq_max)

    def algo():
        dyn = dyn_cls(robot, amax, np.asarray(robot.tau_max, float), np.full(len(grid), 0.3), True, terms)
        return tp.algorithm.TOPPRA([timing._velocity_constraint(vmax), dyn], path, gridpoints=grid,
                                   solver_wrapper="seidel")
    ref = algo()
    ref.compute_parameterization(0.0, 0.0)
    from robodesign.solvers.toppra_loop import rest_to_rest
    lean = rest_to_rest(algo())
    assert lean is not None and np.array_equal(lean, ref.problem_data.sd_vec)
