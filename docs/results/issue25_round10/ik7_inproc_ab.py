"""In-process A/B of CollisionCuller.in_collision on the IK stage's recorded queries (20 known-good PTP_3
evaluations): A = the hull proof off (last = -1, the culler before), B = the checkout's (the pair coal found
colliding last). Fresh cullers per round (build records cleared); the same verdicts are asserted; CPU µs per query
and coal's asks per round. usage: ik7_inproc_ab.py CHECKOUT [rounds]"""
import sys, time
sys.path.insert(0, sys.argv[1] + "/src")
from pathlib import Path
from typing import Any, cast
import numpy as np
from robodesign.solvers import ik_kernel
ik_kernel.warm_up()
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.design.solve import warm_up
from robodesign.model import collision_cull, geometry_kernel
import robodesign.solvers.ik_accept as acc
warm_up()
SH = Path("/work/shared/cobra")
p = Problem.build(SH / "tasks/simple/PTP_3.json", SH / "modules/IMPROV", "cyc")
GOOD = ("1", "21", "4", "22", "5", "23", "12")
Evaluator(EvaluatorSpec(p)).evaluate(Candidate(GOOD))
rec = []
orig = acc.Acceptance.__init__
def init(self, robot, *a, **k):
    orig(self, robot, *a, **k)
    if self.in_collision is not None:
        f = self.in_collision
        def wrapped(q, _r=robot, _f=f):
            rec.append((_r, np.array(q, float)))
            return _f(q)
        self.in_collision = wrapped
acc.Acceptance.__init__ = init
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
acc.Acceptance.__init__ = orig


class NoHull(collision_cull.CollisionCuller):
    """in_collision with the hull proof off (last = -1)."""
    def in_collision(self, q):
        args, grids, packed = self._one = self._one or self._kernel_args()
        n, nu, proven, due = cast(Any, geometry_kernel.survivors_packed)(q, *packed, -1)
        for k in self._due[:due].tolist():
            self._prove(k)
        if proven >= 0:
            self._last_hit = proven
        hit = proven >= 0 or (bool(n) and self._ask(q, args[-2][:n].tolist()))
        if nu:
            self._fill(grids, args[-1][:nu].copy())
        return hit


def run(kind):
    for r in (collision_cull._PROOFS, collision_cull._FIELDS, collision_cull._BOUNDS):
        r.clear()
    cullers = {}
    t = time.process_time()
    out = []
    for robot, q in rec:
        c = cullers.get(id(robot))
        if c is None:
            c = cullers[id(robot)] = kind(robot)
        out.append(c.in_collision(q))
    dt = time.process_time() - t
    return dt, out, sum(c.narrow for c in cullers.values())


rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 7
print("queries", len(rec), "robots", len({id(r) for r, _ in rec}))
ref = None
A, B = [], []
for i in range(rounds):
    for name, kind, acc_ in (("A", NoHull, A), ("B", collision_cull.CollisionCuller, B)):
        dt, out, narrow = run(kind)
        ref = out if ref is None else ref
        assert out == ref
        acc_.append(dt / len(rec) * 1e6)
        print("round %d %s: %.2f us/query, coal asks %d" % (i, name, dt / len(rec) * 1e6, narrow))
ratios = [b / a for a, b in zip(A, B)]
print("median A %.2f us, B %.2f us, B/A per round %s, median %.3f" % (np.median(A), np.median(B),
      " ".join("%.3f" % r for r in ratios), np.median(ratios)))
