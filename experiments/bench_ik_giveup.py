"""Benchmark: the cost of giving up on an IK goal (every restart runs), per goal and per LM iteration.

    nice .venv/bin/python experiments/bench_ik_giveup.py [--task GLOB] [--pairs 20] [--restarts 150] [--repeat 9]

(arm, goal) pairs: random candidates of the task's default search space with the built-in set (seeded),
kept when ``solve_ik`` (no collision checks, the reach bounds off, 150 restarts) fails on the task's first
goal; each pair is then solved again with another seed, best of ``--repeat`` rounds (the machine is shared).
Default task: the first generated BPO24 task of experiments/profile_evaluator.py (results/tasks/, generated
there). Prints ms per goal and ns per LM iteration; run the script of two checkouts alternately to compare
them (an older checkout without ``reach_bounds`` runs with its sphere bound, which these pairs pass).
"""
from __future__ import annotations

import argparse
import glob
import inspect
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from robodesign.core.errors import RobodesignError  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.formats.assembly import Assembly  # noqa: E402
from robodesign.model.cell import build_robot  # noqa: E402
from robodesign.solvers import ik_kernel  # noqa: E402
from robodesign.solvers.ik import solve_ik  # noqa: E402
from robodesign.solvers.schedule import static_cell  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--task", default=str(ROOT / "results" / "tasks" / "profile_bpo2024_s0_n2" / "*.json"))
    ap.add_argument("--pairs", type=int, default=20)
    ap.add_argument("--restarts", type=int, default=150)
    ap.add_argument("--repeat", type=int, default=9)
    args = ap.parse_args()
    if not ik_kernel.warm_up():
        print("note: the Python IK loop runs (ROBODESIGN_JIT=0 or no numba)")
    kw = {"reach_bounds": False} if "reach_bounds" in inspect.signature(solve_ik).parameters else {}
    p = Problem.build(sorted(glob.glob(args.task))[0], "robodesign_arm", "cyc")
    goal = p.task.goals[0].pose
    rng = np.random.default_rng(0)
    pairs = []
    while len(pairs) < args.pairs:
        c = p.space.random_candidate(rng)
        try:
            robot = build_robot(static_cell(p.task), p.module_set, Assembly.from_order(p.module_set, list(c.order)),
                                p.base_pose(c))
        except RobodesignError:
            continue
        r = solve_ik(robot, goal, 0, max_restarts=args.restarts, check_collision=False, **kw)
        if not r.success and r.stats["reason"] == "max_restarts":
            pairs.append(robot)
    rounds = []
    for _ in range(args.repeat):
        t = time.perf_counter()
        its = 0
        for robot in pairs:
            its += solve_ik(robot, goal, 1, max_restarts=args.restarts, check_collision=False, **kw).stats["iterations"]
        rounds.append(time.perf_counter() - t)
    best = min(rounds) / len(pairs)
    print(f"giving up after {args.restarts} restarts: best {best * 1e3:.2f} ms, median "
          f"{np.median(rounds) / len(pairs) * 1e3:.2f} ms per goal; {its / len(pairs):.0f} LM iterations per goal "
          f"-> {best / (its / len(pairs)) * 1e9:.0f} ns per iteration")


if __name__ == "__main__":
    main()
