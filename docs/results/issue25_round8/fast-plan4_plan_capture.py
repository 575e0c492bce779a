"""Capture the plan_path calls of n good-arm PTP_3 evaluations and replay them (profile or time)."""
import sys, time, hashlib, cProfile, pstats
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.solve import warm_up; warm_up()
from robodesign.design.problem import Problem
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.search_space import Candidate
from robodesign.solvers import planning
from pathlib import Path
import numpy as np
S = Path('/work/shared/cobra')
GOOD = ("1", "21", "4", "22", "5", "23", "12")
p = Problem.build(S/"tasks/simple/PTP_3.json", S/"modules/IMPROV", "cyc")
calls = []
orig = planning.plan_path
def grab(robot, a, b, **kw):
    calls.append((robot, np.array(a), np.array(b), kw)); return orig(robot, a, b, **kw)
planning.plan_path = grab
for s in range(10):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
planning.plan_path = orig
h = hashlib.sha256()
for r, a, b, kw in calls:
    res = orig(r, a, b, **kw)
    h.update(np.asarray(res.path).tobytes() if res.path is not None else b'none')
def loop():
    for _ in range(10):
        for r, a, b, kw in calls:
            orig(r, a, b, **kw)
if 'prof' in sys.argv:
    cProfile.run('loop()', '/tmp/fp4/prof.out'); pstats.Stats('/tmp/fp4/prof.out').sort_stats('tottime').print_stats(30)
else:
    t0 = time.process_time(); loop()
    print(f"{planning.__file__}: {len(calls)} calls, ms CPU per call {(time.process_time()-t0)/(10*len(calls))*1e3:.3f}, paths {h.hexdigest()[:12]}")
