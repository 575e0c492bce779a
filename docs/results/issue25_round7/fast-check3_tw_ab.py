import sys, time
src = sys.argv[sys.argv.index("--src") + 1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, src + "/tests")
exec(open("/work/h-fast-check3/docs/results/issue25_round7/fast-check3_check_loop.py").read().split("import gc")[0].split("sys.path.insert(0, src + \"/src\")")[1])
import numpy as np
from robodesign.judge.quantities import TrajectoryQuantities
from robodesign.model.cell import solution_robot
from test_quantities_fast import _former_twists
task, sol, ms, kw = sols[0]
r = solution_robot(task, sol, ms)
tq = TrajectoryQuantities.from_solution(r, sol, task)
tq.tcp_twists
f_new = lambda: TrajectoryQuantities.tcp_twists.func(tq)
f_old = lambda: _former_twists(tq)
assert f_new().tobytes() == f_old().tobytes()
ta, tb = [], []
for rep in range(7):
    for lst, f in ((ta, f_old), (tb, f_new)):
        t = time.process_time()
        for _ in range(100): f()
        lst.append((time.process_time() - t) / 100 * 1e3)
print(f"old {np.median(ta):.3f} new {np.median(tb):.3f} ms")
