"""In-process A/B of time_parameterize: base_s7's timing.py (its own BlendedPolyline) vs this checkout's, on the paths of
20 good-arm PTP_3 evaluations (every sample compared bit for bit first). usage: --src CHECKOUT (base: /tmp/base_s7)"""
import sys, time, importlib.util
src = sys.argv[sys.argv.index("--src") + 1]
sys.path.insert(0, src + "/src")
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.solve import warm_up; warm_up()
from robodesign.design.problem import Problem
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.search_space import Candidate
from robodesign.solvers import timing
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
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
gp.time_parameterize = orig
spec = importlib.util.spec_from_file_location("base_timing", "/tmp/base_s7/src/robodesign/solvers/timing.py")
bt = importlib.util.module_from_spec(spec); sys.modules["base_timing"] = bt; spec.loader.exec_module(bt)
import gc; gc.freeze()
for r, P, kw in calls:
    a, b = bt.time_parameterize(r, P, **kw), timing.time_parameterize(r, P, **kw)
    assert all(x.tobytes() == y.tobytes() for x, y in ((a.t, b.t), (a.q, b.q), (a.dq, b.dq), (a.ddq, b.ddq)))
ta, tb = [], []
for rep in range(9):
    for lst, f in ((ta, bt.time_parameterize), (tb, timing.time_parameterize)):
        t = time.process_time()
        for _ in range(5):
            for r, P, kw in calls: f(r, P, **kw)
        lst.append((time.process_time() - t) / (5 * len(calls)) * 1e3)
rr = np.array(ta) / np.array(tb)
print(f"{len(calls)} calls, results identical; ms CPU per call (median of 9 alternating rounds of {5 * len(calls)} calls): "
      f"base {np.median(ta):.3f}, new {np.median(tb):.3f}; per-round ratio base/new median {np.median(rr):.3f} "
      f"(min {rr.min():.3f}, max {rr.max():.3f})")
print("base rounds", np.round(ta, 3).tolist())
print("new rounds ", np.round(tb, 3).tolist())
