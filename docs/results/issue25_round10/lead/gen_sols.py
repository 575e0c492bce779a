import sys, json
sys.path.insert(0, "/tmp/main_final10/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", "/tmp/main_final10"]
import numpy as np
from profile_evaluator import SHARED
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
ev = Evaluator(EvaluatorSpec(ptp3, seed=0, keep_solutions=True))
rng = np.random.default_rng(0)
out = []
for i in range(900):
    c = ptp3.space.random_candidate(rng)
    e = ev.evaluate(c)
    if e.feasible and e.solution is not None:
        out.append(e.solution)
json.dump(out, open("/tmp/s10/ptp3_sols.json", "w"))
print(len(out))
