"""Coal and pinocchio calls of the plan stage (plan_path) on PTP_3's feasible fresh arms (issue 25, round 12, plan7).

Usage: ``python plan7_coal_calls.py CHECKOUT I``: candidate I of /tmp/s11/feas.pkl after the warm-up (I = -1: all of
them); prints the counts of computeCollision, computeDistance and updateGeometryPlacements inside plan_path and its
CPU ms."""
import collections
import pickle
import sys
import time

src = sys.argv[1]; idx = int(sys.argv[2])
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import pinocchio as pin
from profile_evaluator import SHARED

from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel, planning

ik_kernel.warm_up(); warm_up()
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
feas = pickle.load(open("/tmp/s11/feas.pkl", "rb"))
ev = Evaluator(EvaluatorSpec(ptp3, seed=1))
ev.evaluate(feas[0])
cnt = collections.Counter(); on = [False]
for name in ("computeCollision", "computeDistance", "updateGeometryPlacements"):
    f = getattr(pin, name)
    def w(*a, _f=f, _n=name):
        if on[0]: cnt[_n] += 1
        return _f(*a)
    setattr(pin, name, w)
orig = planning.plan_path
def wrapped(*a, **k):
    on[0] = True; t = time.process_time(); r = orig(*a, **k); cnt["cpu_ms"] += int(1000 * (time.process_time() - t)); on[0] = False; return r
planning.plan_path = wrapped
for c in (feas[1:] if idx < 0 else [feas[idx]]): ev.evaluate(c)
print(src, dict(cnt))
