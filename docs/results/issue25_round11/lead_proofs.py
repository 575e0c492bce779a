import sys, time, pickle, collections
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
import robodesign.model.pair_clearance as PC
rec = []
orig_cc = PC.chain_clears
def cc(distance, arms, limit, budget=PC.BUDGET):
    t = time.perf_counter(); r = orig_cc(distance, arms, limit, budget)
    rec.append((len(arms), r, distance.asked, time.perf_counter() - t)); return r
PC.chain_clears = cc
nc = PC.never_collides; calls = [0, 0.0]
def nc2(*a, **k):
    t = time.perf_counter(); r = nc(*a, **k); calls[0] += 1; calls[1] += time.perf_counter() - t; return r
PC.never_collides = nc2
import robodesign.model.collision_cull as CC; CC.pair_clearance = PC
mode = sys.argv[2] if len(sys.argv) > 2 else "feas"
ev = Evaluator(EvaluatorSpec(ptp3, seed=0))
if mode == "feas":
    cands = pickle.load(open("/tmp/s11/feas.pkl", "rb"))
else:
    rng = np.random.default_rng(0); cands = [ptp3.space.random_candidate(rng) for _ in range(900)]
t0 = time.perf_counter(); nf = 0; tf = []
for c in cands:
    t = time.perf_counter(); e = ev.evaluate(c); dt = time.perf_counter() - t
    if e.feasible: nf += 1; tf.append(dt)
print("total s", time.perf_counter() - t0, "feasible", nf, "median feasible ms", np.median(tf) * 1e3)
print("never_collides calls", calls[0], "s", calls[1])
print("chain_clears runs", len(rec))
for k in (0, 1, 2, 3):
    for r in (True, False):
        sel = [x for x in rec if x[0] == k and x[1] == r]
        if sel: print(f"k={k} proven={r}: n={len(sel)} asked med {np.median([x[2] for x in sel]):.0f} mean {np.mean([x[2] for x in sel]):.0f} time total {sum(x[3] for x in sel):.3f}s mean {np.mean([x[3] for x in sel])*1e3:.2f} ms")
