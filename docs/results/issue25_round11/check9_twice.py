"""The 23 feasible PTP_3 candidates evaluated twice each (fresh, then again): check stage ms per candidate."""
import sys, time, pickle
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import SHARED
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
ik_kernel.warm_up(); warm_up()
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
ev = Evaluator(EvaluatorSpec(ptp3, seed=0))
feas = pickle.load(open("/tmp/s11/feas.pkl", "rb"))
a, b = [], []
for c in feas:
    for lst in (a, b):
        e = ev.evaluate(c)
        lst.append({s["name"]: s["seconds"] * 1e3 for s in e.stages})
for k in ("ik", "plan", "timing", "check"):
    print(k, "first %.1f again %.1f" % (np.median([x.get(k, 0) for x in a]), np.median([x.get(k, 0) for x in b])))
print("check first:", " ".join("%.0f" % x.get("check", 0) for x in a))
print("check again:", " ".join("%.0f" % x.get("check", 0) for x in b))
