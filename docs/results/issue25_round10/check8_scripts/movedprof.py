import sys, time, cProfile, pstats
src = sys.argv[1]
sys.path.insert(0, src + "/src")
import numpy as np
from robodesign.solvers import ik_kernel
ik_kernel.warm_up()
from robodesign.design.solve import warm_up
warm_up()
import robodesign.design.solve as sv
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.judge import checker as ck
S = "/work/shared/cobra"
p = Problem.build(f"{S}/tasks/simple/PTP_3.json", f"{S}/modules/IMPROV", "cyc")
sols = []
orig = sv.check
sv.check = lambda task, sol, ms, **kw: (sols.append((task, sol, ms, kw)), orig(task, sol, ms, **kw))[1]
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(("1", "21", "4", "22", "5", "23", "12")))
sv.check = orig
def moved(a, n):
    T = np.eye(4); c, s = np.cos(1e-4 * n), np.sin(1e-4 * n); T[:2, :2] = [[c, -s], [s, c]]; T[0, 3] = 1e-4 * n
    return a[1].with_(base_pose=T @ np.asarray(a[1].base_pose, dtype=float))
jobs = [(a, moved(a, n + 1)) for n, a in enumerate(sols * 3)]
pr = cProfile.Profile(); pr.enable()
for a, sol in jobs:
    ck.check(a[0], sol, a[2], **a[3])
pr.disable(); pstats.Stats(pr).sort_stats(sys.argv[2] if len(sys.argv) > 2 else "tottime").print_stats(35)
