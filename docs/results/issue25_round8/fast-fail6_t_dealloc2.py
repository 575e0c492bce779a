import sys, os, time, gc
sys.argv=['x', '--src', os.environ.get('SRC', '/work/h-fast-fail6')]; sys.path.insert(0,'experiments')
import profile_evaluator as pe
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.solve import warm_up; warm_up()
from robodesign.design.problem import Problem
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.model import cell
import numpy as np
fam = os.environ.get('FAM', "whitman2020_g5o5")
f = pe.family_tasks(fam, 1, 0)[0]
problem = Problem.build(f, "robodesign_arm", "cyc")
ev = Evaluator(EvaluatorSpec(problem, seed=0))
rng = np.random.default_rng(0)
cands = [problem.space.random_candidate(rng) for _ in range(1200)]
ikc=[c for c in cands if ev.evaluate(c).stage=='ik']
kept=[]
orig = cell.RobotPool.give_back
def gb(self, robot):
    orig(self, robot); 
cell.RobotPool.size=0
class P(cell.RobotPool):
    pass
# keep robots instead of dropping them
import robodesign.design.solve as S
def give_back(self):
    if self.robot is not None:
        kept.append(self.robot); self.robot=None
S._Pipeline.give_back = give_back
for c in ikc[:300]: ev.evaluate(c)
from collections import defaultdict
acc={}
gc.disable()
keys=list(vars(kept[0]))
for k in keys:
    t=time.process_time()
    for r in kept:
        if k in vars(r): delattr(r,k)
    acc[k]=time.process_time()-t
t=time.process_time(); del kept[:]; acc['_rest']=time.process_time()-t
for k,v in sorted(acc.items(), key=lambda x:-x[1])[:14]: print(k, '%.1f us'%(v/300*1e6))
print('total', sum(acc.values())/300*1e6)
