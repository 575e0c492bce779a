import sys, time, timeit
pass
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.solve import warm_up; warm_up()
from robodesign.design.problem import Problem
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.search_space import Candidate
from pathlib import Path
import numpy as np
import robodesign.solvers.ik as ik
from robodesign.model import geometry_kernel
from robodesign.model.collision_cull import culler_of
S=Path('/work/shared/cobra')
GOOD = ("1", "21", "4", "22", "5", "23", "12")
p = Problem.build(S/"tasks/simple/PTP_3.json", S/"modules/IMPROV", "cyc")
cap = {}
orig = ik.solve_ik
def spy(robot, goal, *a, **k):
    cap['robot'], cap['goal'] = robot, goal
    r = orig(robot, goal, *a, **k); cap['sols'] = r.solutions; return r
ik.solve_ik = spy
Evaluator(EvaluatorSpec(p)).evaluate(Candidate(GOOD))
robot = cap['robot']
