# Usage (from /work/main): PYTHONPATH=<checkout>/src .venv/bin/python fast-ask_record_sample_base.py oven_hard  (writes /tmp/fa/calls_<task>.pkl)
"""Record every sample_base call (rng state before, order, result, state after) and count robot adoptions."""

import copy
import pickle
import sys

sys.path.insert(0, "/work/main/experiments")
from robodesign.solvers import ik_kernel

ik_kernel.warm_up()
from robodesign.design.solve import warm_up

warm_up()
from profile_evaluator import family_tasks

from robodesign.design import search_space as ssm
from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
from robodesign.design.optimize import Budget, SerialExecutor, Study, create_optimizer
from robodesign.design.problem import Problem
from robodesign.model import cell

task = sys.argv[1]
fam = "whitman2020_g5o5" if "whitman" in task else "bpo2024"
f = next(f for f in family_tasks(fam, 2, 0) if task in f.name)
problem = Problem.build(f, "robodesign_arm", "cyc")
ev = Evaluator(EvaluatorSpec(problem, evaluation_settings(), seed=0))
opt = create_optimizer("genetic", problem, seed=0, options={})
calls = []
orig = ssm.SearchSpace.sample_base


def rec(self, rng, order, tries=64):
    s0 = copy.deepcopy(rng.bit_generator.state)
    out = orig(self, rng, order, tries)
    calls.append((s0, tuple(order), out, copy.deepcopy(rng.bit_generator.state)))
    return out


ssm.SearchSpace.sample_base = rec
n = {"built": 0, "adopted": 0}
kr, ad = cell.kinematic_robot, cell._adopt


def kr2(*a, **k):
    n["built"] += 1
    return kr(*a, **k)


def ad2(*a, **k):
    r = ad(*a, **k)
    n["adopted"] += r is not None
    return r


cell.kinematic_robot, cell._adopt = kr2, ad2
res = Study(opt, SerialExecutor(ev), Budget.parse("200evals"), batch_size=16).run()
print(task, n, "sample_base calls", len(calls))
pickle.dump(
    {"space": problem.space if hasattr(problem, "space") else opt.space, "calls": calls},
    open(f"/tmp/fa/calls_{task}.pkl", "wb"),
)
