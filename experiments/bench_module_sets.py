"""Built-in module sets on goals 1.0–1.5 m away with full orientation: what each set solves, and why not.

    nice .venv/bin/python experiments/bench_module_sets.py [--tasks 6] [--budget 30s] [--seed 0]
                                                          [--sets robodesign_arm,robodesign_heavy]
                                                          [--out docs/results/module_sets]

Part 1 prints each built-in set's reach bound (robodesign.design.reach.set_reach, default search rules) and
the time to compute it. Part 2 writes ``--tasks`` fixed-base tasks shaped like the published Whitman2020
ones that robodesign_arm fails on (issue #21): 3 reach goals, each 1.0–1.5 m from the base in a random
direction, 0.6 m below to 0.6 m above the base plane, full orientation (±1 mm, 0.5°; the tool pointing
down, tilted up to 30° and turned at random), no obstacles, joint q/τ and allGoalsFulfilled. It then runs
``robodesign optimize TASK --modules SET --optimizer genetic --cost cyc --budget B --workers 1 --json`` for
every set and task and prints one row per run: solved (best cycle time) / provably out of reach / not found,
the diagnosis, and where the candidates stopped. Part 3 (``--part reference`` or ``all``) solves every task
with one fixed reference design per set (``robodesign solve --order``: robodesign_arm's example A,
robodesign_heavy's example B, from their READMEs): does a design of the set exist, whatever the search finds?
"""
from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from robodesign.design.reach import module_set_reach
from robodesign.formats.module_io import load_module_set

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = {"robodesign_arm": "1,21,22,4,22,3,23,24,23,12", "robodesign_heavy": "1,21,22,8,24,12,25,26,25,16"}


def rot(axis: np.ndarray, angle: float) -> np.ndarray:
    axis = axis / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def make_task(path: Path, rng: np.random.Generator) -> None:
    goals = []
    for i in range(3):
        d, az, z = rng.uniform(1.0, 1.5), rng.uniform(-math.pi, math.pi), rng.uniform(-0.6, 0.6)
        z = float(np.clip(z, -0.9 * d, 0.9 * d))
        r = math.sqrt(d * d - z * z)
        T = np.eye(4)
        tilt_axis = np.array([math.cos(rng.uniform(0, 2 * math.pi)), math.sin(rng.uniform(0, 2 * math.pi)), 0.0])
        T[:3, :3] = rot(tilt_axis, rng.uniform(0, math.radians(30))) @ np.diag([1.0, -1.0, -1.0]) @ \
            rot(np.array([0.0, 0.0, 1.0]), rng.uniform(-math.pi, math.pi))
        T[:3, 3] = (r * math.cos(az), r * math.sin(az), z)
        goals.append({"ID": f"goal_{i}", "type": "reach", "goalPose": {
            "nominal": np.round(T, 12).tolist(), "toleranceProjection": ["x", "y", "z", "Theta_R"],
            "tolerance": [[-1e-3, 1e-3]] * 3 + [[0.0, math.radians(0.5)]]}})
    base = {"nominal": np.eye(4).tolist(), "toleranceProjection": ["x", "y", "z", "Theta_R"],
            "tolerance": [[-1e-3, 1e-3]] * 3 + [[0.0, math.radians(0.5)]]}
    path.write_text(json.dumps({
        "header": {"ID": f"bench/{path.stem}", "version": "2022", "taskName": path.stem, "author": ["robodesign"],
                   "affiliation": ["robodesign"], "email": [], "tags": ["bench"], "date": "2026-11-26",
                   "timeStepSize": 0.01, "gravity": [0, 0, -9.81]},
        "obstacles": [], "goals": goals,
        "constraints": [{"type": "joint", "parts": ["q", "tau"]}, {"type": "allGoalsFulfilled"},
                        {"type": "basePlacement", "pose": base}]}, indent=1))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--tasks", type=int, default=6)
    ap.add_argument("--budget", default="30s")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--sets", default="robodesign_arm,robodesign_heavy")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "results" / "module_sets")
    ap.add_argument("--part", choices=("search", "reference", "all"), default="all")
    args = ap.parse_args()
    sets = args.sets.split(",")

    print("| module set | reach bound [m] | longest order | seconds |\n|---|---|---|---|")
    for name in sets:
        ms = load_module_set(name)
        t0 = time.perf_counter()
        r = module_set_reach(ms)
        print(f"| {name} | {r.bound:.3f} | {','.join(r.order)} | {time.perf_counter() - t0:.3f} |")

    args.out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(args.seed)
    tasks = []
    for i in range(args.tasks):
        f = args.out / f"far_goals_s{args.seed}_{i:02d}.json"
        make_task(f, rng)
        tasks.append(f)
    if args.part in ("reference", "all"):
        reference(args, tasks, sets)
    if args.part == "reference":
        return 0
    rows = []
    print("\n| task | module set | result | cyc [s] | evaluations | stopped at (failures per stage) | diagnosis |\n"
          "|---|---|---|---|---|---|---|")
    for f in tasks:
        for name in sets:
            cmd = [sys.executable, "-m", "robodesign.cli", "optimize", str(f), "--modules", name, "--optimizer",
                   "genetic", "--cost", "cyc", "--budget", args.budget, "--workers", "1", "--seed", str(args.seed),
                   "--json", "--out", str(args.out / f"{f.stem}_{name}_best.json")]
            p = subprocess.run(cmd, capture_output=True, text=True)
            out = json.loads(p.stdout)
            d = out.get("diagnosis") or {}
            cyc = out["best"]["cost"] if out["feasible"] else None
            row = {"task": f.stem, "set": name, "result": d.get("label", "?"), "cyc": cyc,
                   "evaluations": out["evaluations"], "stage_counts": out.get("stage_counts") or {},
                   "diagnosis": "" if out["feasible"] else d.get("message", "")}
            rows.append(row)
            counts = ", ".join(f"{k} {v}" for k, v in sorted(row["stage_counts"].items(), key=lambda kv: -kv[1]))
            print(f"| {f.stem} | {name} | {row['result']} | {'' if cyc is None else f'{cyc:.2f}'} | "
                  f"{row['evaluations']} | {counts} | {row['diagnosis'][:160]} |", flush=True)
    (args.out / "runs.json").write_text(json.dumps(rows, indent=1))
    print()
    for name in sets:
        mine = [r for r in rows if r["set"] == name]
        solved = [r for r in mine if r["result"] == "solved"]
        torque = sum("torque-infeasible" in r["diagnosis"] for r in mine)
        med = float(np.median([r["cyc"] for r in solved])) if solved else math.nan
        print(f"{name}: solved {len(solved)}/{len(mine)}, provably out of reach "
              f"{sum(r['result'] == 'provably out of reach' for r in mine)}, torque-infeasible {torque}, "
              f"median cycle time {med:.2f} s")
    return 0


def reference(args, tasks, sets) -> None:
    print("\n| task | module set | reference order | result | cyc [s] | stage | message |\n|---|---|---|---|---|---|---|")
    solved = {name: 0 for name in sets}
    for f in tasks:
        for name in sets:
            order = REFERENCE.get(name)
            if order is None:
                continue
            cmd = [sys.executable, "-m", "robodesign.cli", "solve", str(f), "--modules", name, "--order", order,
                   "--cost", "cyc", "--seed", str(args.seed), "--json", "--out", str(args.out / f"{f.stem}_{name}_ref.json")]
            out = json.loads(subprocess.run(cmd, capture_output=True, text=True).stdout)
            ok = bool(out.get("feasible"))
            solved[name] += ok
            print(f"| {f.stem} | {name} | {order} | {'valid' if ok else 'no solution'} | "
                  f"{out['cost']:.2f} | done | |" if ok else
                  f"| {f.stem} | {name} | {order} | no solution | | {out.get('stage', '')} | "
                  f"{str(out.get('message', ''))[:120]} |", flush=True)
    print()
    for name, k in solved.items():
        print(f"{name} reference design: valid on {k}/{len(tasks)} tasks")


if __name__ == "__main__":
    sys.exit(main())
