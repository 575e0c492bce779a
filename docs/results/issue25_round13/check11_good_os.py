"""CPU of the judge's check of the known-good PTP_3 arm's solution (checker.check), repeated, and of its sweeps'
open_steps, in one process (src given)."""
import sys, time
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments"); sys.path.insert(0, "/work/main/tests")
import numpy as np
from profile_evaluator import SHARED
from robodesign.design.solve import SolveSettings, solve, warm_up
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.judge import checker
from robodesign.model import sweep
from robodesign.solvers import ik_kernel
ik_kernel.warm_up(); warm_up()
task = load_task(SHARED / "tasks" / "simple" / "PTP_3.json")
ms = load_module_set(SHARED / "modules" / "IMPROV")
res = solve(task, ms, ["1", "21", "4", "22", "5", "23", "12"], settings=SolveSettings(seed=0))
T = {"open_steps": 0.0, "check": 0.0}
def wrap(owner, name):
    f = getattr(owner, name)
    def g(*a, **k):
        t = time.process_time()
        try:
            return f(*a, **k)
        finally:
            T[name] += time.process_time() - t
    setattr(owner, name, g)
wrap(sweep, "open_steps"); wrap(sweep.SweepChecker, "check")
for _ in range(5):
    checker.check(task, res.solution, ms)
rows = []
for _ in range(40):
    for k in T: T[k] = 0.0
    t = time.process_time()
    checker.check(task, res.solution, ms)
    rows.append((time.process_time() - t, T["check"], T["open_steps"]))
r = np.median(np.array(rows), axis=0) * 1e3
print(f"{src}: judge {r[0]:.2f} ms, sweep.check {r[1]:.2f}, open_steps {r[2]:.2f}  (medians of 40)")
