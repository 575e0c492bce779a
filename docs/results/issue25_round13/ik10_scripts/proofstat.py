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
import robodesign.model.pair_clearance as PC
ik_kernel.warm_up(); warm_up()
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
feas = pickle.load(open("/tmp/s11/feas.pkl", "rb"))
REC = []
orig = PC.chain_clears
def cc(distance, arms, limit, budget=PC.BUDGET):
    calls = []
    def d(C):
        t = time.perf_counter(); r = distance(C); calls.append((len(C), time.perf_counter() - t, int((r <= limit).sum()), int(np.argmax(r <= limit)) if (r<=limit).any() else -1)); return r
    v = orig(d, arms, limit, budget)
    REC.append((v, len(arms), calls, type(distance.a).__name__, type(distance.b).__name__))
    return v
PC.chain_clears = cc
ev = Evaluator(EvaluatorSpec(ptp3, seed=1))
for rep in range(2):
    for c in feas: ev.evaluate(c)
pickle.dump(REC, open("/tmp/ik10/proofs.pkl", "wb"))
tot = sum(sum(x[1] for x in r[2]) for r in REC); n = sum(sum(x[0] for x in r[2]) for r in REC)
print("proofs", len(REC), "true", sum(r[0] for r in REC), "dist calls", n, "sec", round(tot,3), "us/call", round(tot/n*1e6,2))
fail = [r for r in REC if not r[0]]
print("failing proofs", len(fail), "calls in them", sum(sum(x[0] for x in r[2]) for r in fail))
wasted = 0; budgetfail = 0
for r in fail:
    last = r[2][-1]
    if last[2]: wasted += last[0] - last[3] - 1
    else: budgetfail += 1
print("wasted in failing last round", wasted, "budget/other fails", budgetfail)
from collections import Counter
print(Counter((r[1], r[0], len(r[2])) for r in REC).most_common(20))
print(Counter((r[3], r[4]) for r in REC))
