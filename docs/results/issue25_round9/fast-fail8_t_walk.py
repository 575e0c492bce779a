import sys, time
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
N = int(sys.argv[2])
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import family_tasks
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.model import robot_build, robot
from robodesign.solvers import ik_kernel
ik_kernel.warm_up(); warm_up()
problem = Problem.build(family_tasks("whitman2020_g5o5", 1, 0)[0], "robodesign_arm", "cyc")
ev = Evaluator(EvaluatorSpec(problem, seed=0))
rng = np.random.default_rng(0)
cands = [problem.space.random_candidate(rng) for _ in range(N)]
ev.evaluate(cands[0])
acc = {}
def wrap(mod, name):
    f = getattr(mod, name)
    def g(*a, **k):
        t = time.process_time(); r = f(*a, **k); acc.setdefault(name, []).append(time.process_time() - t); return r
    setattr(mod, name, g)
wrap(robot_build, "_model")
orig = robot_build.walk
def w2(*a):
    t = time.process_time(); r = orig(*a); acc.setdefault("walk", []).append(time.process_time() - t); return r
robot.walk = w2
T = []
for c in cands[1:]:
    t = time.process_time(); e = ev.evaluate(c); T.append(time.process_time() - t)
for k, v in acc.items(): print(k, len(v), "median us", round(np.median(v)*1e6, 1), "mean", round(np.mean(v)*1e6, 1))
print("eval median ms", np.median(T)*1e3)
