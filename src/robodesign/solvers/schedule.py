"""Timing around the parts of a cell that move: moving obstacles and other robots.

Planning finds collision-free *paths* among the static obstacles; whether a timed motion along a path
also misses what moves depends on *when* it runs. This module answers that question with the
checker's semantics (docs/checker.md: the motion between samples is linear in joint space, a moving
obstacle keeps the pose in effect at a sample's time over the step to the next sample, another robot
moves linearly between its own samples) and certifies it between samples, and it chooses how long to
wait before a move so that the move misses everything that moves.

A *timed collider* is anything with ``first_collision(t, Q) -> Optional[(sample, description)]``: the
first step ``k`` (motion from ``t[k]`` to ``t[k+1]``, or sample ``k`` itself) where the robot moving through
the rows of ``Q`` at the times ``t`` touches it.
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import Optional, Protocol, Sequence, Tuple

import numpy as np

from robodesign.model.cell import build_robot, moving_obstacle_events, moving_obstacle_indices
from robodesign.model.pair_sweep import RobotPairSweep
from robodesign.model.robot import Robot
from robodesign.model.sweep import SweepChecker


class TimedCollider(Protocol):
    def first_collision(self, t: np.ndarray, Q: np.ndarray) -> Optional[Tuple[int, str]]: ...

    @property
    def settles_at(self) -> float:
        """A time after which this collider no longer changes."""
        ...


class MovingObstacles:
    """The task's moving obstacles as a timed collider of one robot: ``robot`` holds exactly the moving
    obstacles' collision objects (as :func:`moving_obstacles` builds it); the planning robot sees only the
    static cell."""

    def __init__(self, robot: Robot, task):
        self.robot, self.task = robot, task
        self.moving = moving_obstacle_indices(robot, task)
        self.checker = SweepChecker(robot, check_self=False, check_env=True, obstacles=self.moving)
        self.settles_at = max((float(o.motion_t[-1]) for o in task.obstacles if o.moving), default=0.0)

    def first_collision(self, t, Q) -> Optional[Tuple[int, str]]:
        ev = moving_obstacle_events(self.robot, self.task, self.moving, t, Q, first_only=True, checker=self.checker)
        return (ev[0].sample, f"{ev[0].first} ↔ {ev[0].second}") if ev else None


def static_cell(task):
    """The task without its moving obstacles (what IK and the planner see)."""
    return replace(task, obstacles=tuple(o for o in task.obstacles if not o.moving))


def moving_obstacles(task, module_set, assembly, base_pose) -> Optional[MovingObstacles]:
    """The task's moving obstacles as a timed collider of the robot (None if nothing moves)."""
    moving = tuple(o for o in task.obstacles if o.moving)
    if not moving:
        return None
    only = replace(task, obstacles=moving)
    return MovingObstacles(build_robot(only, module_set, assembly, base_pose), only)


class OtherRobot:
    """Another robot that follows a fixed timed motion ``(t_other, Q_other)`` (holding its last sample
    afterwards and its first before) as a timed collider of ``robot``. The times must lie on the same
    grid as the motions checked against it (both multiples of the task's time step)."""

    def __init__(self, robot: Robot, other: Robot, t_other: np.ndarray, Q_other: np.ndarray, margin: float = 0.0,
                 names=("robot", "other")):
        self.sweep = RobotPairSweep(robot, other, margin=margin, names=names)
        self.t_other = np.asarray(t_other, dtype=float)
        self.Q_other = np.asarray(Q_other, dtype=float)
        self.settles_at = float(self.t_other[-1])

    def q_other(self, t: np.ndarray) -> np.ndarray:
        return np.column_stack([np.interp(t, self.t_other, self.Q_other[:, j]) for j in range(self.Q_other.shape[1])])

    def first_collision(self, t, Q) -> Optional[Tuple[int, str]]:
        t = np.asarray(t, dtype=float)
        ev = self.sweep.check(np.hstack([np.asarray(Q, float), self.q_other(t)]), first_only=True)
        return (ev[0].sample, f"{ev[0].first} ↔ {ev[0].second}") if ev else None


def first_collision(colliders: Sequence[TimedCollider], t, Q) -> Optional[Tuple[int, str]]:
    """The earliest collision with any of ``colliders``."""
    hits = [h for h in (c.first_collision(t, Q) for c in colliders) if h is not None]
    return min(hits) if hits else None


class ScheduleError(Exception):
    pass


def find_wait(colliders: Sequence[TimedCollider], t_start: float, q_rest: np.ndarray, seg_t: np.ndarray,
              seg_q: np.ndarray, dt: float, coarse: int = 10) -> int:
    """The number of time steps to wait at rest in ``q_rest`` (from ``t_start``) before the move
    ``(seg_t, seg_q)`` (relative times, starting at ``q_rest``) so that neither the wait nor the move
    touches a collider; the smallest such number found by a coarse scan (``coarse`` steps at a time)
    refined step by step. Raises :class:`ScheduleError` if the robot is hit while it waits or if no wait
    helps (everything has settled and the move still collides)."""
    if not colliders:
        return 0
    rel = np.asarray(seg_t, dtype=float) - float(seg_t[0])
    horizon = max(c.settles_at for c in colliders) - t_start
    n_max = max(0, int(math.ceil(horizon / dt))) + 1

    def move_free(n: int) -> bool:
        return first_collision(colliders, t_start + n * dt + rel, seg_q) is None

    def wait_hit(n0: int, n1: int) -> Optional[Tuple[int, str]]:
        """A collision while holding q_rest over steps n0..n1."""
        times = t_start + dt * np.arange(n0, n1 + 1)
        return first_collision(colliders, times, np.repeat(np.asarray(q_rest, float)[None], len(times), axis=0))

    if move_free(0):
        return 0
    prev = 0
    n = 0
    while n < n_max:
        n = min(prev + coarse, n_max)
        hit = wait_hit(prev, n)
        if hit is not None:
            raise ScheduleError(f"hit while waiting at rest at t = {t_start + (prev + hit[0]) * dt:.3f} s ({hit[1]})")
        if move_free(n):
            for m in range(prev + 1, n):  # the smallest wait in the last coarse interval
                if move_free(m):
                    return m
            return n
        prev = n
    raise ScheduleError("the move collides with a moving part even after everything has settled")


def check_hold(colliders: Sequence[TimedCollider], t_start: float, q_rest: np.ndarray, duration: float,
               dt: float) -> Optional[str]:
    """Why holding ``q_rest`` from ``t_start`` for ``duration`` collides (None if it does not)."""
    if not colliders or duration <= 0:
        return None
    n = max(1, int(math.ceil(duration / dt - 1e-9)))
    times = t_start + dt * np.arange(n + 1)
    hit = first_collision(colliders, times, np.repeat(np.asarray(q_rest, float)[None], n + 1, axis=0))
    return None if hit is None else f"at t = {times[hit[0]]:.3f} s ({hit[1]})"
