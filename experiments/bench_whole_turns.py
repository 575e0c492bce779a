"""Whole turns: how often the plan stage reaches every goal with the IK solutions in one sheet of whole turns
(``solve_ik(canonical=True)``, the default, plus the plan fallback's one-joint turn variants) and without
(the restarts' own sheets, no turn variants), on the same designs.

    .venv/bin/python experiments/bench_whole_turns.py [--tasks GLOB ...] [--designs 3] [--max-candidates 200]

For each task, informed candidates of robodesign_heavy (seeded) are drawn until ``--designs`` of them pass the
IK and static-torque stages in both variants (at most ``--max-candidates``); each such design runs the plan
stage in both variants (seed 0, plan_time 1 s). Prints and writes (docs/results/whole_turns.json) the designs
whose plan stage passed, per variant and family.
"""
from __future__ import annotations

import argparse
import glob
import json
import time
from pathlib import Path

import numpy as np

import robodesign.solvers.ik as ik_module
from robodesign.design.problem import Problem
from robodesign.design.solve import SolveSettings, solve, warm_up
from robodesign.model.robot import Robot

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "results"


def run_variant(pr, cand, canonical: bool):
    real_solve_ik, real_variants = ik_module.solve_ik, Robot.turn_variants

    def solve_ik(*a, **k):
        k.setdefault("canonical", canonical)
        return real_solve_ik(*a, **k)
    ik_module.solve_ik = solve_ik
    if not canonical:
        Robot.turn_variants = lambda self, q: []
    try:
        t = time.perf_counter()
        r = solve(pr.task, pr.module_set, list(cand.order), pr.base_bounds.pose(cand.base), "cyc",
                  SolveSettings(stop_after="plan"))
        return r.stage, r.message, time.perf_counter() - t
    finally:
        ik_module.solve_ik, Robot.turn_variants = real_solve_ik, real_variants


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="+", default=[str(ROOT / "results" / "tasks" / "whitman2020_g5o5_free_s1_n50" / "*.json"),
                                                    str(ROOT / "results" / "tasks" / "liu2020_published_s1_n50" / "*.json")])
    ap.add_argument("--count", type=int, default=12, help="tasks per glob (the first ones in name order)")
    ap.add_argument("--designs", type=int, default=3)
    ap.add_argument("--max-candidates", type=int, default=200)
    ap.add_argument("--out", default=str(RESULTS / "whole_turns.json"))
    args = ap.parse_args()
    warm_up()
    rows = []
    for pattern in args.tasks:
        for path in sorted(glob.glob(pattern))[: args.count]:
            pr = Problem.build(path, "robodesign_heavy", "cyc")
            rng = np.random.default_rng(0)
            found = 0
            for _ in range(args.max_candidates):
                cand = pr.space.informed_candidate(rng)
                new = run_variant(pr, cand, True)
                if new[0] in ("reach", "base", "assembly"):
                    continue
                old = run_variant(pr, cand, False)
                if new[0] in ("ik", "static_torque") or old[0] in ("ik", "static_torque"):
                    continue
                found += 1
                rows.append({"task": Path(path).name, "design": cand.key(), "new": new[0], "old": old[0],
                             "new_s": round(new[2], 2), "old_s": round(old[2], 2), "new_msg": new[1][:120],
                             "old_msg": old[1][:120]})
                print(f"{Path(path).name[:50]}: one sheet -> {new[0]}, own sheets -> {old[0]}", flush=True)
                if found >= args.designs:
                    break
    fam = {}
    for r in rows:
        f = r["task"].split("_s1_")[0]
        d = fam.setdefault(f, {"designs": 0, "plan_passed_one_sheet": 0, "plan_passed_own_sheets": 0})
        d["designs"] += 1
        d["plan_passed_one_sheet"] += r["new"] == "done"
        d["plan_passed_own_sheets"] += r["old"] == "done"
    out = {"command": "experiments/bench_whole_turns.py " + " ".join(f"--{k.replace('_', '-')} {v}" for k, v in
                                                                    vars(args).items() if k != "tasks"),
           "families": fam, "rows": rows}
    Path(args.out).write_text(json.dumps(out, indent=1))
    print(json.dumps(fam, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
