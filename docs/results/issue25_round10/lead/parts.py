import sys, time, gc, functools
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
SPECS = sys.argv[2:]; sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import family_tasks
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
ik_kernel.warm_up(); warm_up()
problem = Problem.build(family_tasks("whitman2020_g5o5", 1, 0)[0], "robodesign_arm", "cyc")
ev = Evaluator(EvaluatorSpec(problem, seed=0))
rng = np.random.default_rng(0)
cands = [problem.space.random_candidate(rng) for _ in range(300)]
fail = [c for c in cands if (lambda e: e.stage == "ik" and not e.feasible)(ev.evaluate(c))]
ev = Evaluator(EvaluatorSpec(problem, seed=1)); ev.evaluate(cands[0])
T = {}
def wrap(obj, name, label=None):
    f = getattr(obj, name); label = label or f"{getattr(obj,'__name__',obj)}.{name}"
    @functools.wraps(f)
    def g(*a, **k):
        t = time.perf_counter()
        try: return f(*a, **k)
        finally: T[label] = T.get(label, 0.0) + time.perf_counter() - t
    setattr(obj, name, g)
import robodesign.design.solve as S, robodesign.model.robot as R, robodesign.model.cell as C, robodesign.formats.assembly as A
import robodesign.model.robot_build as RB, robodesign.design.goal_planner as GP, robodesign.solvers.ik as IK
import robodesign.design.evaluator as E
for spec in SPECS:
    mod, name = spec.rsplit(".", 1)
    obj = eval(mod)
    wrap(obj, name, spec)
ts = []
for c in fail * 3:
    t = time.perf_counter(); ev.evaluate(c); ts.append(time.perf_counter() - t)
n = len(ts)
print("median", np.median(ts)*1e3, "mean", np.mean(ts)*1e3)
for k, v in T.items(): print(f"{k:50s} {v/n*1e6:8.1f} us")
