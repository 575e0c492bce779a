import sys, os, cProfile, pstats
sys.argv=['x', '--src', os.environ.get('SRC', '/work/h-fast-fail6')]; sys.path.insert(0,'experiments')
import profile_evaluator as pe
import robodesign; print(robodesign.__file__)
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
from collections import Counter; st=Counter()
ikc=[]
for c in cands:
    e = ev.evaluate(c); st[e.stage]+=1
    if e.stage=='ik': ikc.append(c)
print(st)
pr = cProfile.Profile(); pr.enable()
for c in ikc: ev.evaluate(c)
pr.disable()
print(len(ikc))
pstats.Stats(pr).sort_stats(os.environ.get('SORT','cumulative')).print_stats(int(os.environ.get('N','70')))
