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
from robodesign.judge import motion, checker
from robodesign.model import sweep
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
ev = Evaluator(EvaluatorSpec(ptp3, seed=0))
feas = pickle.load(open("/tmp/s11/feas.pkl", "rb"))
T = {"at": 0.0, "n": 0, "dist": 0.0, "nd": 0, "adv": 0.0, "check": 0.0, "sw": 0.0}
f = motion.StepMotion.at
def g(self, k, s):
    t = time.perf_counter(); r = f(self, k, s); T["at"] += time.perf_counter() - t; T["n"] += 1; return r
motion.StepMotion.at = g
for name, key in (("_advance", "adv"), ("check", "sw")):
    o = getattr(sweep.SweepChecker, name)
    def w(*a, _o=o, _k=key, **k):
        t = time.perf_counter(); r = _o(*a, **k); T[_k] += time.perf_counter() - t; return r
    setattr(sweep.SweepChecker, name, w)
oc = checker._check
def wc(*a, **k):
    t = time.perf_counter(); r = oc(*a, **k); T["check"] += time.perf_counter() - t; return r
checker._check = wc
rows = []
for c in feas:
    before = dict(T); ev.evaluate(c)
    rows.append({k: (T[k] - before[k]) * (1e3 if isinstance(T[k], float) else 1) for k in T})
rows.sort(key=lambda r: r["check"])
for r in rows: print("  ".join(f"{k} {v:.1f}" for k, v in r.items() if k not in ("dist", "nd")))
print({k: round(v * 1e3 / 23, 2) if isinstance(v, float) else v for k, v in T.items()}, "ms per check")
