"""fresh_stream, with a cProfile only around the feasible candidates (indices from a first pass, cached)."""
import sys, time, hashlib, os, json
src = sys.argv[1]; N = 900; out = sys.argv[2]
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
rng = np.random.default_rng(0); cands = [ptp3.space.random_candidate(rng) for _ in range(N)]
feas = set(json.load(open(__file__.rsplit("/", 1)[0] + "/feas.json"))) if os.path.exists(__file__.rsplit("/", 1)[0] + "/feas.json") else None
import cProfile; pr = cProfile.Profile()
fl = []
for i, c in enumerate(cands):
    on = feas is not None and i in feas
    if on: pr.enable()
    e = ev.evaluate(c)
    if on: pr.disable()
    if e.feasible: fl.append(i)
json.dump(fl, open(__file__.rsplit("/", 1)[0] + "/feas.json", "w"))
pr.dump_stats(out)
