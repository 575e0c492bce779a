"""solvers.timing.sample_torques, which runs the 'before' RNEA only at the samples where q̈ changes, against the
former formula (both one-sided accelerations at every sample): the same numbers
byte for byte on random robots and trajectories with runs of equal accelerations, zeros of either sign, inf and
NaN (issue 25)."""
from __future__ import annotations

import numpy as np
from test_arc_torques import robots  # noqa: F401  (the fixture: IMPROV, based IMPROV, primitives, reversed)

from robodesign.core.trajectory import Trajectory
from robodesign.solvers import timing


def _former(robot, traj):
    """sample_torques as it was: Robot.drivetrain_torques with each one-sided acceleration at every sample."""
    after = robot.drivetrain_torques(traj.q, traj.dq, traj.ddq)
    if len(traj.t) < 2:
        return np.abs(after)
    before = robot.drivetrain_torques(traj.q, traj.dq, np.vstack([traj.ddq[:1], traj.ddq[:-1]]))
    return np.maximum(np.abs(after), np.abs(before))


def _trajectory(rng, n, dof):
    """n samples whose accelerations come in runs (equal rows), with zeros of both signs and a few inf and NaN."""
    q, dq = rng.uniform(-3, 3, (n, dof)), rng.uniform(-2, 2, (n, dof))
    ddq = rng.uniform(-9, 9, (n, dof))
    for k in range(1, n):
        if rng.uniform() < 0.5:
            ddq[k] = ddq[k - 1]
    zero = rng.uniform(size=(n, dof)) < 0.15
    ddq[zero] = np.where(rng.uniform(size=zero.sum()) < 0.5, 0.0, -0.0)
    odd = rng.uniform(size=(n, dof))
    ddq[odd < 0.01] = np.nan
    ddq[(odd >= 0.01) & (odd < 0.02)] = np.inf
    dq[rng.uniform(size=(n, dof)) < 0.1] = -0.0
    return Trajectory(0.01 * np.arange(n), q, dq, ddq)


def test_sample_torques_equal_the_former_formula(robots):  # noqa: F811
    rng = np.random.default_rng(41)
    for r in robots:
        for n in (1, 2, 3, 17, 120):
            for _ in range(4):
                tr = _trajectory(rng, n, r.dof)
                with np.errstate(invalid="ignore", over="ignore"):
                    new, old = timing.sample_torques(r, tr), _former(r, tr)
                assert new.tobytes() == old.tobytes(), (r.dof, n)


def test_sample_torques_on_a_timed_motion(robots):  # noqa: F811
    """On time_parameterize's own samples (rest, cruise and switch samples) as well."""
    path = np.array([[0.0, 0.3, -0.5, 0.2, 0.1, 0.0, 0.0], [1.0, -0.4, 0.6, -0.8, 0.5, 0.3, 0.2],
                     [-0.5, 0.2, 0.9, 0.4, -0.6, 0.1, -0.3]])
    for r in robots:
        tr = timing.time_parameterize(r, path[:, :r.dof], dt=0.01)
        assert timing.sample_torques(r, tr).tobytes() == _former(r, tr).tobytes()
