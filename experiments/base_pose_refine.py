"""Same robot, better base: how much cycle time does the base pose alone save for the best module orders?

    .venv/bin/python experiments/base_pose_refine.py [--results docs/results/base_pose] [--designs 5]
                                                     [--budget 80] [--seed 0]

Reads a finished ``configs/base_pose.yaml`` run, takes the ``--designs`` best distinct module orders that
the *modules-only* runs found (base at the task's nominal pose), and for each order searches the base pose
alone — x, y and yaw inside the task's base-placement tolerance — with the ``base_pose`` optimizer plugin
(TPE, nominal base first) for ``--budget`` evaluations. Every evaluation is the evaluator's full pipeline with a checked solution (the
same settings as the study).

Planning is randomised, so a search that evaluates a robot many times also draws many planner seeds. The
control therefore gets the same number of draws: the nominal base is evaluated ``--budget`` times with
different evaluator seeds, and the saving compares the best of those with the best of the base search —
what is left is what the base pose itself is worth. Writes ``base_refine.json`` and ``base_refine.md``
into the results folder.
"""
from __future__ import annotations

import argparse
import json
import sqlite3
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.optimize import Budget, SerialExecutor, Study, create_optimizer
from robodesign.core.paths import project_root
from robodesign.design.problem import Problem
from robodesign.design.search_space import BASE_PARAMS, Candidate

HERE = Path(__file__).resolve().parent
RESULTS = HERE.parent / "docs" / "results"  # the measured records behind docs/benchmarks.md


def _f(x):
    return "—" if x is None else f"{x:.3g}"


def best_orders(db: Path, run_task: str, k: int):
    con = sqlite3.connect(db)
    rows = con.execute("SELECT e.module_order, MIN(e.cost) FROM evaluations e JOIN runs r USING (run_id) "
                       "WHERE r.task = ? AND e.feasible = 1 AND e.cost IS NOT NULL GROUP BY e.module_order "
                       "ORDER BY MIN(e.cost) LIMIT ?", (run_task, k)).fetchall()
    con.close()
    return [(json.loads(o), c) for o, c in rows]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--results", default=str(RESULTS / "base_pose"))
    ap.add_argument("--designs", type=int, default=5)
    ap.add_argument("--budget", type=int, default=80)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    res_dir = Path(args.results)
    meta = json.loads((res_dir / "meta.json").read_text())
    task_file = project_root() / "assets" / "tasks" / "robodesign" / "base_placement.json"
    settings = meta.get("solve") or {}
    from robodesign.design.solve import SolveSettings
    problem = Problem.build(task_file, "robodesign_arm", "cyc")
    spec = EvaluatorSpec(problem, seed=args.seed)
    if settings:
        known = set(SolveSettings.__dataclass_fields__)
        spec = replace(spec, settings=SolveSettings(**{k: v for k, v in settings.items() if k in known}))
    ev = Evaluator(spec)
    space = problem.space
    free = problem.base_bounds.free
    names = BASE_PARAMS
    out = []
    for order, study_cost in best_orders(res_dir / "evaluations.sqlite", "modules_only", args.designs):
        t0 = time.perf_counter()
        # the control: nominal base, as many planner seeds as the base search has evaluations
        nominal_runs = []
        for k in range(args.budget):
            nominal_runs.append(Evaluator(replace(spec, seed=args.seed + k)).evaluate(Candidate(tuple(order))))
        nominal_costs = [e.cost for e in nominal_runs if e.feasible]
        nominal = min((e for e in nominal_runs if e.feasible), key=lambda e: e.cost, default=nominal_runs[0])
        # the search: the base_pose plugin (TPE over the free base parameters, nominal base first)
        dof = sum(space.module_info(m).dof for m in order)
        sub = problem.with_(rules={"min_dof": dof, "max_dof": dof, "max_links_between": space.max_modules})
        opt = create_optimizer("base_pose", sub, seed=args.seed, options={"order": order})
        hist = Study(opt, SerialExecutor(ev), Budget(evaluations=args.budget)).run().history
        feasible = sum(e.feasible for e in hist)
        best = min((e for e in hist if e.feasible), key=lambda e: e.cost, default=None)
        row = {"order": order, "study_best_cyc": study_cost,
               "nominal_cyc": nominal.cost if nominal.feasible else None,
               "nominal_cyc_median": float(np.median(nominal_costs)) if nominal_costs else None,
               "nominal_feasible": len(nominal_costs),
               "best_cyc": best.cost if best is not None else None,
               "best_base": dict(zip([names[i] for i in free], best.candidate.base))
               if best is not None and best.candidate.base else {},
               "evaluations": args.budget, "feasible": feasible, "seconds": round(time.perf_counter() - t0, 1)}
        if row["nominal_cyc"] and row["best_cyc"]:
            row["saving"] = 1.0 - row["best_cyc"] / row["nominal_cyc"]
        out.append(row)
        print(f"{','.join(order)}: nominal base {_f(row['nominal_cyc'])} s (best of {args.budget} seeds) -> "
              f"best base {_f(row['best_cyc'])} s "
              f"({100 * row.get('saving', 0) + 0.0:.1f} % less) in {row['seconds']} s", flush=True)
    (res_dir / "base_refine.json").write_text(json.dumps({"designs": out, "budget": args.budget, "seed": args.seed},
                                                         indent=1))
    lines = ["# Same robot, better base", "",
             f"The {len(out)} best module orders of the modules-only runs; base pose alone searched with TPE, "
             f"{args.budget} evaluations each (`experiments/base_pose_refine.py`). Control: the nominal base "
             f"evaluated with {args.budget} planner seeds (the same number of draws); saving = 1 − best base / "
             "best nominal. Costs in seconds.", "",
             "| module order | study | nominal base: best [median] of seeds | best base (TPE) | saving | "
             "best base offsets (m, rad) |", "|---|---|---|---|---|---|"]
    for r in out:
        bb = ", ".join(f"{k} {v:+.3f}" for k, v in r["best_base"].items()) or "nominal"
        sav = f"{100 * r['saving'] + 0.0:.1f} %" if "saving" in r else "—"
        lines.append(f"| `{','.join(r['order'])}` | {_f(r['study_best_cyc'])} | {_f(r['nominal_cyc'])} "
                     f"[{_f(r['nominal_cyc_median'])}] | {_f(r['best_cyc'])} | {sav} | {bb} |")
    savings = [r["saving"] for r in out if "saving" in r]
    if savings:
        lines += ["", f"Median saving {100 * float(np.median(savings)) + 0.0:.1f} % "
                      f"(range {100 * min(savings) + 0.0:.1f} % to {100 * max(savings):.1f} %)."]
    (res_dir / "base_refine.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
