"""Capture the time_parameterize calls of n good-arm PTP_3 evaluations (capture(n): [(robot, path, options)])."""
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

def capture(n=20):
    p = Problem.build(S/"tasks/simple/PTP_3.json", S/"modules/IMPROV", "cyc")
    calls = []
    orig = gp.time_parameterize
    def grab(robot, path, **kw):
        calls.append((robot, np.array(path), kw)); return orig(robot, path, **kw)
    gp.time_parameterize = grab
    for s in range(n):
        Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
    gp.time_parameterize = orig
    return calls
