"""The parts this branch changed, timed alone on 150 robots of random valid candidates of the whitman2020 profile
task (as profile_evaluator draws them), each at its candidate's base pose: µs per robot, the best and the median of
7 passes (run once per checkout, alternating: PYTHONPATH=CHECKOUT/src python fast-fail2_micro.py).

* generic_rank (reach bound cached), reach_bound, ChainBounds (reach bound cached).
"""
import statistics
import time
from pathlib import Path

import numpy as np

from robodesign.design.problem import Problem
from robodesign.formats.assembly import Assembly
from robodesign.model.robot import Robot
from robodesign.solvers import ik as IK

f = sorted(Path("/work/main/results/tasks/profile_whitman2020_g5o5_s0_n1").glob("*.json"))[0]
problem = Problem.build(f, "robodesign_arm", "cyc")
ms = problem.module_set
rng = np.random.default_rng(0)
robots = []
while len(robots) < 150:
    c = problem.space.random_candidate(rng)
    try:
        robots.append(Robot(ms, Assembly.from_order(ms, list(c.order)), base_pose=problem.base_pose(c)))
    except Exception:   # noqa: BLE001 - an order that does not assemble
        pass


def bench(label, fn, reps=7):
    ts = []
    for _ in range(reps):
        t = time.process_time()
        for r in robots:
            fn(r)
        ts.append((time.process_time() - t) / len(robots) * 1e6)
    print(f"{label:28s} best {min(ts):7.1f} µs  median {statistics.median(ts):7.1f} µs")


def reach(r):
    r._reach = None
    r.reach_bound()


def rank(r):
    r._generic_rank = None
    r.generic_rank()


bench("reach_bound", reach)
bench("generic_rank", rank)
bench("ChainBounds", lambda r: IK.ChainBounds(r))
