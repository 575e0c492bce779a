"""The planner's OMPL side: its start and goal states, and OMPL's discrete motion check one motion at a time
instead of one state at a time (issue 25).

OMPL's default motion validator (``DiscreteMotionValidator::checkMotion(s1, s2)``) asks the state validity checker
about ``s2`` first, then about the ``nd − 1`` states between (``nd = space.validSegmentCount(s1, s2)``, state ``j``
at ``s1 + (s2 − s1)·(j/nd)``) in the order of a queue of bisections (the middle of ``[1, nd − 1]``, then the middles
of its two halves, ...), and stops at the first invalid one: every state is one call from C++ into Python.
:func:`motion_validator` makes a validator that builds the same states in the same order (the same floating-point
operations: tests/test_ompl_motion.py compares them with OMPL's own interpolation bit for bit and the states a
planner asks for with and without it) and hands them to ``first_invalid`` at once, which decides them in that order
with the planner's own checks (budget, memo, bounds in front of coal): the planner sees the same verdicts.

Only the two-state form is provided; a planner that asks for the last valid state (KPIECE and its variants) keeps
OMPL's validator (:data:`PLANNERS_TWO_STATE`).
"""
from __future__ import annotations

import functools
from collections import deque
from typing import Callable, List

import numpy as np

#: OMPL planners (their robodesign names) whose motion checks are the two-state form only
PLANNERS_TWO_STATE = frozenset({"rrtconnect"})


def bisection_order(nd: int) -> List[int]:
    """The states 1 … nd − 1 of a motion in the order OMPL's ``checkMotion(s1, s2)`` checks them (a queue of
    intervals, each checked at its middle, ``(first + last) // 2``, then split)."""
    out: List[int] = []
    pos = deque([(1, nd - 1)]) if nd >= 2 else deque()
    while pos:
        a, b = pos.popleft()
        mid = (a + b) // 2
        out.append(mid)
        if a < mid:
            pos.append((a, mid - 1))
        if b > mid:
            pos.append((mid + 1, b))
    return out


def motion_states(a: np.ndarray, b: np.ndarray, nd: int, order: List[int]) -> np.ndarray:
    """``[b, a + (b − a)·(j/nd) for j in order]``: the states OMPL's ``checkMotion(a, b)`` asks about, in order."""
    return _interpolated(a, b, np.array(order, dtype=float) / float(nd))


def _interpolated(a: np.ndarray, b: np.ndarray, T: np.ndarray) -> np.ndarray:
    """``[b, a + (b − a)·t for t in T]``."""
    return np.vstack([b[None, :], a[None, :] + (b - a)[None, :] * T[:, None]])


@functools.lru_cache(maxsize=1024)
def _fractions(nd: int) -> np.ndarray:
    """:func:`bisection_order` of ``nd`` divided by ``nd`` (what :func:`motion_states` interpolates at), remembered
    across planning calls (read-only)."""
    T = np.array(bisection_order(nd), dtype=float) / float(nd)
    T.flags.writeable = False
    return T


def motion_validator(ob, space, si, n: int, first_invalid: Callable[[np.ndarray], int]):
    """An ``ob.MotionValidator`` for ``si`` whose ``checkMotion(s1, s2)`` is OMPL's discrete one with the states
    decided by ``first_invalid(Q)`` (the index of the first invalid row of ``Q`` in row order, or −1). It holds
    ``space`` (for its segment count), not ``si``: no reference cycle through OMPL's objects."""
    idx = range(n)

    class BatchedMotionValidator(ob.MotionValidator):
        def checkMotion(self, s1, s2, *last_valid) -> bool:
            if last_valid:   # (not installed for the planners that ask for it)
                raise NotImplementedError("checkMotion with the last valid state")
            T = _fractions(int(space.validSegmentCount(s1, s2)))
            a = np.array([s1[i] for i in idx], dtype=float)
            b = np.array([s2[i] for i in idx], dtype=float)
            return first_invalid(_interpolated(a, b, T)) < 0

    return BatchedMotionValidator(si)


def set_start_and_goals(ob, ss, space, si, qs: np.ndarray, G: np.ndarray, tol: float) -> None:
    """OMPL's start state ``qs`` and goal (threshold ``tol``): the one row of ``G``, or any of its rows."""
    n = len(qs)
    start = space.allocState()
    for i in range(n):
        start[i] = float(qs[i])
    if len(G) == 1:
        goal = space.allocState()
        for i in range(n):
            goal[i] = float(G[0, i])
        ss.setStartAndGoalStates(start, goal, tol)
        return
    goals = ob.GoalStates(si)
    for row in G:
        st = space.allocState()
        for i in range(n):
            st[i] = float(row[i])
        goals.addState(st)
    goals.setThreshold(tol)
    ss.setStartState(start)
    ss.setGoal(goals)


__all__ = ["PLANNERS_TWO_STATE", "bisection_order", "motion_states", "motion_validator", "set_start_and_goals"]
