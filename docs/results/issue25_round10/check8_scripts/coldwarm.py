"""check time inside the evaluation (cold) vs the same check replayed right after (warm), per part.
usage: python coldwarm.py SRC [n]"""
import sys, time
src = sys.argv[1]
sys.path.insert(0, src + "/src")
from pathlib import Path
import numpy as np
from robodesign.solvers import ik_kernel
ik_kernel.warm_up()
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.design.solve import warm_up
import robodesign.design.solve as sv
from robodesign.judge import checker as ck
warm_up()
SH = Path("/work/shared/cobra")
p = Problem.build(SH/"tasks/simple/PTP_3.json", SH/"modules/IMPROV", "cyc")
GOOD = ("1","21","4","22","5","23","12")
Evaluator(EvaluatorSpec(p)).evaluate(Candidate(GOOD))
orig = sv.check
cold, warm, sols = [], [], []
tim_c, tim_w = [], []
def wrapped(*a, **k):
    t = time.process_time(); r = orig(*a, **k); cold.append(time.process_time() - t); tim_c.append(r.timings)
    sols.append((a, k))
    t = time.process_time(); r2 = orig(*a, **k); warm.append(time.process_time() - t); tim_w.append(r2.timings)
    return r
sv.check = wrapped
n = int(sys.argv[2]) if len(sys.argv) > 2 else 20
for s in range(n):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
print("samples", [a[1].trajectory.n for a, k in sols][:10])
print(f"cold {np.median(cold)*1e3:.2f} ms  warm {np.median(warm)*1e3:.2f} ms")
for key in tim_c[0]:
    print(f"  {key:12s} cold {np.median([t[key] for t in tim_c])*1e3:6.2f}  warm {np.median([t[key] for t in tim_w])*1e3:6.2f}")
