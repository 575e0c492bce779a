"""In-process A/B of judge.check on the good IMPROV arm's 20 PTP_3 solutions (study seeds 0-19), branch fast-check6:
side A runs the sweep's former loop (SweepChecker.check with the heap of (sample, pair) and sweep_clearance.due_pairs,
copied below verbatim from the session's main, 3e6561b), side B this branch's (the compiled DueQueue). A and B
alternate check by check, so the machine's swings hit both alike. The verdicts (violations, costs, goals) and the
sweep's query counts must be equal.
usage (from /work/main): OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock .venv/bin/python
       docs/results/issue25_round8/fast-check6_check_ab.py SRC [rounds]"""
import heapq
import sys
import time
from typing import Callable, List, Optional

src = sys.argv[1]
rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 9
sys.path.insert(0, src + "/src")
import numpy as np  # noqa: E402
from robodesign.solvers import ik_kernel  # noqa: E402
ik_kernel.warm_up()
from robodesign.design.solve import warm_up  # noqa: E402
warm_up()
import robodesign.design.solve as sv  # noqa: E402
from robodesign.design.evaluator import Evaluator, EvaluatorSpec  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.search_space import Candidate  # noqa: E402
from robodesign.judge import checker as ck  # noqa: E402
from robodesign.model import sweep  # noqa: E402
from robodesign.model.sweep import _EXTEND_SELF, CollisionEvent, PosedArms, open_steps  # noqa: E402,F401


def due_pairs(heap: list, k: int, n: int, skip: Optional[np.ndarray]) -> List[int]:
    """Pop the pairs due at sample k from the sweep's ``heap`` ((sample, pair), the earliest first): those to query
    there; a pair whose clearance bounds certify from k (``skip``: :func:`open_steps`) is pushed back at the first
    step they do not certify (to query its first sample), or dropped when they certify it to the end."""
    due = []
    while heap and heap[0][0] == k:
        c = heapq.heappop(heap)[1]
        j = int(skip[c, k]) if skip is not None and k < n - 1 else k
        if j == k:
            due.append(c)
        elif j < n - 1:
            heapq.heappush(heap, (j, c))
    return due



def old_check(self, Q: np.ndarray, first_only: bool = True, path: Optional[np.ndarray] = None,
          at: Optional[Callable[[int, float], np.ndarray]] = None,
          poses: Optional[np.ndarray] = None) -> List[CollisionEvent]:
    """Collision events along a motion through the rows of Q: by default the piecewise-linear one.

    Another motion through the same samples is given by ``at(k, s)`` (q at fraction s ∈ [0, 1] of step k)
    and ``path`` (n−1, dof): per step and joint a bound on the joint's speed per unit of s, so that it moves
    at most ``path·|s' − s|`` between any two fractions s, s' of the step (|ΔQ| for the linear motion; the
    judge's motion: h·max|q̇|). Conservative advancement then certifies that motion: from an exact distance at
    an instant the pair stays free while the accumulated path bounds stay below the clearance.
    With ``first_only`` the search stops at the earliest event; otherwise one event is reported per pair
    and contact episode (the pair is re-armed once it separates again). ``poses``: ``robot.joint_poses_batch(Q)``
    if the caller has it (the posed bounds read it).
    """
    Q = np.asarray(Q, dtype=float)
    n = len(Q)
    P = len(self.pairs)
    if P == 0 or n == 0:
        return []
    if n == 1:
        return self._at_one_sample(Q[0], first_only)
    seg, sched, cum, cum_rows, TG = self._bounds(Q, path, poses)
    posed: Optional[PosedArms] = getattr(self, "_posed", None)  # (RobotPairSweep has none)
    ext = 4 * self.tolerance
    mov, ref = (np.array(getattr(self, a, ()), dtype=np.int64) for a in ("_mov", "_ref"))
    margins, is_env = self.margins.tolist(), self.is_env.tolist()
    events: List[CollisionEvent] = []
    # priority queue of (sample index where the pair must be re-checked, pair)
    heap = [(0, c) for c in range(P)]
    heapq.heapify(heap)
    skip = open_steps(self, TG, sched, seg.dQ, ext) if not first_only else None  # (sweep_clearance)
    while heap:
        k = heap[0][0]
        due = due_pairs(heap, k, n, skip)
        if not due:
            continue
        d = self.distances(Q[k], due)
        certified = (posed.certify(due, d, k, self.margins, self.is_env, cum_rows, TG, mov, ref, sched, ext,
                                   _EXTEND_SELF) if posed is not None else [-2] * len(due))
        for c, dist, nxt in zip(due, d.tolist(), certified):
            free = dist - margins[c]
            if free <= 0:
                events.append(CollisionEvent(k, 0.0, *self.pair_names[c], dist, bool(self.is_env[c])))
                if first_only:
                    return events
                again = self._rearm(Q, k, c, cum)
                if again is not None:
                    heapq.heappush(heap, (again, c))
                continue
            # the pair is certified free until the accumulated bound exceeds `free`
            row = cum_rows[c]
            if nxt == -2:  # no posed bounds, or a clearance or bound that is no finite number
                nxt = int(row.searchsorted(float(row[k]) + free, side="right")) - 1  # last sample certified
                if TG is not None and posed is not None and nxt < n - 1 and (is_env[c] or _EXTEND_SELF):
                    nxt = posed.extend(TG, self._mov[c], self._ref[c], k, nxt, sched, cum_rows, c, free - ext)
            if nxt >= n - 1:
                continue  # certified to the end
            if nxt > k:
                ahead = is_env[c] and (skip is None or skip[c, nxt] == nxt)  # (not where the bounds go on)
                nxt2 = self._ahead(Q, k, c, free, row, nxt) if ahead else nxt
                if nxt2 is not None:
                    heapq.heappush(heap, (nxt2, c))
                continue
            # nxt == k: the very next segment moves more than the clearance → advance inside it
            hit = self._advance(Q[k], Q[k + 1], seg[k, c], c, free,
                                None if at is None else (lambda s, k=k: at(k, s)))
            if hit is not None:
                s, dist2 = hit
                events.append(CollisionEvent(k, s, *self.pair_names[c], dist2, bool(self.is_env[c])))
                if first_only:
                    continue  # another pair of this batch may touch earlier inside the same step
                again = self._rearm(Q, k + 1, c, cum)
                if again is not None:
                    heapq.heappush(heap, (again, c))
            else:
                heapq.heappush(heap, (k + 1, c))
        if first_only and events:  # every pair was certified free up to sample k: the earliest is here
            return [min(events, key=lambda e: e.s)]
    events.sort(key=lambda e: (e.sample, e.s))
    return events



NEW = sweep.SweepChecker.check
S = "/work/shared/cobra"
p = Problem.build(f"{S}/tasks/simple/PTP_3.json", f"{S}/modules/IMPROV", "cyc")
sols = []
orig = sv.check
sv.check = lambda task, sol, ms, **kw: (sols.append((task, sol, ms, kw)), orig(task, sol, ms, **kw))[1]
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(("1", "21", "4", "22", "5", "23", "12")))
sv.check = orig
QUERIES = [0]
real_distances = sweep.SweepChecker.distances


def counted(self, q, cols):
    QUERIES[0] += len(cols)
    return real_distances(self, q, cols)


def set_side(side):
    """A: the former loop; B: this branch's."""
    sweep.SweepChecker.check = old_check if side == "A" else NEW


def key(v):
    return (v.valid, str([x.to_json() for x in v.violations]), repr(v.costs), repr(v.cost), v.goals)


import gc  # noqa: E402
gc.freeze()
verd = {}
for side in ("A", "B"):
    set_side(side)
    sweep.SweepChecker.distances = counted
    QUERIES[0] = 0
    verd[side] = ([key(ck.check(a[0], a[1], a[2], **a[3])) for a in sols], QUERIES[0])
    sweep.SweepChecker.distances = real_distances
assert verd["A"] == verd["B"], "verdicts or query counts differ"
ta, tb = [], []
for r in range(rounds):
    sa = sb = 0.0
    for rep in range(3):
        for i, a in enumerate(sols):
            for side in (("A", "B") if (i + r + rep) % 2 == 0 else ("B", "A")):
                set_side(side)
                t = time.process_time()
                ck.check(a[0], a[1], a[2], **a[3])
                d = time.process_time() - t
                if side == "A":
                    sa += d
                else:
                    sb += d
    ta.append(sa / (3 * len(sols)) * 1e3)
    tb.append(sb / (3 * len(sols)) * 1e3)
r = np.array(ta) / np.array(tb)
print(f"judge.check, ms CPU per check, median of {rounds} rounds (60 checks per side each, alternating check by check): "
      f"A (former heap loop) {np.median(ta):.3f}, B (compiled queue) {np.median(tb):.3f}; per-round ratio A/B median "
      f"{np.median(r):.3f} (min {r.min():.3f}, max {r.max():.3f}); verdicts and {verd['A'][1]} sweep queries equal")
print("A rounds", np.round(ta, 3).tolist())
print("B rounds", np.round(tb, 3).tolist())
