"""Benchmark: wall time to turn a 6-DoF IMPROV arm and simple/PTP_3 into a checked valid solution
(no trajectory optimization, one core), and planning success over many arms and seeds.

    .venv/bin/python experiments/bench_solve.py [--arms 40] [--seeds 3]

Random valid 6-DoF arms are drawn; those whose IK fails (the arm cannot reach a goal) are counted
separately — the timing figure is over arms that reach every goal.
"""
from __future__ import annotations

import argparse
import time
from collections import Counter
from pathlib import Path

import numpy as np

from robodesign import load_module_set
from robodesign.formats.assembly import random_serial_order
from robodesign.design.solve import SolveSettings, solve
from robodesign.formats.task_io import load_task

SHARED = Path(__file__).resolve().parents[2] / "shared" / "cobra"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--arms", type=int, default=40)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    task = load_task(SHARED / "tasks" / "simple" / "PTP_3.json")
    ms = load_module_set(SHARED / "modules" / "IMPROV")
    from robodesign.solvers import ik_kernel
    ik_kernel.warm_up()  # the compiled IK from the start, also on a cold cache (no-op with ROBODESIGN_JIT=0)
    solve(task, ms, ["1", "21", "4", "22", "5", "23", "12"])  # warm-up: meshes, imports
    rng = np.random.default_rng(args.seed)
    times, stages, plan_ok, plan_all = [], Counter(), 0, 0
    per_stage = {}
    n_valid = 0
    reachable = 0
    while reachable < args.arms:
        order = random_serial_order(ms, rng, dof=6)
        first = solve(task, ms, order, settings=SolveSettings(seed=0))
        if first.stage in ("assembly", "reach", "ik", "static_torque"):
            stages[first.stage] += 1
            continue
        reachable += 1
        for s in range(args.seeds):
            t0 = time.perf_counter()
            res = solve(task, ms, order, settings=SolveSettings(seed=s))
            dt = time.perf_counter() - t0
            stages[res.stage] += 1
            for st in res.stages:
                per_stage.setdefault(st.name, []).append(st.seconds)
            if any(st.name == "plan" for st in res.stages):
                plan_all += 1
                plan_ok += any(st.name == "plan" and st.passed for st in res.stages)
            if res.feasible:
                n_valid += 1
                times.append(dt)
    t = np.array(times)
    print(f"arms reaching every goal: {reachable}; solves: {reachable * args.seeds}; checked valid: {n_valid} "
          f"({100 * n_valid / (reachable * args.seeds):.1f} %)")
    print(f"wall time to a checked valid solution: median {np.median(t) * 1e3:.0f} ms, p90 "
          f"{np.percentile(t, 90) * 1e3:.0f} ms, max {t.max() * 1e3:.0f} ms")
    print(f"planning success: {plan_ok}/{plan_all} = {100 * plan_ok / max(plan_all, 1):.1f} %")
    print("outcome counts (first failing stage or done, incl. discarded unreachable draws):", dict(stages))
    print("median stage times [ms]: " + ", ".join(f"{k} {np.median(v) * 1e3:.1f}" for k, v in per_stage.items()))


if __name__ == "__main__":
    main()
