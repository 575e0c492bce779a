"""cProfile of only the judge's check inside 20 good-arm PTP_3 evaluations (profiler on only during check).
usage: python inevalprof.py SRC [sortkey] [n]"""
import sys, time, cProfile, pstats
src = sys.argv[1]
sys.path.insert(0, src + "/src")
from pathlib import Path
from robodesign.solvers import ik_kernel
ik_kernel.warm_up()
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.design.solve import warm_up
import robodesign.design.solve as sv
warm_up()
SH = Path("/work/shared/cobra")
p = Problem.build(SH/"tasks/simple/PTP_3.json", SH/"modules/IMPROV", "cyc")
GOOD = ("1","21","4","22","5","23","12")
Evaluator(EvaluatorSpec(p)).evaluate(Candidate(GOOD))
pr = cProfile.Profile()
orig = sv.check
ts = []
mode = sys.argv[2] if len(sys.argv) > 2 else "tottime"
def wrapped(*a, **k):
    if mode != "time":
        pr.enable()
    t = time.process_time()
    r = orig(*a, **k)
    ts.append(time.process_time() - t)
    if mode != "time":
        pr.disable()
    return r
sv.check = wrapped
n = int(sys.argv[3]) if len(sys.argv) > 3 else 20
for s in range(n):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
import numpy as np
print(f"check in evaluation: median {np.median(ts)*1e3:.3f} ms mean {np.mean(ts)*1e3:.3f}")
if mode != "time":
    pstats.Stats(pr).sort_stats(mode).print_stats(80)
