"""fast-fail4's replay of the candidates that fail at IK, split by reason: 1,500 random candidates of
profile_evaluator's first generated task of family FAM (whitman2020_g5o5 or bpo2024) are evaluated once; those
that fail at IK are evaluated again on a new robot pool, timed (CPU), and grouped by their message (the goal id
and numbers masked). Prints the overall median CPU ms, then per reason: count, median CPU ms, stage medians.
SRC: the checkout whose src/ is evaluated (run from /work/main)."""
import sys, os, time, re
SRC = os.environ.get('SRC', '/work/h-fast-fail4')
sys.argv=['x','--src',SRC]; sys.path.insert(0,'experiments')
import profile_evaluator as pe
import robodesign; print(robodesign.__file__)
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.solve import warm_up; warm_up()
from robodesign.design import solve as S
from robodesign.model import cell
from robodesign.design.problem import Problem
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
import numpy as np
from collections import defaultdict
fam = os.environ.get('FAM', "whitman2020_g5o5")
f = pe.family_tasks(fam, 1, 0)[0]
problem = Problem.build(f, "robodesign_arm", "cyc")
ev = Evaluator(EvaluatorSpec(problem, seed=0))
rng = np.random.default_rng(0)
cands = [problem.space.random_candidate(rng) for _ in range(1500)]
ikf = [c for c in cands if ev.evaluate(c).stage == 'ik']
S._POOLS.clear(); cell._SPARE.clear()
cat = defaultdict(list); stg = defaultdict(lambda: defaultdict(list))
for c in ikf:
    t = time.process_time(); e = ev.evaluate(c); dt = time.process_time() - t
    m = re.sub(r"goal \S+", "goal G", e.message); m = re.sub(r"\d+(\.\d+)?", "#", m)[:70]
    cat[m].append(dt)
    for s in e.stages: stg[m][s['name']].append(s['seconds'])
allt = sorted(x for v in cat.values() for x in v)
print('n', len(allt), 'median CPU ms %.3f' % (allt[len(allt)//2]*1e3))
for m, v in sorted(cat.items(), key=lambda kv: -len(kv[1])):
    v.sort(); print(len(v), '%.2f' % (v[len(v)//2]*1e3), m, {k: round(sorted(x)[len(x)//2]*1e3, 2) for k, x in stg[m].items()})
