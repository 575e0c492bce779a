"""Benchmark: how many IK solutions per goal should the sequencing choose from?

    .venv/bin/python experiments/bench_ik_choice.py [--arms 8] [--seeds 10] [--solutions 4,16,48,96] [--restarts 150]

For each task (simple/PTP_3 with IMPROV, robodesign/base_placement with robodesign_arm) random valid
arms that reach every goal are drawn (6 joints for IMPROV, 6 and 7 alternately for robodesign_arm). Each arm is
solved with every ``--solutions`` setting (``SolveSettings.ik_solutions``), each ``--restarts`` setting
(``ik_restarts``, LM restarts per goal: the evaluator's 150 by default) and ``--seeds`` seeds, the evaluator's
settings otherwise. Per setting: how often the solve ends in a checked valid solution, the cycle time relative to
the best cycle time any setting found for that arm (median over arms of the median over seeds, and the
median over arms of the worst seed), and the mean wall and CPU time per solve.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from robodesign import load_module_set
from robodesign.core.paths import project_root
from robodesign.design.evaluator import evaluation_settings
from robodesign.design.solve import solve
from robodesign.formats.assembly import random_serial_order
from robodesign.formats.task_io import load_task

SHARED = Path(__file__).resolve().parents[2] / "shared" / "cobra"
# (name, task file, module set, joint counts of the drawn arms, used in turn)
TASKS = [("simple/PTP_3", SHARED / "tasks" / "simple" / "PTP_3.json", str(SHARED / "modules" / "IMPROV"), (6,)),
         ("robodesign/base_placement", project_root() / "assets" / "tasks" / "robodesign" / "base_placement.json",
          "robodesign_arm", (6, 7))]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--arms", type=int, default=8)
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--solutions", default="4,16,48,96")
    ap.add_argument("--restarts", default="150", help="LM restarts per goal (comma-separated)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    settings = [(int(r), int(k)) for r in args.restarts.split(",") for k in args.solutions.split(",")]
    print(f"{args.arms} arms per task, {args.seeds} seeds per arm and setting")
    for name, task_file, modules, dofs in TASKS:
        task, ms = load_task(task_file), load_module_set(modules)
        rng = np.random.default_rng(args.seed)
        arms = []
        while len(arms) < args.arms:
            order = random_serial_order(ms, rng, dof=dofs[len(arms) % len(dofs)])
            if solve(task, ms, order, settings=evaluation_settings(seed=0, stop_after="ik")).stage == "done":
                arms.append(order)
        cyc = np.full((len(settings), len(arms), args.seeds), np.nan)
        secs, cpu = np.zeros(len(settings)), np.zeros(len(settings))
        for si, (restarts, k) in enumerate(settings):
            t0, c0 = time.perf_counter(), time.process_time()
            for ai, order in enumerate(arms):
                for s in range(args.seeds):
                    r = solve(task, ms, order, cost="cyc",
                              settings=evaluation_settings(seed=s, ik_solutions=k, ik_restarts=restarts))
                    if r.feasible:
                        cyc[si, ai, s] = r.cost
            secs[si] = (time.perf_counter() - t0) / (len(arms) * args.seeds)
            cpu[si] = (time.process_time() - c0) / (len(arms) * args.seeds)
        per_arm = cyc.transpose(1, 0, 2).reshape(len(arms), -1)
        never = ~np.isfinite(per_arm).any(axis=1)
        best = np.full(len(arms), np.nan)
        best[~never] = np.nanmin(per_arm[~never], axis=1)
        print(f"\n{name} ({modules.split('/')[-1]}), arms: " + "; ".join(",".join(a) for a in arms))
        if never.any():
            print(f"{int(never.sum())} arm(s) never ended in a checked valid solution (left out of the ratios)")
        print("| IK restarts | IK solutions per goal | checked valid | cycle time / arm's best: median "
              "| worst seed (median over arms) | s per solve | CPU s per solve |")
        print("|---|---|---|---|---|---|---|")
        for si, (restarts, k) in enumerate(settings):
            valid = np.isfinite(cyc[si])
            rel = [c / b for c, b, ok in zip(cyc[si], best, valid) if ok.any()]
            med = np.median([np.nanmedian(r) for r in rel])
            worst = np.median([np.nanmax(r) for r in rel])
            print(f"| {restarts} | {k} | {100 * valid.mean():.0f} % | {med:.3f} | {worst:.3f} | {secs[si]:.3f} "
                  f"| {cpu[si]:.3f} |", flush=True)


if __name__ == "__main__":
    main()
