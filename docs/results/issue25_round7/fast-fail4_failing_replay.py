"""fast-fail4's replay of the candidates that fail at IK, split by reason: 1,500 random candidates of
profile_evaluator's first generated task of family FAM (whitman2020_g5o5 or bpo2024) are evaluated once; those
that fail at IK are evaluated again on a new robot pool, timed (CPU), and grouped by their message (the goal id
and numbers masked). Prints the overall median CPU ms, then per reason: count, median CPU ms, stage medians.
SRC: the checkout whose src/ is evaluated (run from /work/main)."""
import os
import re
import sys
import time
from collections import defaultdict

SRC = os.environ.get("SRC", "/work/h-fast-fail4")
sys.argv = ["x", "--src", SRC]   # (profile_evaluator puts SRC's src/ first on the path when imported)
sys.path.insert(0, "experiments")
import numpy as np  # noqa: E402
import profile_evaluator as pe  # noqa: E402

import robodesign  # noqa: E402
from robodesign.design import solve as S  # noqa: E402
from robodesign.design.evaluator import Evaluator, EvaluatorSpec  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.model import cell  # noqa: E402
from robodesign.solvers import ik_kernel  # noqa: E402


def reason(message: str) -> str:
    """The failure message with the goal id and the numbers masked (the first 70 characters)."""
    m = re.sub(r"goal \S+", "goal G", message)
    return re.sub(r"\d+(\.\d+)?", "#", m)[:70]


def median(xs):
    """The upper median of ``xs``."""
    xs = sorted(xs)
    return xs[len(xs) // 2]


def main() -> None:
    print(robodesign.__file__)
    ik_kernel.warm_up()
    S.warm_up()
    task = pe.family_tasks(os.environ.get("FAM", "whitman2020_g5o5"), 1, 0)[0]
    problem = Problem.build(task, "robodesign_arm", "cyc")
    ev = Evaluator(EvaluatorSpec(problem, seed=0))
    rng = np.random.default_rng(0)
    cands = [problem.space.random_candidate(rng) for _ in range(1500)]
    failing = [c for c in cands if ev.evaluate(c).stage == "ik"]
    S._POOLS.clear()
    cell._SPARE.clear()
    cpu = defaultdict(list)
    stages = defaultdict(lambda: defaultdict(list))
    for c in failing:
        t = time.process_time()
        e = ev.evaluate(c)
        dt = time.process_time() - t
        cpu[reason(e.message)].append(dt)
        for s in e.stages:
            stages[reason(e.message)][s["name"]].append(s["seconds"])
    every = [x for v in cpu.values() for x in v]
    print("n", len(every), "median CPU ms %.3f" % (median(every) * 1e3))
    for m, v in sorted(cpu.items(), key=lambda kv: -len(kv[1])):
        print(len(v), "%.2f" % (median(v) * 1e3), m, {k: round(median(x) * 1e3, 2) for k, x in stages[m].items()})


if __name__ == "__main__":
    main()
