"""Which candidate's PosedArms.__init__ takes ~220 ms, and whether it is the garbage collector."""
import sys, time, pickle, gc
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
from profile_evaluator import SHARED
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
from robodesign.model import sweep_bounds
ik_kernel.warm_up(); warm_up()
f = sweep_bounds.PosedArms.__init__
log = []
def g(self, *a, **k):
    t = time.perf_counter(); c0 = gc.get_stats()[2]["collections"]
    f(self, *a, **k)
    log.append((time.perf_counter() - t, gc.get_stats()[2]["collections"] - c0))
sweep_bounds.PosedArms.__init__ = g
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
feas = pickle.load(open("/tmp/s11/feas.pkl", "rb"))
ev = Evaluator(EvaluatorSpec(ptp3, seed=1))
for i, c in enumerate(feas):
    log.clear(); ev.evaluate(c)
    print(i, [(round(t * 1e3, 2), n) for t, n in log])
