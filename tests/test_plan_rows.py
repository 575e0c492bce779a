"""solvers/planning.py, ``_Memoized.first_invalid``: the states of a block decided together (bounds, certificates,
torque tests at once; only the states that can be invalid visited one by one, a work limit's gate asked only where
its ``room()`` ends) give what asking ``valid(q)`` state by state gives: the first invalid row, the counter, the
lookups, the gate's refusal, and the verdicts remembered in the same order. Random IMPROV arms in the PTP_3 cell
and built-in arms among random boxes, segments with and without collisions, memos holding earlier verdicts (valid
and invalid), repeated states, work limits that end a segment midway; seeded."""
import numpy as np
import pytest
from conftest import IMPROV, ROOT, TASKS, boxes_around

from robodesign.design.problem import Problem
from robodesign.formats.assembly import Assembly
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.model.cell import build_robot
from robodesign.model.robot import Robot
from robodesign.solvers import planning
from robodesign.solvers.schedule import static_cell

BUILTIN = ROOT / "assets" / "modules" / "robodesign_arm"


@pytest.fixture(scope="module")
def robots():
    """Five random IMPROV arms of the PTP_3 search space (seed 3) in its cell, and three random built-in arms among
    boxes."""
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    space = Problem.build(TASKS / "simple" / "PTP_3.json", IMPROV, "cyc").space
    rng = np.random.default_rng(3)
    orders = [space.random_order(rng) for _ in range(4)] + [("1", "21", "4", "22", "5", "23", "12")]
    out = [build_robot(static_cell(task), ms, Assembly.from_order(ms, o), task.nominal_base_pose) for o in orders]
    builtin = Problem.build(TASKS / "simple" / "PTP_3.json", BUILTIN, "cyc").space
    for i in range(3):
        r = Robot.from_order(load_module_set(BUILTIN), list(builtin.random_order(rng)))
        r.set_obstacles(boxes_around(r, 40 + i, n=6))
        out.append(r)
    return out


def _segment(robot, rng) -> np.ndarray:
    """A straight segment's states in bisection order (as the planner asks them), sometimes a state repeated."""
    a = robot.random_configuration(rng)
    b = a + rng.normal(0.0, rng.choice([0.1, 0.5, 1.2]), robot.dof)
    n = max(2, int(np.ceil(np.max(np.abs(b - a)) / 0.01)))
    Q = np.vstack([b[None, :], a + (b - a) * (np.array(planning._bisection_order(n), dtype=float) / n)[:, None]])
    if rng.random() < 0.2:
        Q = np.vstack([Q[:5], Q[2:3], Q[5:]])
    return Q


class _Gate:
    """A work limit as the planner's: a counted state passes while the counter is below ``budget`` (``room()``:
    how many more pass); ``refused``: the calls that said False."""

    def __init__(self, counter, budget: int):
        self.counter, self.budget, self.refused = counter, budget, 0

    def __call__(self) -> bool:
        self.refused += self.counter[0] >= self.budget
        return self.counter[0] < self.budget

    def room(self) -> int:
        return self.budget - self.counter[0] - 1


@pytest.mark.parametrize("gated", [False, True])
def test_block_verdicts_are_the_state_by_state_ones(robots, gated):
    rng = np.random.default_rng(21 + gated)
    invalid = visited = 0
    for robot in robots:
        rest = [robot.random_configuration(rng) for _ in range(2)]
        fast = planning._Memoized(planning._config_validator(robot, True, rest), robot)
        plain = planning._Memoized(planning._config_validator(robot, True, rest))   # no robot: state by state
        assert fast.culler() is not None and plain.culler() is None
        segments = [_segment(robot, rng) for _ in range(14)]
        for k in range(24):
            Q = segments[int(rng.integers(len(segments)))]   # (segments asked again: memo hits, valid and invalid)
            if rng.random() < 0.3:
                Q = Q[int(rng.integers(len(Q))):]
            budget = int(rng.integers(1, 2 * len(Q))) if gated else 0
            got, want = [0], [0]
            gates = (_Gate(got, budget), _Gate(want, budget)) if gated else (None, None)
            i = fast.first_invalid(Q, got, gates[0])
            j = plain.first_invalid(Q, want, gates[1])
            assert i == j
            if gated:   # the work limit's stop asked (and only it)
                assert gates[0].refused == gates[1].refused <= 1
            assert got == want and fast.lookups == plain.lookups
            assert list(fast.memo.items()) == list(plain.memo.items())   # the same verdicts, remembered in order
            invalid += i >= 0
            visited += 1
    assert 0.2 * visited < invalid < 0.9 * visited   # segments that pass and that fail


def test_row_keys_are_each_rows_bytes():
    """``planning._row_keys`` gives ``q.tobytes()`` of every row (the keys ``_Memoized.__call__`` remembers):
    random rows of 1–9 columns with zeros, −0.0, NaN, infinities, subnormals and rows ending in zero bytes, also
    strided and transposed views and empty blocks; seeded."""
    rng = np.random.default_rng(25)
    specials = np.array([0.0, -0.0, np.nan, np.inf, -np.inf, 5e-324, 1.0, 2.0, -1.5])
    for _ in range(300):
        n, d = int(rng.integers(0, 40)), int(rng.integers(1, 10))
        Q = rng.normal(size=(n, d)) * 10.0 ** rng.integers(-8, 8)
        mask = rng.random((n, d)) < 0.3
        Q[mask] = rng.choice(specials, size=int(mask.sum()))
        for rows in (Q, Q[::2], np.asfortranarray(Q), Q.T.copy().T):
            keys = planning._row_keys(rows)
            assert keys == [q.tobytes() for q in rows]
            assert all(type(k) is bytes and len(k) == 8 * d for k in keys)
