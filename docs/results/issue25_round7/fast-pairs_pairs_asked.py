import sys, collections
sys.path.insert(0,'experiments')
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.solve import warm_up; warm_up()
from robodesign.design.problem import Problem
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.search_space import Candidate
from robodesign.model import collision_cull
from pathlib import Path
S=Path('/work/shared/cobra')
GOOD = ("1", "21", "4", "22", "5", "23", "12")
p = Problem.build(S/"tasks/simple/PTP_3.json", S/"modules/IMPROV", "cyc")
cnt = collections.Counter(); hits = collections.Counter(); robots = {}
orig = collision_cull.CollisionCuller.collides
def col(self, q, pairs):
    ks = list(pairs) if type(pairs) is list else [int(k) for k in pairs]
    robots[id(self.robot)] = self.robot
    for k in ks: cnt[(id(self.robot), k)] += 1
    r = orig(self, q, ks)
    if r: hits[(id(self.robot), self._last_hit)] += 1
    return r
collision_cull.CollisionCuller.collides = col
for s in range(5):
    e = Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
byname = collections.Counter(); byhit = collections.Counter()
for (rid, k), c in cnt.items():
    r = robots[rid]; gm = r.geom_model; cp = gm.collisionPairs[k]
    a, b = gm.geometryObjects[cp.first], gm.geometryObjects[cp.second]
    key = (a.name, a.parentJoint, b.name, b.parentJoint)
    byname[key] += c; byhit[key] += hits[(rid, k)]
print(sum(cnt.values()), 'pair tests in 5 evals')
for key, c in byname.most_common(25): print(c, byhit[key], key)
