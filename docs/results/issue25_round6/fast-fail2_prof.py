"""cProfile of random candidates on a profile task (the evaluator of profile_evaluator.py), failing ones kept.

    PYTHONPATH=SRC python fast-fail2_prof.py FAMILY N [sort]
"""
import cProfile
import pstats
import sys
from pathlib import Path

import numpy as np

from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel

fam, n = sys.argv[1], int(sys.argv[2])
sort = sys.argv[3] if len(sys.argv) > 3 else "tottime"
ik_kernel.warm_up()
warm_up()
f = sorted(Path(f"/work/main/results/tasks/profile_{fam}_s0_n1").glob("*.json"))[0]
problem = Problem.build(f, "robodesign_arm", "cyc")
ev = Evaluator(EvaluatorSpec(problem, seed=0))
rng = np.random.default_rng(0)
cands = [problem.space.random_candidate(rng) for _ in range(n)]
for c in cands[:20]:
    ev.evaluate(c)
pr = cProfile.Profile()
stages = {}
pr.enable()
for c in cands[20:]:
    e = ev.evaluate(c)
    stages[e.stage] = stages.get(e.stage, 0) + 1
pr.disable()
print(stages)
pstats.Stats(pr).sort_stats(sort).print_stats(45)
