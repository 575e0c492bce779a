import sys, time, cProfile, pstats, io
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import SHARED
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
import robodesign.design.solve as S
ik_kernel.warm_up(); warm_up()
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
Evaluator(EvaluatorSpec(ptp3)).evaluate(Candidate(("1", "21", "4", "22", "5", "23", "12")))
pr = cProfile.Profile()
orig = S.check
T = []
def wrapped(*a, **k):
    t = time.process_time(); pr.enable()
    try: return orig(*a, **k)
    finally:
        pr.disable(); T.append(time.process_time() - t)
S.check = wrapped
ev = Evaluator(EvaluatorSpec(ptp3, seed=0))
rng = np.random.default_rng(0)
for i in range(900):
    ev.evaluate(ptp3.space.random_candidate(rng))
print("checks", len(T), "median ms", round(np.median(T) * 1e3, 2), "sum", round(sum(T) * 1e3, 1))
s = io.StringIO(); pstats.Stats(pr, stream=s).sort_stats("tottime").print_stats(35); print(s.getvalue())
