"""Replay the time_parameterize calls of 10 good-arm PTP_3 evaluations; cProfile or timing."""
import sys, time, hashlib, cProfile, pstats
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.solve import warm_up; warm_up()
from robodesign.design.problem import Problem
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.search_space import Candidate
import robodesign.design.goal_planner as gp
from pathlib import Path
import numpy as np
S = Path('/work/shared/cobra')
GOOD = ("1", "21", "4", "22", "5", "23", "12")
p = Problem.build(S/"tasks/simple/PTP_3.json", S/"modules/IMPROV", "cyc")
calls = []
orig = gp.time_parameterize
def grab(robot, path, **kw):
    calls.append((robot, np.array(path), kw)); return orig(robot, path, **kw)
gp.time_parameterize = grab
for s in range(10):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
gp.time_parameterize = orig
h = hashlib.sha256()
for r, P, kw in calls:
    tr = orig(r, P, **kw)
    for x in (tr.t, tr.q, tr.dq, tr.ddq): h.update(np.asarray(x).tobytes())
print("hash", h.hexdigest()[:12], len(calls), "calls")
if sys.argv[1:2] == ["prof"]:
    pr = cProfile.Profile(); pr.enable()
    for _ in range(10):
        for r, P, kw in calls: orig(r, P, **kw)
    pr.disable(); pstats.Stats(pr).sort_stats(sys.argv[2] if len(sys.argv) > 2 else "tottime").print_stats(40)
else:
    for k in range(5):
        t0 = time.process_time()
        for _ in range(10):
            for r, P, kw in calls: orig(r, P, **kw)
        print(f"{(time.process_time() - t0) / (10 * len(calls)) * 1e3:.3f} ms/call")
