import sys, time, gc
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import family_tasks
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up, robot_pool
from robodesign.solvers import ik_kernel
ik_kernel.warm_up(); warm_up()
problem = Problem.build(family_tasks("whitman2020_g5o5", 1, 0)[0], "robodesign_arm", "cyc")
ev = Evaluator(EvaluatorSpec(problem, seed=0))
rng = np.random.default_rng(0)
cands = [problem.space.random_candidate(rng) for _ in range(400)]
pool = robot_pool(problem.task)
pool.size = 10**6   # keep every robot: drop them by hand afterwards
for c in cands: ev.evaluate(c)
robots = [r for rs in pool._free.values() for r in rs]
pool._free.clear()
gc.disable()
T = {"data": [], "model": [], "python rest": [], "whole (other robots)": []}
half = len(robots) // 2
for r in robots[:half]:
    t = time.perf_counter(); r.data = None; T["data"].append(time.perf_counter() - t)
    m = r.kinematic_model; r.kinematic_model = None; w = r._bodies_of; r._bodies_of = None
    t = time.perf_counter(); del m, w; T["model"].append(time.perf_counter() - t)
for i in range(half):
    r = robots[i]; robots[i] = None
    t = time.perf_counter(); del r; T["python rest"].append(time.perf_counter() - t)
for i in range(half, len(robots)):
    r = robots[i]; robots[i] = None
    t = time.perf_counter(); del r; T["whole (other robots)"].append(time.perf_counter() - t)
for k, v in T.items(): print(f"{k:22s} median {np.median(v)*1e6:7.1f} us  n {len(v)}")
