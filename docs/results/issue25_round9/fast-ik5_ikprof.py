import sys, time, collections
sys.path.insert(0, sys.argv[1] + "/src")
import numpy as np
from pathlib import Path
from robodesign.solvers import ik_kernel
ik_kernel.warm_up()
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.design.solve import warm_up
import robodesign.solvers.ik as ik
import robodesign.solvers.ik_accept as acc
warm_up()
SH = Path("/work/shared/cobra")
p = Problem.build(SH/"tasks/simple/PTP_3.json", SH/"modules/IMPROV", "cyc")
GOOD = ("1","21","4","22","5","23","12")
Evaluator(EvaluatorSpec(p)).evaluate(Candidate(GOOD))
T = collections.Counter(); C = collections.Counter()
orig_solve = ik.solve_ik
def solve(*a, **k):
    t=time.perf_counter(); r = orig_solve(*a, **k); T["solve_ik"] += time.perf_counter()-t; C["solve_ik"]+=1
    for key in ("attempts","converged","rejected_collision","rejected_duplicate","repairs","iterations"):
        C[key] += r.stats[key]
    C["sols"] += len(r.solutions) if hasattr(r,"solutions") else 0
    return r
ik.solve_ik = solve
import robodesign.design.stages as st
for mod in list(sys.modules.values()):
    if mod and getattr(mod, "solve_ik", None) is orig_solve and mod is not ik:
        mod.solve_ik = solve
orig_init = acc.Acceptance.__init__
def init(self, robot, *a, **k):
    orig_init(self, robot, *a, **k)
    if self.in_collision is not None:
        f = self.in_collision
        def timed(q):
            t=time.perf_counter(); r=f(q); T["in_collision"] += time.perf_counter()-t; C["in_collision"]+=1; C["coll_true"]+=bool(r); return r
        self.in_collision = timed
acc.Acceptance.__init__ = init

DN = "descend" if hasattr(ik._Kernel, "descend") else "repair"
ob, od = ik._Kernel.batch, getattr(ik._Kernel, DN)
def tb(self,*a):
    t=time.perf_counter(); r=ob(self,*a); T["k.batch"]+=time.perf_counter()-t; C["k.batch"]+=1; return r
def td(self,*a):
    t=time.perf_counter(); r=od(self,*a); T["k.descend"]+=time.perf_counter()-t; C["k.descend"]+=1; return r
ik._Kernel.batch = tb; setattr(ik._Kernel, DN, td)
ov = ik.GoalModel  # noqa
N=20
stages = collections.Counter()
for s in range(N):
    ev = Evaluator(EvaluatorSpec(p, seed=s))
    e = ev.evaluate(Candidate(GOOD))
    for x in e.stages: stages[x["name"]] += x["seconds"]
print({k: round(v/N*1e3,2) for k,v in stages.items()})
print({k: round(v/N*1e3,2) for k,v in T.items()})
print({k: v/N for k,v in C.items()})
