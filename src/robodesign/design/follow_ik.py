"""The configurations of a follow goal's poses (the ik stage, :meth:`GoalPlanner.follow_chain
<robodesign.design.goal_planner.GoalPlanner.follow_chain>`) and the timed motion through them.

A follow with given times moves between consecutive poses in exactly those times (:func:`timed_follow`: quintic
rest-to-rest moves), so each pose's configuration must lie within what the joints' speed and acceleration limits
let them move from the one before in its time (:func:`follow_steps`). A chain whose next pose has no such
configuration starts again from another configuration of the first pose."""
from __future__ import annotations

import math
from typing import List, Optional, Sequence, Tuple

import numpy as np

from robodesign.core.trajectory import Trajectory

#: how many configurations of a timed follow's first pose follow_chain starts a chain from
FOLLOW_TRIES = 8
#: the share of the joints' speed and acceleration limits a timed follow's quintic moves may use at their peaks
#: (the judge checks the samples and the motion between them: a little room for the difference)
_FOLLOW_LIMIT_SHARE = 0.9


def follow_steps(robot, t_rel: np.ndarray, dt: float) -> np.ndarray:
    """Per move of a timed follow (row k: from pose k to pose k + 1) and joint, the largest |Δq| whose quintic
    rest-to-rest move (:func:`timed_follow`) stays within :data:`_FOLLOW_LIMIT_SHARE` of the joint's speed and
    acceleration limits: its peak speed is 15/8·|Δq|/T, its peak acceleration 10/√3·|Δq|/T²."""
    T = np.diff(np.asarray(t_rel, dtype=float))
    T = np.minimum(T, np.maximum(1, np.round(T / dt)) * dt)[:, None]   # the sampled move's time, if shorter
    by_speed = np.asarray(robot.dq_max, dtype=float)[None, :] * T / 1.875
    by_acc = np.asarray(robot.ddq_max, dtype=float)[None, :] * T ** 2 / (10.0 / math.sqrt(3.0))
    return _FOLLOW_LIMIT_SHARE * np.minimum(by_speed, by_acc)


def follow_chain(robot, poses: Sequence, t_rel: Optional[np.ndarray], dt: float, rng,
                 restarts: int) -> Tuple[Optional[List[np.ndarray]], int]:
    """(one configuration per pose, each found from the one before, -1) or (None, the pose none was found
    for). With the follow's times ``t_rel`` each configuration lies within :func:`follow_steps` of the one before,
    and up to :data:`FOLLOW_TRIES` chains are started, each from another configuration of the first pose (all
    drawn from ``rng``); without times one chain, as the untimed motion stops at every pose."""
    from robodesign.solvers.ik import solve_ik
    steps = None if t_rel is None else follow_steps(robot, t_rel, dt)
    k = 0
    for _ in range(FOLLOW_TRIES if steps is not None else 1):
        q = solve_ik(robot, poses[0], rng, max_restarts=restarts).q
        if q is None:
            return None, 0
        sols = [q]
        for k in range(1, len(poses)):
            q = solve_ik(robot, poses[k], rng, q_seed=sols[-1], max_restarts=restarts,
                         max_step=None if steps is None else steps[k - 1]).q
            if q is None:
                break
            sols.append(q)
        if len(sols) == len(poses):
            return sols, -1
    return None, k


def timed_follow(path: np.ndarray, t_rel: np.ndarray, dt: float):
    """Quintic rest-to-rest moves between consecutive follow poses with exactly the given timing."""
    out = Trajectory.at_rest(path[0])
    for a, b, T in zip(path, path[1:], np.diff(t_rel)):
        n = max(1, int(round(T / dt)))
        s = np.linspace(0, 1, n + 1)[:, None]
        d = b - a
        q = a + d * (10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5)
        dq = d * (30 * s ** 2 - 60 * s ** 3 + 30 * s ** 4) / T
        ddq = d * (60 * s - 180 * s ** 2 + 120 * s ** 3) / T ** 2
        ddq[-1] = 0.0
        out = out.concatenate(Trajectory(np.arange(n + 1) * dt, q, dq, ddq))
    return out
