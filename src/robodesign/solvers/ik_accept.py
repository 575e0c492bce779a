"""The acceptance of a converged IK configuration (:func:`robodesign.solvers.ik.solve_ik`): joint limits,
collision, whole turns towards the seed and distinctness from the solutions found so far.

Each test decides exactly as its plain form (issue 25: the same solutions bit for bit, faster):

* the limits on Python floats (``lo ≤ q`` for every joint, then ``q ≤ hi``; NaN fails as in numpy);
* :meth:`Robot.nearest_equivalent <robodesign.model.robot.Robot.nearest_equivalent>` is asked only when a joint
  lies more than half a turn from its reference (``|ref − q|/2π > 0.5``, the quotient it rounds): within that
  every whole-turn shift rounds to 0 and it returns q itself (a q within the limits);
* the duplicate test ``‖q − s‖ ≤ tol`` with the norm numpy computes (√ of the difference's ``dot`` with itself;
  :func:`near_any`)."""
from __future__ import annotations

import math
from operator import le
from typing import Any, Dict, List, Optional

import numpy as np

TWO_PI = 2.0 * math.pi


def near_any(q: np.ndarray, sols: List[np.ndarray], tol: float, rows: Optional[np.ndarray] = None) -> bool:
    """``any(np.linalg.norm(q - s) <= tol for s in sols)``, decided by the same numbers: the norm as numpy
    computes it (√ of the difference's ``dot`` with itself). With many solutions, one vectorised sum of squares
    first drops those farther than tol·√(1 + 1e-9): both sums are within n·2⁻⁵³ (relative) of the exact one, so
    none of those can be within tol by the exact test (tol > 1e-100: no underflow of tol²); the rest are tested
    one by one, in order. ``rows``: the solutions stacked (row i = sols[i], at least len(sols) rows; else stacked
    here)."""
    if len(sols) > 8 and tol > 1e-100:
        d = (np.array(sols) if rows is None else rows[:len(sols)]) - q
        idx = np.flatnonzero(np.einsum("ij,ij->i", d, d) <= tol * tol * (1.0 + 1e-9)).tolist()
        sols = [sols[i] for i in idx]
    for s in sols:
        d = q - s
        if math.sqrt(d.dot(d)) <= tol:
            return True
    return False


class Acceptance:
    """``accept(q) -> verdict`` ("limits", "collision", "far", "duplicate" or "added") of one :func:`solve_ik`
    call: counts the rejections in ``stats`` and appends an accepted configuration (its whole-turn equivalent
    nearest ``q_seed``, else nearest 0, when ``canonical`` and that one is valid too) to ``sols``. With
    ``max_step`` (per joint; needs ``q_seed``) a configuration farther than that from ``q_seed`` in some joint is
    rejected as "far"."""

    def __init__(self, robot, valid, lo: np.ndarray, hi: np.ndarray, q_seed: Optional[np.ndarray],
                 check_collision: bool, canonical: bool, distinct_tol: float, stats: Dict[str, Any],
                 sols: List[np.ndarray], max_step: Optional[np.ndarray] = None) -> None:
        self.robot, self.valid, self.q_seed = robot, valid, q_seed
        self.max_step = max_step
        self.lo, self.hi = lo.tolist(), hi.tolist()
        self.in_collision = robot.in_collision if check_collision else None
        self.canonical, self.distinct_tol, self.stats, self.sols = canonical, distinct_tol, stats, sols
        self._rows = np.array(sols, dtype=float).reshape(len(sols), len(lo))   # sols stacked (rows beyond: unused)
        # Robot.nearest_equivalent's reference point
        self.turn_ref = (np.clip(0.0, robot.q_lower, robot.q_upper) if q_seed is None else q_seed).tolist() \
            if canonical else []

    def __call__(self, q: np.ndarray) -> str:
        ql = q.tolist()
        if not (all(map(le, self.lo, ql)) and all(map(le, ql, self.hi))):   # guaranteed by the clamping: a guard
            self.stats["rejected_limits"] += 1
            return "limits"
        if self.in_collision is not None and self.in_collision(q):
            self.stats["rejected_collision"] += 1
            return "collision"
        # whole turns towards the seed (or 0): one sheet of the joint space (Robot.nearest_equivalent), which
        # returns q itself when no joint is more than half a turn from the reference (not asked then)
        if self.canonical and not all(-0.5 <= (r - v) / TWO_PI <= 0.5 for r, v in zip(self.turn_ref, ql)):
            q2 = self.robot.nearest_equivalent(q, self.q_seed)
            if not np.array_equal(q2, q) and self.valid(self.robot.fk(q2)):
                q = q2
        if self.max_step is not None and not np.all(np.abs(q - self.q_seed) <= self.max_step):
            self.stats["rejected_far"] = self.stats.get("rejected_far", 0) + 1
            return "far"
        if self.sols and near_any(q, self.sols, self.distinct_tol, self._rows):
            self.stats["rejected_duplicate"] += 1
            return "duplicate"
        self._stack(q)
        self.sols.append(q.copy())
        return "added"

    def _stack(self, q: np.ndarray) -> None:
        """Put ``q`` in ``_rows`` after the solutions so far (their room doubled when full)."""
        m = len(self.sols)
        if m == len(self._rows):
            grown = np.empty((max(2 * m, 16), len(q)))
            grown[:m] = self._rows
            self._rows = grown
        self._rows[m] = q
