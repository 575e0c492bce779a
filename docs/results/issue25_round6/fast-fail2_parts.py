"""Where a candidate failing at IK spends its time: wrap functions with timers, evaluate random candidates of
the profile tasks (as profile_evaluator.py), and print per function the median µs per failing candidate.

    PYTHONPATH=SRC python fast-fail2_parts.py FAMILY N
"""
import statistics
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

from robodesign.design import evaluator as E, goal_planner as GP, solve as S
from robodesign.design.problem import Problem
from robodesign.formats import assembly as A
from robodesign.model import cell as C, robot as R, robot_build as RB, robot_geometry as RG
from robodesign.solvers import ik as IK, ik_kernel

ACC = defaultdict(float)


def wrap(owner, name, label):
    f = getattr(owner, name)

    def g(*a, **k):
        t = time.perf_counter()
        try:
            return f(*a, **k)
        finally:
            ACC[label] += time.perf_counter() - t
    setattr(owner, name, g)


for owner, name in [(RB, "walk"), (RB, "_model"), (R.Robot, "set_base_pose"), (R.Robot, "__init__"),
                    (A.Assembly, "_from_order"), (C.RobotPool, "give_back"), (C.RobotPool, "take"),
                    (RG.RobotGeometry, "base_collisions"), (R.Robot, "reach_bound"), (R.Robot, "generic_rank"),
                    (GP.GoalPlanner, "_tool_block"), (IK, "provably_unreachable"), (IK, "solve_ik"),
                    (RG.RobotGeometry, "set_obstacles"), (R.Robot, "set_gravity"), (S, "moving_obstacles"),
                    (R.Robot, "_build"), (RB, "finish"), (GP.GoalPlanner, "__init__"), (S, "solve")]:
    wrap(owner, name, f"{getattr(owner, '__name__', '')}.{name}")
GP.solve_ik = IK.solve_ik

fam, n = sys.argv[1], int(sys.argv[2])
ik_kernel.warm_up()
S.warm_up()
f = sorted(Path(f"/work/main/results/tasks/profile_{fam}_s0_n1").glob("*.json"))[0]
problem = Problem.build(f, "robodesign_arm", "cyc")
ev = E.Evaluator(E.EvaluatorSpec(problem, seed=0))
rng = np.random.default_rng(0)
rows = []
for k in range(n):
    c = problem.space.random_candidate(rng)
    ACC.clear()
    e = ev.evaluate(c)
    if e.stage == "ik" and k >= 10:
        st = {s["name"]: s["seconds"] for s in e.stages}
        d = dict(ACC)
        d["ev.seconds"] = e.seconds
        d["outside"] = e.seconds - sum(st.values())
        for s, v in st.items():
            d["stage " + s] = v
        rows.append(d)
print(f"{fam}: {len(rows)} failing at ik")
keys = sorted({k for r in rows for k in r}, key=lambda k: -statistics.median(r.get(k, 0) for r in rows))
for k in keys:
    v = [r.get(k, 0.0) for r in rows]
    print(f"{k:40s} median {statistics.median(v) * 1e6:8.1f} µs  mean {statistics.mean(v) * 1e6:8.1f} µs")
