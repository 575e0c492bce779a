import sys, collections
sys.path.insert(0, sys.argv[1] + "/src")
from pathlib import Path
from robodesign.solvers import ik_kernel
ik_kernel.warm_up()
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.design.solve import warm_up
import robodesign.model.collision_cull as C
warm_up()
SH = Path("/work/shared/cobra")
p = Problem.build(SH/"tasks/simple/PTP_3.json", SH/"modules/IMPROV", "cyc")
GOOD = ("1","21","4","22","5","23","12")
Evaluator(EvaluatorSpec(p)).evaluate(Candidate(GOOD))
H = collections.Counter(); P = collections.Counter(); N = collections.Counter()
oa = C.CollisionCuller._ask
def ask(self, q, ks):
    r = oa(self, q, ks)
    nr = len(self.parent)
    if r:
        k = self._last_hit
        H[(int(self.first[k]), int(self.second[k]), "obst" if self.second[k] >= nr else "self")] += 1
    else:
        N[len(ks)] += 1
    return r
C.CollisionCuller._ask = ask
oi = C.CollisionCuller.in_collision
def inc(self, q):
    r = oi(self, q)
    return r
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
print("coal hits", H.most_common(12))
print("coal misses by #pairs", sorted(N.items()))
