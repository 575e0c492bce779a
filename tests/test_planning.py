"""plan_path / check_path: collision-free joint paths around an obstacle that blocks the straight line."""
import math

import coal
import numpy as np
import pytest

from robodesign.core.errors import InputError
from robodesign.formats.module_io import load_module_set
from robodesign.model.robot import Obstacle, Robot
from robodesign.solvers.planning import available_planners, check_path, plan_path

from conftest import IMPROV

ORDER = ["1", "21", "4", "22", "5", "23", "12"]
QA = np.array([1.2, 0.6, 0.3, 0.8, 0.0, 0.5])
QB = np.array([-1.2, 0.6, -0.3, 0.8, 0.0, 0.5])


@pytest.fixture(scope="module")
def robot():
    r = Robot.from_order(load_module_set(IMPROV), ORDER)
    # a 15 cm box around the TCP of the midpoint of the straight line QA→QB
    mid = 0.5 * (QA + QB)
    P = np.eye(4)
    P[:3, 3] = r.fk(mid)[:3, 3]
    r.set_obstacles([Obstacle("box", coal.Box(0.15, 0.15, 0.15), P)])
    return r


def dense_ok(robot, path, step):
    """Independent dense check: every state at most ``step`` apart (per joint) is collision-free."""
    for a, b in zip(path[:-1], path[1:]):
        n = max(1, math.ceil(np.max(np.abs(b - a)) / step))
        for k in range(n + 1):
            q = a + (b - a) * (k / n)
            if robot.in_collision(q) or np.any(q < robot.q_lower) or np.any(q > robot.q_upper):
                return False
    return True


def test_setup_blocks_the_straight_line(robot):
    assert not robot.in_collision(QA) and not robot.in_collision(QB)
    assert robot.in_collision(0.5 * (QA + QB))
    ok, bad = check_path(robot, np.array([QA, QB]), 0.01)
    assert not ok and bad == 0


def test_plan_around_the_box(robot):
    res = plan_path(robot, QA, QB, time_limit=5.0, seed=1)
    assert res.success and res.stats["reason"] == "planned" and not res.stats["straight_line"]
    P = res.path
    assert P.ndim == 2 and P.shape[1] == robot.dof and len(P) >= 3
    assert np.array_equal(P[0], QA) and np.array_equal(P[-1], QB)      # start and goal exact
    assert check_path(robot, P, 0.005) == (True, -1)
    assert dense_ok(robot, P, 0.005)
    assert res.stats["length"] == pytest.approx(float(np.sum(np.linalg.norm(np.diff(P, axis=0), axis=1))))
    # every state is evaluated once: the final dense check of the shortcut path only revisits states the
    # shortcuts decided, so fewer states are evaluated than looked up; the planner's single states are one
    # full collision query each, the segments' states are decided by the culled queries (collision_cull.py)
    calls = []
    real = robot.in_collision
    robot.in_collision = lambda q: calls.append(1) or real(q)
    try:
        again = plan_path(robot, QA, QB, time_limit=5.0, seed=1)
    finally:
        del robot.in_collision
    assert np.array_equal(again.path, P)
    assert 0 < len(calls) < again.stats["distinct_states"] < again.stats["lookups"]


def test_culled_segment_checks_plan_the_same_path(robot, monkeypatch):
    """The segments' states decided with the culled collision queries (the default) or each with a full
    ``robot.in_collision``: the same verdicts, so the same path, check count and states."""
    from robodesign.solvers import planning
    culled = plan_path(robot, QA, QB, time_limit=5.0, seed=3)
    monkeypatch.setattr(planning._Memoized, "culler", lambda self: None)
    full = plan_path(robot, QA, QB, time_limit=5.0, seed=3)
    assert culled.success and np.array_equal(culled.path, full.path)
    for k in ("checks", "lookups", "distinct_states", "raw_waypoints"):
        assert culled.stats[k] == full.stats[k]


def test_same_seed_same_path(robot):
    a = plan_path(robot, QA, QB, seed=7, time_limit=5.0)
    b = plan_path(robot, QA, QB, seed=7, time_limit=5.0)
    assert a.success and b.success
    assert np.array_equal(a.path, b.path)


@pytest.mark.parametrize("planner", ["bitstar", "prm"])
def test_other_planners(robot, planner):
    res = plan_path(robot, QA, QB, planner=planner, time_limit=5.0, seed=0)
    assert res.success and res.stats["planner"] == planner
    assert np.array_equal(res.path[0], QA) and np.array_equal(res.path[-1], QB)
    assert dense_ok(robot, res.path, 0.005)


def test_straight_line_first(robot):
    q1 = QA + np.array([0.0, 0.0, 0.0, 0.0, 0.2, 0.0])
    res = plan_path(robot, QA, q1)
    assert res.success and res.stats["straight_line"] and res.stats["reason"] == "straight_line"
    assert np.array_equal(res.path, np.array([QA, q1]))
    same = plan_path(robot, QA, QA)
    assert same.success and np.array_equal(same.path, np.array([QA, QA]))


def test_invalid_requests(robot):
    with pytest.raises(InputError) as e:
        plan_path(robot, QA, QB, planner="nosuchplanner")
    assert "rrtconnect" in str(e.value) and "bitstar" in str(e.value)
    assert "rrtconnect" in available_planners() and "ait*" not in available_planners()
    with pytest.raises(InputError):
        plan_path(robot, QA[:3], QB)
    mid = 0.5 * (QA + QB)                      # colliding start / goal: a clean failure, no exception
    res = plan_path(robot, mid, QB)
    assert not res.success and res.stats["reason"] == "invalid_start" and res.path.shape == (0, robot.dof)
    res = plan_path(robot, QA, mid)
    assert not res.success and res.stats["reason"] == "invalid_goal"
    outside = QA.copy()
    outside[0] = robot.q_upper[0] + 0.1
    assert not plan_path(robot, outside, QB).success


def test_check_path_reports_the_first_bad_segment(robot):
    mid = 0.5 * (QA + QB)
    q1 = QA + np.array([0.0, 0.0, 0.0, 0.0, 0.2, 0.0])
    assert check_path(robot, np.array([q1, QA]), 0.01) == (True, -1)
    assert check_path(robot, np.array([q1, QA, QB]), 0.01) == (False, 1)     # segment QA→QB hits the box
    assert check_path(robot, np.array([q1, QA, mid]), 5.0) == (False, 2)     # the waypoint itself collides
    assert check_path(robot, np.array([mid, QA]), 0.01) == (False, 0)
    assert check_path(robot, np.zeros((0, robot.dof)), 0.01) == (True, -1)


# a long built-in arm (two 0.5 m links, Panda joint limits 87 / 12 Nm): folded up it holds itself, stretched
# out sideways it needs 1.9 × the shoulder's torque (checked below with the RNEA gravity torque)
HEAVY_ORDER = "1,21,22,7,22,7,22,3,23,24,23,12".split(",")
FOLD_A = np.array([0.0, -1.2, 2.4, 0.0, 0.0, 0.0, 0.0])    # elbow folded one way
FOLD_B = np.array([0.0, -1.2, -2.4, 0.0, 0.0, 0.0, 0.0])   # ... and the other: the straight line stretches the arm


def test_static_torque_planning_avoids_configurations_the_joints_cannot_hold():
    """The straight line between two held configurations is collision-free but passes poses whose gravity
    torque exceeds the joints' limits (time scaling cannot repair that: slowing down leaves gravity);
    ``static_torque=True`` plans around them, and every state of the result (independent dense check) is
    held within the limits."""
    from robodesign.solvers.timing import TimingError, time_parameterize
    r = Robot.from_order(load_module_set("robodesign_arm"), HEAVY_ORDER)
    tau_max = np.asarray(r.tau_max)
    ratio = lambda q: float(np.max(np.abs(r.gravity_torque(q)) / tau_max))
    assert ratio(FOLD_A) < 1 and ratio(FOLD_B) < 1
    line = np.linspace(FOLD_A, FOLD_B, 201)
    assert max(ratio(q) for q in line) == pytest.approx(1.91, abs=0.02)   # stretched sideways at the middle
    assert check_path(r, np.array([FOLD_A, FOLD_B]), 0.01) == (True, -1)   # collision-free
    assert check_path(r, np.array([FOLD_A, FOLD_B]), 0.01, static_torque=True) == (False, 0)
    with pytest.raises(TimingError, match="gravity alone exceeds"):
        time_parameterize(r, np.array([FOLD_A, FOLD_B]), dt=0.01)

    plain = plan_path(r, FOLD_A, FOLD_B, time_limit=5.0, seed=0)
    assert plain.stats["straight_line"] and len(plain.path) == 2            # the old behaviour
    res = plan_path(r, FOLD_A, FOLD_B, time_limit=5.0, seed=0, static_torque=True)
    assert res.success and res.stats["reason"] == "planned"
    np.testing.assert_array_equal(res.path[0], FOLD_A)
    np.testing.assert_array_equal(res.path[-1], FOLD_B)
    worst = 0.0
    for a, b in zip(res.path[:-1], res.path[1:]):
        n = max(1, math.ceil(np.max(np.abs(b - a)) / 0.005))
        worst = max(worst, max(ratio(a + (b - a) * (k / n)) for k in range(n + 1)))
    assert worst <= 1.0 and dense_ok(r, res.path, 0.005)
    traj = time_parameterize(r, res.path, dt=0.01)                          # and it can be timed
    np.testing.assert_allclose(traj.q[-1], FOLD_B, atol=1e-9)


def test_a_busy_machine_plans_the_same_path(robot, monkeypatch):
    """The planner's limit is a count of validity checks, not seconds: making every check 40x slower (as a
    loaded machine does) leaves the path and the check count unchanged, although the slowed solve takes far
    longer than its nominal time limit."""
    import time as _time

    from robodesign.solvers import planning
    quick = plan_path(robot, QA, QB, time_limit=0.5, seed=3)
    assert quick.success and quick.stats["reason"] == "planned"
    real = planning.static_validator

    def wait(rows: int) -> None:
        t = _time.perf_counter()
        while _time.perf_counter() - t < 2e-4 * rows:   # busy-wait: ~40x the cost of a check, per state
            pass

    def slowed_validator(*args):   # every state's test slowed, one at a time or a motion's states at once
        ok = real(*args)

        def slow(q):
            wait(1)
            return ok(q)

        def slow_rows(Q):
            wait(len(Q))
            return ok.rows(Q)
        slow.rows = slow_rows
        return slow
    monkeypatch.setattr(planning, "static_validator", slowed_validator)
    slowed = plan_path(robot, QA, QB, time_limit=0.5, seed=3)
    assert slowed.success and slowed.stats["checks"] == quick.stats["checks"]
    assert np.array_equal(slowed.path, quick.path)
    assert slowed.stats["plan_time"] > quick.stats["plan_time"]
    assert planning.CHECKS_PER_SECOND * 0.5 > quick.stats["checks"]   # it stopped on a solution, not the budget


def test_the_work_budget_stops_a_planner_that_cannot_succeed(robot, monkeypatch):
    """A query with no solution (the goal region walled off) spends exactly its check budget in OMPL."""
    from robodesign.solvers import planning
    monkeypatch.setattr(planning, "CHECKS_PER_SECOND", 2000)
    real = planning.static_validator
    wall = 0.5 * (QA[0] + QB[0])
    asked = []

    def walled_validator(*args):   # a wall across joint 0 halfway between the two configurations, for every
        ok = real(*args)           # state: one at a time or a motion's states at once

        def walled(q):
            asked.append(1)
            return ok(q) and bool(abs(q[0] - wall) >= 0.05)

        def walled_rows(Q):
            asked.append(len(Q))
            return ok.rows(Q) & (np.abs(Q[:, 0] - wall) >= 0.05)
        walled.rows = walled_rows
        return walled
    monkeypatch.setattr(planning, "static_validator", walled_validator)
    monkeypatch.setattr(planning, "CHECKS_PER_SECOND", 100_000)   # a budget that plans around the box alone
    assert plan_path(robot, QA, QB, time_limit=0.25, seed=0, resolution=0.02).stats["reason"] == "no_solution"
    monkeypatch.setattr(planning, "static_validator", real)
    assert plan_path(robot, QA, QB, time_limit=0.25, seed=0, resolution=0.02).success   # (the wall is the obstacle)
    monkeypatch.setattr(planning, "static_validator", walled_validator)
    monkeypatch.setattr(planning, "CHECKS_PER_SECOND", 2000)
    res = plan_path(robot, QA, QB, time_limit=0.25, seed=0)
    assert not res.success and res.stats["reason"] == "no_solution" and sum(asked) > 500
    assert 500 <= res.stats["checks"] <= 500 + 2 + 2000   # 0.25 s x 2000 checks/s, plus the straight-line checks


def test_any_of_several_goal_configurations(robot):
    """``other_goals``: the planner's goal tree grows from every valid goal configuration at once and the path
    ends exactly at the one it reached; a goal in collision is skipped (here the requested one: the midpoint,
    inside the box), and with no valid goal the request fails as 'invalid_goal'."""
    mid = 0.5 * (QA + QB)
    res = plan_path(robot, QA, mid, time_limit=5.0, seed=1, other_goals=[mid + 1e-3, QB])
    assert res.success and res.stats["goal"] == 2 and np.array_equal(res.path[-1], QB)
    assert np.array_equal(res.path[0], QA) and dense_ok(robot, res.path, 0.005)
    # the requested goal, when reachable in a straight line, is taken directly
    q1 = QA + np.array([0.05, 0, 0, 0, 0, 0])
    res = plan_path(robot, QA, q1, other_goals=[QB])
    assert res.success and res.stats["straight_line"] and res.stats["goal"] == 0 and np.array_equal(res.path[-1], q1)
    # no valid goal at all
    res = plan_path(robot, QA, mid, other_goals=[mid + 1e-3])
    assert not res.success and res.stats["reason"] == "invalid_goal"
    with pytest.raises(InputError):
        plan_path(robot, QA, QB, other_goals=[QB[:3]])


def test_planned_states_leave_room_for_friction_away_from_the_rests():
    """A state the robot moves through needs |g(q)| + f_c ≤ τ_max: Coulomb friction adds f_c however slowly it
    moves, so a path through poses held with less headroom cannot be timed (the timing gives up: "slowing down
    does not bring the torque within the limit"). The shoulder swung through its largest gravity torque with the
    elbow set so that the peak is 85 Nm (limit 87, friction 5), the way friction adds to it: the straight line
    holds still everywhere but cannot be timed; the planner (whose test does not ask the direction) goes around, its states beyond REST_RADIUS from start and goal keep the
    headroom (independent dense check), and the path can be timed."""
    from robodesign.solvers.planning import REST_RADIUS
    from robodesign.solvers.timing import TimingError, time_parameterize
    r = Robot.from_order(load_module_set("robodesign_arm"), HEAVY_ORDER)
    tau, fc = np.asarray(r.tau_max), np.asarray(r.friction_coulomb)
    assert tau[1] == 87.0 and fc[1] == 5.0

    def q(sh, el):
        return np.array([0.0, sh, el, 0.0, 0.0, 0.0, 0.0])

    shoulders = np.linspace(0.0, 1.5, 301)

    def peak(el):
        g = [abs(r.gravity_torque(q(s, el))[1]) for s in shoulders]
        return max(g), shoulders[int(np.argmax(g))]

    lo, hi = 2.1, 2.2  # peak 87.8 and 80.5 Nm (by the scan above): bisect to 85 Nm
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if peak(mid)[0] > 85.0 else (lo, mid)
    el = 0.5 * (lo + hi)
    g_peak, s_peak = peak(el)
    assert g_peak == pytest.approx(85.0, abs=0.01)
    A, B = q(s_peak - 0.6, el), q(s_peak + 0.6, el)
    if r.gravity_torque(q(s_peak, el))[1] < 0:  # move the way friction adds to the holding torque: τ = g + f_c·σ(q̇)
        A, B = B, A
    headroom = lambda x: np.all(np.abs(r.gravity_torque(x)) + fc <= tau)
    assert headroom(A) and headroom(B)
    assert check_path(r, np.array([A, B]), 0.01, static_torque=True) == (True, -1)  # held standing still
    with pytest.raises(TimingError, match="slowing down does not bring the torque"):
        time_parameterize(r, np.array([A, B]), dt=0.01)

    res = plan_path(r, A, B, time_limit=5.0, seed=0, static_torque=True)
    assert res.success and not res.stats["straight_line"], res.stats
    for a, b in zip(res.path[:-1], res.path[1:]):
        n = max(1, math.ceil(np.max(np.abs(b - a)) / 0.005))
        for k in range(n + 1):
            x = a + (b - a) * (k / n)
            if min(np.max(np.abs(x - A)), np.max(np.abs(x - B))) > REST_RADIUS + 0.01:
                assert headroom(x), x
    traj = time_parameterize(r, res.path, dt=0.01)
    np.testing.assert_allclose(traj.q[-1], B, atol=1e-9)


def test_the_batched_static_test_gives_each_state_its_own_verdict():
    """``rows`` of the static validator (the gravity torques of a segment's states in one RNEA call) answers
    exactly as the one-state test (pinocchio's computeGeneralizedGravity per state) on every state: on a heavy
    arm swung through poses it holds, poses it cannot hold, and poses near and far from the rests, with and
    without the rest condition; and the torques themselves are those of computeGeneralizedGravity bit for bit
    (up to the sign of a zero)."""
    import pinocchio as pin

    from robodesign.model.rnea_batch import rnea_rows
    from robodesign.solvers.static_validity import static_validator
    r = Robot.from_order(load_module_set("robodesign_arm"), HEAVY_ORDER)
    rng = np.random.default_rng(2)
    Q = np.vstack([np.linspace(FOLD_A, FOLD_B, 201), rng.uniform(r.q_lower, r.q_upper, (400, r.dof)),
                   FOLD_A + rng.normal(0, 0.05, (100, r.dof))])
    Z = np.zeros_like(Q)
    exact = np.array([pin.computeGeneralizedGravity(r.model, r.data, q).copy() for q in Q])
    assert np.array_equal(np.abs(rnea_rows(r.model, Q, Z, Z)), np.abs(exact))
    verdicts = []
    for rest in ((), (FOLD_A, FOLD_B)):
        ok = static_validator(r, True, rest)
        each = np.array([ok(q) for q in Q])
        assert np.array_equal(ok.rows(Q), each)
        assert 50 < each.sum() < len(Q) - 50   # both verdicts, many times
        verdicts.append(each)
    # states held standing still but without room for friction: out only away from the rests
    assert (verdicts[0] & ~verdicts[1]).sum() >= 5
