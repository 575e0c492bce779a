"""How many distance-field cells coal computes (DistanceField._exact) per stage, over PTP_3's 900-candidate stream's
first 900 random candidates' 23 feasible ones (feas.pkl) evaluated in one process."""
import sys, pickle
from collections import Counter
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
from profile_evaluator import SHARED
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
from robodesign.model import collision_cull
from robodesign.judge import checker
ik_kernel.warm_up(); warm_up()
count, where = Counter(), ["other"]
f = collision_cull.DistanceField._exact
def g(self, c):
    count[where[0]] += 1
    return f(self, c)
collision_cull.DistanceField._exact = g
ch = checker._check
def judged(*a, **k):
    where[0] = "judge"
    try:
        return ch(*a, **k)
    finally:
        where[0] = "other"
checker._check = judged
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
feas = pickle.load(open("/tmp/s11/feas.pkl", "rb"))
ev = Evaluator(EvaluatorSpec(ptp3, seed=1))
for c in feas:
    ev.evaluate(c)
print(src, dict(count))
