"""The IK stage of candidates that fail the rank test, in the pipeline (cold, as a search meets them), with timers
around the parts this branch changed: random candidates of the whitman2020 profile task (as profile_evaluator draws
them), the medians over those that fail at IK because the arm's Jacobian rank is below 6 (µs).

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=CHECKOUT/src python fast-fail2_inpipeline.py
"""
import statistics
import time
from collections import defaultdict
from pathlib import Path

import numpy as np
import numpy.random as NR

from robodesign.design import evaluator as E, goal_planner as GP, solve as S
from robodesign.design.problem import Problem
from robodesign.model import robot as R
from robodesign.solvers import ik_kernel

ik_kernel.warm_up()
S.warm_up()
ACC = defaultdict(float)


def wrap(owner, name):
    f = getattr(owner, name)

    def timed(*a, **k):
        t = time.perf_counter()
        try:
            return f(*a, **k)
        finally:
            ACC[name] += time.perf_counter() - t
    setattr(owner, name, timed)


for o, n in [(NR, "default_rng"), (np.linalg, "svd"), (R.Robot, "reach_bound"), (R.Robot, "generic_rank"),
             (GP.GoalPlanner, "solve_ik")]:
    wrap(o, n)
f = sorted(Path("/work/main/results/tasks/profile_whitman2020_g5o5_s0_n1").glob("*.json"))[0]
problem = Problem.build(f, "robodesign_arm", "cyc")
ev = E.Evaluator(E.EvaluatorSpec(problem, seed=0))
rng = np.random.default_rng(0)
rows = []
for k in range(400):
    ACC.clear()
    e = ev.evaluate(problem.space.random_candidate(rng))
    if "independent directions" in e.message:
        d = {n: ACC.get(n, 0.0) for n in ("default_rng", "svd", "reach_bound", "generic_rank", "solve_ik")}
        st = {s["name"]: s["seconds"] for s in e.stages}
        d.update({"stage reach": st["reach"], "stage ik": st["ik"], "evaluation": e.seconds})
        rows.append(d)
print(f"{len(rows)} candidates failing the rank test")
for k in rows[0]:
    print(f"{k:14s} median {statistics.median(r[k] for r in rows) * 1e6:7.1f} µs")
