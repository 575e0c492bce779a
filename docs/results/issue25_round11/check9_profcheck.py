"""cProfile of the judge's check only, over the 23 feasible PTP_3 candidates' first evaluations (argv[2]=first)
or their second ones (again)."""
import sys, time, pickle, cProfile
src = sys.argv[1]; which = sys.argv[2]; out = sys.argv[3]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import SHARED
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
from robodesign.judge import checker
import robodesign.design.evaluator as EVm
ik_kernel.warm_up(); warm_up()
from robodesign.judge import interval_kernel; from robodesign.model import sweep_kernel
interval_kernel.warm_up(); sweep_kernel.warm_up()
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
ev = Evaluator(EvaluatorSpec(ptp3, seed=0))
feas = pickle.load(open("/tmp/s11/feas.pkl", "rb"))
import pstats, time, os
state = {"on": False}; kept = []
orig = checker._check
def wrapped(*a, **k):
    if not state["on"]:
        return orig(*a, **k)
    pr = cProfile.Profile(); t = time.process_time(); pr.enable()
    try: return orig(*a, **k)
    finally:
        pr.disable(); dt = time.process_time() - t
        if dt < 0.12:
            pr.dump_stats(out + f".{len(kept)}"); kept.append(out + f".{len(kept)}")
checker._check = wrapped
for c in feas:
    state["on"] = which == "first"; ev.evaluate(c)
    state["on"] = which == "again"; ev.evaluate(c)
st = pstats.Stats(kept[0])
for f in kept[1:]: st.add(f)
st.dump_stats(out); print(len(kept), "checks kept")
