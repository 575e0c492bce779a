import sys, timeit
sys.path.insert(0, "/work/h-check8/src")
import numpy as np
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.formats.assembly import Assembly
from robodesign.model.cell import build_robot
from robodesign.model import sweep
task = load_task("/work/shared/cobra/tasks/simple/PTP_3.json"); ms = load_module_set("/work/shared/cobra/modules/IMPROV")
r = build_robot(task, ms, Assembly.from_order(ms, ("1","21","4","22","5","23","12")), task.nominal_base_pose)
n = 200
print("_setup (judge's flags) us", timeit.timeit(lambda: sweep._setup(r, True, True, None, True, True), number=n)/n*1e6)
import cProfile, pstats
pr = cProfile.Profile(); pr.enable()
for _ in range(100): sweep._setup(r, True, True, None, True, True)
pr.disable(); pstats.Stats(pr).sort_stats("cumtime").print_stats(14)
