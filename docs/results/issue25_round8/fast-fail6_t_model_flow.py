import sys, os, time
sys.argv=['x', '--src', os.environ.get('SRC', '/work/h-fast-fail6')]; sys.path.insert(0,'experiments')
import profile_evaluator as pe
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.solve import warm_up; warm_up()
from robodesign.design.problem import Problem
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.model import robot_build as rb
import numpy as np
f = pe.family_tasks(os.environ.get('FAM',"whitman2020_g5o5"), 1, 0)[0]
problem = Problem.build(f, "robodesign_arm", "cyc")
ev = Evaluator(EvaluatorSpec(problem, seed=0))
rng = np.random.default_rng(0)
cands = [problem.space.random_candidate(rng) for _ in range(1200)]
ikc=[c for c in cands if ev.evaluate(c).stage=='ik']
orig_model, orig_walk = rb._model, rb.walk
tm=[]; tw=[]
def _model(w):
    t=time.process_time(); orig_model(w); tm.append(time.process_time()-t)
rb._model=_model
import robodesign.model.robot as R
def walk(*a):
    t=time.process_time(); w=orig_walk(*a); tw.append(time.process_time()-t); return w
R.walk=walk
for c in ikc: ev.evaluate(c)
print('flow: _model median us', np.median(tm)*1e6, 'walk median us', np.median(tw)*1e6)
from robodesign.formats.assembly import Assembly
import pinocchio as pin
ms=problem.module_set
asms=[Assembly.from_order(ms, list(c.order)) for c in ikc]
ws=[orig_walk(ms,a,False) for a in asms]
tm.clear()
for w in ws:
    w.model=pin.Model(); _model(w)
print('isolated (after flow) _model median us', np.median(tm)*1e6)
tm.clear()
ws2=[orig_walk(ms,a,False) for a in asms]
print('walks in a row: _model median us', np.median(tm)*1e6)
