"""solvers/ompl_motion.py: OMPL's discrete motion check one motion at a time. Its states are OMPL's own (order by
hand, interpolation bit for bit against OMPL's), and the planner asks the same states in the same order with it
as with OMPL's validator: on the real PTP_3 cell (IMPROV arm, CNC-machine mesh), queries that succeed and queries
that spend their whole work limit give the same paths, counts and verdicts."""
import numpy as np
import pytest
from conftest import IMPROV, TASKS
from ompl import base as ob

from robodesign.formats.assembly import Assembly
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.model.cell import build_robot
from robodesign.solvers import planning
from robodesign.solvers.ompl_motion import bisection_order, motion_states
from robodesign.solvers.schedule import static_cell

GOOD = ("1", "21", "4", "22", "5", "23", "12")


def test_bisection_order_by_hand():
    assert bisection_order(0) == [] and bisection_order(1) == [] and bisection_order(2) == [1]
    assert bisection_order(3) == [1, 2]                  # [1, 2]: middle 1, then [2, 2]
    assert bisection_order(5) == [2, 1, 3, 4]            # [1, 4]: 2; [1, 1]: 1, [3, 4]: 3; [4, 4]: 4
    assert bisection_order(8) == [4, 2, 6, 1, 3, 5, 7]   # [1, 7]: 4; [1, 3]: 2, [5, 7]: 6; then 1, 3, 5, 7
    for nd in range(2, 60):
        assert sorted(bisection_order(nd)) == list(range(1, nd))


def test_segment_states_are_the_per_state_formula_bit_for_bit(monkeypatch):
    """planning._segment_ok builds a segment's states at once: the same floats as a + d·(k/n) one at a time."""
    rng = np.random.default_rng(8)
    seen = []
    monkeypatch.setattr(planning._Memoized, "first_invalid", lambda self, Q, counter=None, gate=None: seen.append(Q) or -1)
    memo = planning._Memoized(lambda q: True)
    for trial in range(40):
        a, b = rng.uniform(-3, 3, 6), rng.uniform(-3, 3, 6)
        start = bool(trial % 2)
        assert planning._segment_ok(memo, a, b, 0.013, include_start=start)
        d = b - a
        n = max(1, int(np.ceil(float(np.max(np.abs(d))) / 0.013 - 1e-12)))
        want = ([a] if start else []) + [b] + [a + d * (k / n) for k in planning._bisection_order(n)]
        assert np.array_equal(seen[-1], np.array(want))


def test_states_equal_ompl_interpolation_bit_for_bit():
    n = 7
    space = ob.RealVectorStateSpace(n)
    bounds = ob.RealVectorBounds(n)
    bounds.setLow(-4.0)
    bounds.setHigh(4.0)
    space.setBounds(bounds)
    s1, s2, out = space.allocState(), space.allocState(), space.allocState()
    rng = np.random.default_rng(3)
    for trial in range(60):
        a, b = rng.uniform(-4, 4, n), rng.uniform(-4, 4, n)
        for i in range(n):
            s1[i], s2[i] = float(a[i]), float(b[i])
        nd = int(rng.integers(2, 90))
        order = bisection_order(nd)
        Q = motion_states(a, b, nd, order)
        assert np.array_equal(Q[0], b)
        for row, j in zip(Q[1:], order):
            space.interpolate(s1, s2, j / nd, out)
            assert np.array_equal(row, [out[i] for i in range(n)])


def test_the_remembered_fractions_are_the_orders_divided():
    """The validator's fractions, remembered per segment count across planning calls, are bisection_order(nd) / nd
    bit for bit (what motion_states interpolates at), read-only, and give motion_states' states."""
    from robodesign.solvers.ompl_motion import _fractions, _interpolated
    rng = np.random.default_rng(8)
    for nd in list(range(1, 700)) + [1500, 4000]:
        want = np.array(bisection_order(nd), dtype=float) / float(nd)
        got = _fractions(nd)
        assert got.tobytes() == want.tobytes() and not got.flags.writeable and _fractions(nd) is got
        a, b = rng.uniform(-4, 4, 7), rng.uniform(-4, 4, 7)
        assert _interpolated(a, b, got).tobytes() == motion_states(a, b, nd, bisection_order(nd)).tobytes()


@pytest.fixture(scope="module")
def queries():
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    robot = build_robot(static_cell(task), ms, Assembly.from_order(ms, GOOD), task.nominal_base_pose)
    rng = np.random.default_rng(4)
    free = [q for q in (robot.random_configuration(rng) for _ in range(240)) if not robot.in_collision(q)]
    pairs = [(a, b) for a, b in zip(free[::2], free[1::2]) if robot.in_collision(0.5 * (a + b))]  # blocked lines
    assert len(pairs) >= 6
    return robot, pairs[:6]


def _plan(robot, a, b, seed, limit, monkeypatch, batched: bool):
    asked, made = [], []
    real, real_mv = planning._Memoized.__init__, planning.motion_validator

    def keep(self, valid, robot=None):   # the planner's memo, to read which states it decided, in order
        real(self, valid, robot)
        asked.append(self)
    with monkeypatch.context() as m:
        m.setattr(planning._Memoized, "__init__", keep)
        m.setattr(planning, "motion_validator", lambda *a: made.append(1) or real_mv(*a))
        if not batched:
            m.setattr(planning, "PLANNERS_TWO_STATE", frozenset())
        r = planning.plan_path(robot, a, b, time_limit=limit, seed=seed, static_torque=True)
    assert len(made) == (batched and r.stats["plan_time"] > 0)   # OMPL ran, with the batched validator or not
    return r, list(asked[0].memo.items())


@pytest.mark.parametrize("limit", [0.5, 0.004])
def test_the_planner_asks_the_same_states_with_the_batched_validator(queries, monkeypatch, limit):
    """0.5 s: some queries are solved, others spend the work limit (4,000 checks); 0.004 s (32 checks): the work
    limit ends every search, mid-motion."""
    robot, pairs = queries
    reasons = set()
    for i, (a, b) in enumerate(pairs):
        ref, ref_states = _plan(robot, a, b, i, limit, monkeypatch, batched=False)
        got, got_states = _plan(robot, a, b, i, limit, monkeypatch, batched=True)
        assert got_states == ref_states                  # the same states decided, in the same order, same verdicts
        assert np.array_equal(got.path, ref.path)
        for k in ("reason", "checks", "lookups", "distinct_states", "raw_waypoints", "goal"):
            assert got.stats[k] == ref.stats[k], k
        reasons.add(ref.stats["reason"])
    assert reasons == ({"planned", "no_solution"} if limit > 0.1 else {"no_solution"})   # (both kinds at 0.5 s)
