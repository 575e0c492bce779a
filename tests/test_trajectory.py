"""One trajectory type (issue 23): the solvers' motions and the solution files' trajectories are the same
class, ``robodesign.core.trajectory.Trajectory``; goal times travel with its time operations."""
from __future__ import annotations

import numpy as np
import pytest

from robodesign.core.trajectory import Trajectory
from robodesign.formats import solution as solution_mod
from robodesign.formats.solution import parse_solution
from robodesign.solvers import timing


def _ramp() -> Trajectory:
    """q = t² on [0, 0.3] for one joint, exactly integrated with ddq = 2: samples every 0.1 s."""
    t = np.array([0.0, 0.1, 0.2, 0.3])
    return Trajectory(t, t ** 2, 2 * t, np.full(4, 2.0), {"g1": 0.2})


def test_old_names_are_the_one_type() -> None:
    assert timing.JointTrajectory is Trajectory
    assert solution_mod.SolutionTrajectory is Trajectory


def test_a_parsed_solution_trajectory_is_the_solver_type() -> None:
    data = {"taskID": "x", "costFunction": "cyc", "moduleSet": "IMPROV", "moduleOrder": ["1"],
            "basePose": [np.eye(4).tolist()],
            "trajectory": {"t": 0.1, "q": [[0.0], [0.01], [0.04]], "goal2time": {"g": 0.1}}}
    tr = parse_solution(data, "sol.json").trajectory
    assert type(tr) is Trajectory
    assert tr.n == 3 and tr.dof == 1 and tr.goal2time == {"g": 0.1}
    np.testing.assert_allclose(tr.t, [0.0, 0.1, 0.2])
    # numpy.gradient fills dq: (0.01 - 0) / 0.1, central difference (0.04 - 0) / 0.2, (0.04 - 0.01) / 0.1
    np.testing.assert_allclose(tr.dq[:, 0], [0.1, 0.2, 0.3])
    # the solver's methods work on a file's trajectory: q(0.15) on the piecewise-quadratic rule from sample 1
    q, dq, ddq = tr.interpolate(0.15)
    assert q[0, 0] == pytest.approx(0.01 + 0.2 * 0.05 + 0.5 * tr.ddq[1, 0] * 0.05 ** 2)


def test_goal_times_follow_shift_slice_and_concatenation() -> None:
    tr = _ramp()
    assert tr.shifted(1.0).goal2time == {"g1": pytest.approx(1.2)}
    assert tr.slice(0, 1).goal2time == {}  # 0.2 s lies outside samples 0..1
    assert tr.slice(1, 3).goal2time == {"g1": pytest.approx(0.2)}
    rest = Trajectory(np.array([0.0, 0.1]), np.zeros(2), np.zeros(2), np.zeros(2), {"g2": 0.1})
    start = Trajectory.at_rest([0.0])
    both = rest.concatenate(Trajectory(np.array([5.0, 5.1]), np.zeros(2), np.zeros(2), np.zeros(2), {"g3": 5.1}))
    assert both.goal2time == {"g2": pytest.approx(0.1), "g3": pytest.approx(0.2)}
    np.testing.assert_allclose(both.t, [0.0, 0.1, 0.2])
    held = start.hold(0.25, dt=0.1)
    assert held.n == 4 and held.duration == pytest.approx(0.3)
    assert held.copy().goal2time is not held.goal2time


def test_the_integration_rule_residual() -> None:
    assert max(_ramp().consistency_residual()) < 1e-12
    bad = _ramp()
    bad.q[2] += 1e-3
    rq, rv = bad.consistency_residual()
    assert rq == pytest.approx(1e-3) and rv < 1e-12


def test_times_must_increase() -> None:
    with pytest.raises(ValueError, match="strictly increasing"):
        Trajectory(np.array([0.0, 0.0]), np.zeros(2), np.zeros(2), np.zeros(2))
