import sys, json
src = sys.argv[1]; out = sys.argv[2]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import SHARED
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
from robodesign.design import goal_planner as gp
from robodesign.model import geometry_kernel
ik_kernel.warm_up(); warm_up(); geometry_kernel.ready()
import cProfile; pr = cProfile.Profile()
ON = [False]
f = gp.GoalPlanner.solve_ik
def g(self, *a, **k):
    if ON[0]: pr.enable()
    try: return f(self, *a, **k)
    finally: pr.disable()
gp.GoalPlanner.solve_ik = g
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
ev = Evaluator(EvaluatorSpec(ptp3, seed=0))
rng = np.random.default_rng(0); cands = [ptp3.space.random_candidate(rng) for _ in range(900)]
feas = [i for i in json.load(open(__file__.rsplit("/", 1)[0] + "/feas.json")) if i >= 250]
for i, c in enumerate(cands):
    ON[0] = i in feas
    ev.evaluate(c)
pr.dump_stats(out)
