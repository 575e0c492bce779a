import sys, os, time
sys.argv=['x', '--src', os.environ.get('SRC', '/work/h-fast-fail6')]; sys.path.insert(0,'experiments')
import profile_evaluator as pe
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.solve import warm_up; warm_up()
from robodesign.design.problem import Problem
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
import numpy as np
fam = os.environ.get('FAM', "whitman2020_g5o5")
f = pe.family_tasks(fam, 1, 0)[0]
problem = Problem.build(f, "robodesign_arm", "cyc")
ev = Evaluator(EvaluatorSpec(problem, seed=0))
rng = np.random.default_rng(0)
cands = [problem.space.random_candidate(rng) for _ in range(1200)]
ikc=[c for c in cands if ev.evaluate(c).stage=='ik']
import gc
tot=[]; st={}; ovh=[]
for rep in range(3):
  for c in ikc:
    t=time.perf_counter(); e=ev.evaluate(c); tot.append(time.perf_counter()-t); ovh.append(tot[-1]-sum(s['seconds'] for s in e.stages))
    for s in e.stages: st.setdefault(s['name'],[]).append(s['seconds'])
print(len(ikc), 'total median ms', np.median(tot)*1e3, 'mean', np.mean(tot)*1e3)
for k,v in st.items(): print(k, 'median ms %.3f mean %.3f'%(np.median(v)*1e3, np.mean(v)*1e3))
print('overhead median ms', np.median(ovh)*1e3);print('overhead mean ms', np.mean(tot)*1e3 - sum(np.mean(v) for v in st.values())*1e3)
