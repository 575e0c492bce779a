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
import robodesign.solvers.ik as IK
import robodesign.solvers.ik_accept as IA
ik_kernel.warm_up(); warm_up()
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
feas = pickle.load(open("/tmp/s11/feas.pkl", "rb"))
T = {"solve":0.0,"batch":0.0,"repair":0.0,"accept":0.0,"coll":0.0}
N = {k:0 for k in T}
pc = time.process_time
def wrap(obj, name, key):
    f = getattr(obj, name)
    def w(*a, **k):
        t = pc(); r = f(*a, **k); T[key] += pc()-t; N[key]+=1; return r
    setattr(obj, name, w)
wrap(IK._Kernel, "batch", "batch"); wrap(IK._Kernel, "repair", "repair")
wrap(IA.Acceptance, "__call__", "accept")
orig = IK.solve_ik
def ws(*a, **k):
    t = pc(); r = orig(*a, **k); T["solve"] += pc()-t; N["solve"]+=1; return r
for mod in list(sys.modules.values()):
    if mod and getattr(mod, "solve_ik", None) is orig: mod.solve_ik = ws
ev = Evaluator(EvaluatorSpec(ptp3, seed=1))
for rep in range(4):
    for k in T: T[k]=0.0; N[k]=0
    t0=pc()
    for c in feas: ev.evaluate(c)
    tot=pc()-t0
    print(rep, "per candidate ms (second pass):", {k: round(v/len(feas)*1e3,2) for k,v in T.items()}, "calls", {k: round(v/len(feas),1) for k,v in N.items()}, "total", round(tot/len(feas)*1e3,1))
