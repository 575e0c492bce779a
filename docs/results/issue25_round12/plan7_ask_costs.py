"""The cost of a certificate's distance ask and of a collision ask of the touching pair (pair 1) of PTP_3's feasible fresh
arm 4 (/tmp/s11/feas.pkl), at its first planning call's start (issue 25, round 12, plan7).

Usage: ``python plan7_ask_costs.py CHECKOUT``."""
import pickle
import sys
import timeit

src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import SHARED

from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel, planning

ik_kernel.warm_up(); warm_up()
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
feas = pickle.load(open("/tmp/s11/feas.pkl", "rb"))
ev = Evaluator(EvaluatorSpec(ptp3, seed=1))
keep = {}
orig = planning.plan_path
def wrapped(robot, qs, *a, **k):
    keep["r"], keep["q"] = robot, qs; return orig(robot, qs, *a, **k)
planning.plan_path = wrapped
ev.evaluate(feas[4])
r, q = keep["r"], np.asarray(keep["q"], float)
v = planning._Memoized(planning._config_validator(r), r); c = v.culler(); certs = v.certificates
own = np.array([1]); n = 3000
td = min(timeit.repeat(lambda: certs._distances(q, own), number=n, repeat=5)) / n * 1e6
tc = min(timeit.repeat(lambda: c._ask(q, [1]), number=n, repeat=5)) / n * 1e6
print("distance ask (placements + 1 distance) %.1f us, collision ask (placements + 1 test) %.1f us" % (td, tc))
