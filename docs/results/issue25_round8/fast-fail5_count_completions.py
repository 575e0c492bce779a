import sys, os, time
sys.argv=['x','--src','/work/h-fast-fail5']; sys.path.insert(0,'experiments')
import profile_evaluator as pe
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.problem import Problem
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.model import robot as rmod
import numpy as np, traceback
from collections import Counter
calls=Counter()
orig=rmod.add_bodies
def ab(w,t):
    st=traceback.extract_stack(limit=4)[0]
    calls[(st.filename.split('/')[-1], st.lineno)]+=1
    return orig(w,t)
rmod.add_bodies=ab
for fam in ["whitman2020_g5o5","bpo2024"]:
    f = pe.family_tasks(fam, 1, 0)[0]
    problem = Problem.build(f, "robodesign_arm", "cyc")
    ev = Evaluator(EvaluatorSpec(problem, seed=0))
    rng = np.random.default_rng(0)
    st=Counter()
    for c in [problem.space.random_candidate(rng) for _ in range(300)]:
        n=sum(calls.values()); e=ev.evaluate(c); st[(e.stage, sum(calls.values())>n)]+=1
    print(fam, st); print(calls.most_common(8)); calls.clear()
