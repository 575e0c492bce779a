"""Whole turns of revolute joints: robodesign_heavy's joints turn ±2π (two sheets of every pose), and the IK
stage keeps every solution in the sheet nearest 0 (Robot.nearest_equivalent), so a goal's solutions and the
next goal's lie in one piece of free space; the plan stage's fallback also offers the other sheets of a joint
(Robot.turn_variants). docs/diagnosis.md, "Whole turns"."""
from __future__ import annotations

import math

import numpy as np

from robodesign import Robot, load_module_set
from robodesign.formats.tolerance import ToleratedPose
from robodesign.solvers.ik import solve_ik

ORDER = "1,21,22,8,24,12,25,26,25,16".split(",")  # robodesign_heavy's example B: six revolute joints, ±2π
TWO_PI = 2 * math.pi


def heavy_robot() -> Robot:
    return Robot.from_order(load_module_set("robodesign_heavy"), ORDER)


def test_nearest_equivalent_turns_each_joint_by_whole_turns_towards_zero_within_the_limits():
    r = heavy_robot()
    assert np.allclose(r.q_lower, -TWO_PI) and np.allclose(r.q_upper, TWO_PI)
    q = np.array([4.0, -4.0, 0.5, 6.0, -6.2, 3.0])
    # by hand: 4 − 2π, −4 + 2π, 0.5 stays, 6 − 2π, −6.2 + 2π, 3.0 < π stays
    want = np.array([4.0 - TWO_PI, -4.0 + TWO_PI, 0.5, 6.0 - TWO_PI, -6.2 + TWO_PI, 3.0])
    got = r.nearest_equivalent(q)
    assert np.allclose(got, want, atol=1e-15)
    assert np.allclose(r.fk(got), r.fk(q), atol=1e-12)  # the same pose
    # towards another reference: joint 0 near 4 stays at 4, joint 1 near −4 stays at −4
    near = np.array([5.0, -5.0, 0.0, 0.0, 0.0, 0.0])
    assert np.allclose(r.nearest_equivalent(q, near)[:2], [4.0, -4.0])
    # a limit the nearest turn would leave: limits [−1, 6] on joint 0, q0 = 5.0 → 5 − 2π = −1.28 < −1: stays
    r.q_lower = r.q_lower.copy()
    r.q_lower[0] = -1.0
    assert r.nearest_equivalent(np.array([5.0, 0, 0, 0, 0, 0]))[0] == 5.0
    assert math.isclose(r.nearest_equivalent(np.array([5.5, 0, 0, 0, 0, 0]))[0], 5.5 - TWO_PI)


def test_turn_variants_are_the_same_pose_with_one_joint_turned_once():
    r = heavy_robot()
    q = np.array([0.3, -0.2, 1.0, 4.0, -0.5, 0.0])
    vs = r.turn_variants(q)
    # within ±2π a joint at q ≠ 0 turns one way only (0.3 − 2π, −0.2 + 2π, 1 − 2π, 4 − 2π, −0.5 + 2π), a joint
    # at exactly 0 both ways (the limits themselves): 5 + 2 = 7 variants
    assert len(vs) == 7
    for v in vs:
        d = v - q
        assert np.count_nonzero(d) == 1 and math.isclose(abs(d[np.nonzero(d)[0][0]]), TWO_PI)
        assert np.allclose(r.fk(v), r.fk(q), atol=1e-12)


def test_ik_solutions_lie_in_one_sheet():
    """Without the rule the restarts (uniform in ±2π) land in either sheet of each joint; with it every
    solution's joints lie in [−π, π] (the sheet nearest 0), and solutions that differ by whole turns only are
    one solution."""
    r = heavy_robot()
    q_ref = np.array([0.4, -0.7, 1.1, 0.3, 0.8, -0.2])
    goal = ToleratedPose(r.fk(q_ref))  # the default tolerance: ±1 mm, 0.5°
    raw = solve_ik(r, goal, rng=3, n_solutions=12, canonical=False)
    one = solve_ik(r, goal, rng=3, n_solutions=12)
    assert raw and one
    assert any(np.any(np.abs(q) > math.pi) for q in raw.solutions)  # the rule has something to do
    for q in one.solutions:
        assert np.all(np.abs(q) <= math.pi + 1e-9), q
        assert goal.valid(r.fk(q))
    # pairwise distinct modulo whole turns
    for i, a in enumerate(one.solutions):
        for b in one.solutions[i + 1:]:
            d = (a - b + math.pi) % TWO_PI - math.pi
            assert np.linalg.norm(d) > 1e-3
