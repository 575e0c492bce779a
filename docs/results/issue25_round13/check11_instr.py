"""Per-candidate CPU of the judge's pieces over PTP_3's 22 fresh feasible arms (after the first)."""
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
from robodesign.model import sweep, sweep_clearance, sweep_bounds
from robodesign.judge import checker, robots, arc_torques
import robodesign.model.sweep_clearance as sc
ik_kernel.warm_up(); warm_up()
T = {}
def wrap(owner, name, label):
    f = getattr(owner, name)
    def g(*a, **k):
        t = time.process_time()
        try:
            return f(*a, **k)
        finally:
            T[label] = T.get(label, 0.0) + time.process_time() - t
    setattr(owner, name, g)
wrap(checker, "_check", "judge")
wrap(checker, "_sweep_events", "sweep_events")
wrap(sweep.SweepChecker, "__init__", "setup")
wrap(sweep.SweepChecker, "check", "check")
wrap(sweep.SweepChecker, "_advance", "advance")
wrap(sweep.SweepChecker, "_bounds", "bounds")
wrap(sweep.SweepChecker, "distances", "distances")
wrap(sweep, "open_steps", "open_steps")
wrap(robots, "take", "take")
wrap(robots, "scratch", "scratch")
wrap(checker, "certify_arc_torques", "arc")
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
feas = pickle.load(open("/tmp/s11/feas.pkl", "rb"))
ev = Evaluator(EvaluatorSpec(ptp3, seed=1))
ev.evaluate(feas[0])
rows = []
for c in feas[1:]:
    T.clear()
    ev.evaluate(c)
    rows.append(dict(T))
keys = sorted({k for r in rows for k in r})
for k in keys:
    v = np.array([r.get(k, 0.0) for r in rows]) * 1e3
    print(f"{k:14s} median {np.median(v):7.2f} ms  mean {v.mean():7.2f}  max {v.max():7.2f}")
