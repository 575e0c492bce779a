"""Generated task families, solved by `robodesign optimize`: checked-valid share and best cycle times per
family, for the built-in module set and the IMPROV set, against the Mayer & Althoff 2024 anchors.

For every family variant, ``--count`` tasks are generated (seeded; robodesign.generate, into
results/tasks/<variant>_s<seed>_n<count>, shared with configs/*.yaml) and each task is given to

    robodesign optimize TASK --modules SET --optimizer genetic --cost cyc --budget 60s --seed 0 --workers 1 --json

(modules + base pose: the base is searched within the task's basePlacement tolerance), whose best
solution is re-checked with `robodesign check`. Tasks are run round-robin (task 0 of every variant and set,
then task 1, ...), so a cut-off run still covers every family evenly. Every finished task is appended to
``runs.jsonl`` at once (a kill loses at most the tasks in flight; a re-run skips what is there) and
``runs.csv``, ``summary.json`` and ``summary.md`` are rewritten.

Run it on the shared machine as (at most 2 tasks at a time, lower priority)::

    flock /tmp/robodesign-bench.lock nice -n 5 .venv/bin/python experiments/bench_families.py --jobs 2

Per family and module set it prints: tasks run, checked-valid %, median/min/max best cycle time, the
median's ratio to the anchor (target ≤ 0.5; built-in set ≥ 95 % valid) and, for the failures, the stage
that stopped every candidate (experiment/suites.py).
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from robodesign.experiment.config import SuiteEntry, suite_task_files  # noqa: E402
from robodesign.experiment.suites import SuiteRecord, cell, stage_counts_text, summarize_suites  # noqa: E402

# variant → (generator family, option sets (the tasks are spread evenly over them), Mayer & Althoff 2024
# median best cycle time [s], their setting)
VARIANTS = {
    # the published families (issue 21): the generators' default, published variant
    "whitman2020_g3o3_fixed": ("whitman2020", [{"goals": 3, "obstacles": 3, "base": "fixed"}], 8.8,
                               "Whitman 3 goals / 3 obstacles, fixed base, full-pose goals (±1 mm, 0.5°)"),
    "whitman2020_g3o3_free": ("whitman2020", [{"goals": 3, "obstacles": 3, "base": "xyz_any_rot"}], 8.8,
                              "Whitman 3 goals / 3 obstacles, base free ±1 m, any rotation, full-pose goals"),
    "whitman2020_g5o5_free": ("whitman2020", [{"goals": 5, "obstacles": 5, "base": "xyz_any_rot"}], 18.9,
                              "Whitman 5 goals / 5 obstacles, base free ±1 m, any rotation, full-pose goals"),
    "liu2020_published": ("liu2020", [{"machine": "<cobra>/tasks/assets/QUASER_MV205_v3_compressed.stl"}], 12.0,
                          "Liu case 2b, QUASER MV205 mesh, full-pose goals in order, base free ±1 m"),
    "bpo2024_edge": ("bpo2024", [{}], 11.4,
                     "BPO24 edge cases: 10 archetypes, medium/hard shifts, full-pose goals, base free ±1 m"),
    # the earlier easy variants (docs/generators.md, --variant easy): the table of 2026-11-25
    "whitman2020_g3o3": ("whitman2020", [{"variant": "easy", "goals": 3, "obstacles": 3, "base": "xyz_any_rot"}], 8.8,
                         "easy variant: Whitman 3 goals / 3 obstacles, free base"),
    "whitman2020_g5o5": ("whitman2020", [{"variant": "easy", "goals": 5, "obstacles": 5, "base": "xyz_any_rot"}], 18.9,
                         "easy variant: Whitman 5 goals / 5 obstacles, free base"),
    "liu2020": ("liu2020", [{"variant": "easy", "machine": "<cobra>/tasks/assets/QUASER_MV205_v3_compressed.stl"}],
                12.0, "easy variant: Liu case 2b (machine tending), QUASER MV205 mesh of the CoBRA data"),
    "bpo2024": ("bpo2024", [{"variant": "easy", "structure": "mixed", "difficulty": "mixed"}], 11.4,
                "easy variant: x, cross, house, oven, random field by task index, 5 easy / 5 medium / 5 hard"),
}
PUBLISHED = ("whitman2020_g3o3_fixed", "whitman2020_g3o3_free", "whitman2020_g5o5_free", "liu2020_published",
             "bpo2024_edge")
COBRA = ROOT.parent / "shared" / "cobra"  # the CoBRA reference data beside the checkout (--cobra)
SETS = {"builtin": "robodesign_arm", "heavy": "robodesign_heavy", "IMPROV": "<cobra>/modules/IMPROV"}
FIELDS = ("variant", "family", "set", "task", "index", "valid", "cyc", "verdict", "stopped_at", "stage_counts",
          "evaluations", "first_feasible_s", "optimize_s", "budget_overrun", "exit_optimize", "exit_check", "message",
          "finished")


def _rd() -> list:
    exe = Path(sys.executable).with_name("robodesign")
    return [str(exe)] if exe.is_file() else [sys.executable, "-m", "robodesign.cli"]


def task_files(variant: str, count: int, seed: int) -> list:
    """``count`` task files of a variant, generated on first use (robodesign.experiment.config's suite
    folders: deterministic, recorded in .suite.json), interleaved over its option sets."""
    family, option_sets, _, _ = VARIANTS[variant]
    per = -(-count // len(option_sets))
    blocks = [{"family": family, "count": per, "seed": seed,
               "options": {k: v.replace("<cobra>", str(COBRA)) if isinstance(v, str) else v for k, v in o.items()}}
              for o in option_sets]
    su = SuiteEntry.model_validate({"name": variant, "generate": blocks,
                                    "folder": str(ROOT / "results" / "tasks" / f"{variant}_s{seed}_n{count}")})
    files = suite_task_files(su, ROOT, "bench_families", ["suites", 0])
    return [files[b * per + k] for k in range(per) for b in range(len(blocks))][:count]


def run_task(variant: str, set_name: str, index: int, task: Path, out: Path, budget: str, optimizer: str,
             seed: int, workers: int = 1) -> dict:
    sol = out / "solutions" / variant / set_name / f"{task.stem}.json"
    sol.parent.mkdir(parents=True, exist_ok=True)
    # a task killed in flight (not in runs.jsonl) left its search's journal, which optimize would refuse to start
    # over ("use --resume"): the task is searched afresh, as if it had never started (a resumed time budget would
    # not be the budget of the other tasks)
    for stale in sol.parent.glob(f"{task.stem}.journal.sqlite*"):
        stale.unlink()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src"), str(ROOT / "optimizers"),
                                                        os.environ.get("PYTHONPATH", "")]))
    t0 = time.perf_counter()
    cmd = _rd() + ["optimize", str(task), "--modules", SETS[set_name], "--optimizer", optimizer, "--cost", "cyc",
                   "--budget", budget, "--seed", str(seed), "--workers", str(workers), "--out", str(sol), "--json"]
    seconds = float(budget.rstrip("s")) if budget.endswith("s") and budget[:-1].replace(".", "").isdigit() else 600
    row = {"variant": variant, "family": VARIANTS[variant][0], "set": set_name, "task": task.stem, "index": index,
           "valid": False, "cyc": None, "stopped_at": "", "stage_counts": "", "evaluations": 0,
           "first_feasible_s": None, "exit_check": None, "message": ""}
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=seconds + 300)
        row["exit_optimize"] = p.returncode
        res = json.loads(p.stdout.strip().splitlines()[-1]) if p.stdout.strip() else {}
    except subprocess.TimeoutExpired:
        row.update(exit_optimize=None, stopped_at="timeout", message="robodesign optimize did not return")
        res = {}
    except ValueError:
        res = {}
        row["message"] = (p.stderr.strip().splitlines() or ["no JSON output"])[-1][:300]
    row["optimize_s"] = round(time.perf_counter() - t0, 2)
    if res:
        row["evaluations"] = res.get("evaluations", 0)
        row["first_feasible_s"] = res.get("first_feasible_seconds")
        row["stopped_at"] = res.get("stopped_at") or ""
        diag = res.get("diagnosis") or {}
        row["verdict"] = "solved" if res.get("feasible") else (diag.get("verdict") or "")
        row["diagnosis"] = (diag.get("message") or "")[:300]
        row["reach_bound"] = diag.get("reach_bound")
        row["budget_overrun"] = res.get("budget_overrun")
        row["stage_counts"] = stage_counts_text(res.get("stage_counts") or {})
        if not res.get("feasible") and res.get("best"):
            row["message"] = f"best candidate failed at {res['best'].get('stage')}: {res['best'].get('message', '')}"[:300]
    elif row["exit_optimize"] not in (None, 0, 1) and not row["message"]:
        row["message"] = (p.stderr.strip().splitlines() or ["?"])[-1][:300]
    if row.get("exit_optimize") == 0 and sol.is_file():
        c = subprocess.run(_rd() + ["check", str(task), str(sol), "--modules", SETS[set_name], "--json"],
                           capture_output=True, text=True, env=env, timeout=600)
        row["exit_check"] = c.returncode
        try:
            v = json.loads(c.stdout)
        except ValueError:
            v = {}
        row["valid"] = c.returncode == 0 and bool(v.get("valid"))
        row["cyc"] = v.get("cost") if row["valid"] else None
        if not row["valid"]:
            row["verdict"] = "not_found"
            row["stopped_at"] = "check (re-check)"
            row["message"] = "; ".join(str(x.get("message", x)) for x in (v.get("violations") or [])[:2])[:300]
    row["finished"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    return row


def load_rows(path: Path) -> list:
    rows = []
    if path.is_file():
        for line in path.read_text().splitlines():
            try:
                rows.append(json.loads(line))
            except ValueError:
                pass  # a line cut by a kill: that task is run again
    return rows


def records(rows: list) -> list:
    return [SuiteRecord(suite=r["variant"], task=r["task"], optimizer=r["set"], seed=0, solved=bool(r["valid"]),
                        best=r["cyc"], first_feasible_s=r["first_feasible_s"], evaluations=r["evaluations"],
                        stopped_at=r["stopped_at"], message=r["message"],
                        verdict=r.get("verdict") or ("solved" if r["valid"] else ""),
                        diagnosis=r.get("diagnosis") or "", reach_bound=r.get("reach_bound")) for r in rows]


def summarize(rows: list) -> list:
    out = []
    for s in summarize_suites(records(rows)):
        anchor = VARIANTS[s["suite"]][2]
        ratio = s["best_cost_median"] / anchor if math.isfinite(s["best_cost_median"]) else math.nan
        cyc = sorted(r["cyc"] for r in rows if r["variant"] == s["suite"] and r["set"] == s["optimizer"]
                     and r["valid"] and r["cyc"] is not None)
        p90 = cyc[min(len(cyc) - 1, math.ceil(0.9 * len(cyc)) - 1)] if cyc else math.nan
        out.append({**s, "best_cost_p90": p90, "anchor_s": anchor, "ratio_median_to_anchor": ratio})
    order = {v: i for i, v in enumerate(VARIANTS)}
    return sorted(out, key=lambda s: (order[s["suite"]], s["optimizer"] != "builtin"))


def write_outputs(out: Path, rows: list, meta: dict) -> list:
    summary = summarize(rows)
    tmp = out / "runs.csv.tmp"
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, FIELDS, extrasaction="ignore")
        w.writeheader()
        for r in sorted(rows, key=lambda r: (r["variant"], r["set"], r["index"])):
            w.writerow(r)
    tmp.replace(out / "runs.csv")
    (out / "summary.json").write_text(json.dumps({"meta": meta, "summary": summary}, indent=1, default=str))
    cols = ("suite", "optimizer", "tasks", "solved", "out_of_reach", "not_found", "solved_pct_reachable",
            "best_cost_median", "best_cost_p90", "best_cost_min", "best_cost_max", "anchor_s", "ratio_median_to_anchor",
            "first_feasible_s_median", "unsolved_stopped_at")
    head = ("family", "module set", "tasks", "solved (checked valid)", "provably out of reach", "not found",
            "solved / not proven", "median best cyc [s]", "p90", "min", "max", "anchor [s]", "median / anchor",
            "first valid design [s] (median)", "not found: furthest stage")
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(cell(c, s[c]) for c in cols) + " |" for s in summary]
    (out / "summary.md").write_text("\n".join(lines) + "\n")
    return summary


def main(argv=None) -> int:
    global COBRA
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=50, help="tasks per family variant (default 50)")
    ap.add_argument("--seed", type=int, default=0, help="generator seed (default 0)")
    ap.add_argument("--budget", default="60s", help="robodesign optimize budget per task (default 60s)")
    ap.add_argument("--optimizer", default="genetic")
    ap.add_argument("--jobs", type=int, default=2, help="tasks at a time (default 2; the machine is shared)")
    ap.add_argument("--workers", type=int, default=1,
                    help="robodesign optimize --workers per task (default 1: --jobs tasks already fill the cores)")
    ap.add_argument("--variants", default=",".join(PUBLISHED),
                    help=f"comma-separated, of {', '.join(VARIANTS)} (default: the published families)")
    ap.add_argument("--sets", default="heavy",
                    help="comma-separated module sets: builtin (robodesign_arm), heavy (robodesign_heavy), IMPROV "
                         "(default heavy)")
    ap.add_argument("--out", default=str(ROOT / "docs" / "results" / "families"))
    ap.add_argument("--cobra", default=str(COBRA), help="the CoBRA reference data (IMPROV modules, machine "
                                                         "meshes; default: ../shared/cobra beside the checkout)")
    ap.add_argument("--stop-at", help="UTC time HH:MM: start no new task after it (the ones running finish)")
    args = ap.parse_args(argv)
    COBRA = Path(args.cobra).resolve()
    SETS["IMPROV"] = str(COBRA / "modules" / "IMPROV")
    variants = [v for v in args.variants.split(",") if v]
    sets = [s for s in args.sets.split(",") if s]
    for v in variants:
        if v not in VARIANTS:
            ap.error(f"unknown variant {v!r}")
    for s in sets:
        if s not in SETS:
            ap.error(f"unknown module set {s!r}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    files = {}
    for v in variants:
        try:
            files[v] = task_files(v, args.count, args.seed)
        except Exception as e:  # a family not available in this checkout: say so, run the others
            print(f"{v}: cannot generate tasks: {' '.join(str(e).split())[:300]}", file=sys.stderr)
    jsonl = out / "runs.jsonl"
    rows = load_rows(jsonl)
    done = {(r["variant"], r["set"], r["task"]) for r in rows}
    todo = [(v, s, i, files[v][i]) for i in range(args.count) for v in variants if v in files and i < len(files[v])
            for s in sets if (v, s, files[v][i].stem) not in done]
    meta = {"command": " ".join([Path(sys.argv[0]).name] + (argv if argv is not None else sys.argv[1:])),
            "count": args.count, "seed": args.seed, "budget": args.budget, "optimizer": args.optimizer,
            "jobs": args.jobs, "workers": args.workers, "cpus": os.cpu_count(), "load_avg_at_start": os.getloadavg(),
            "tasks_to_run_this_session": len(todo), "tasks_stored_before": len(rows)}
    print(f"{len(rows)} tasks stored, {len(todo)} to run ({args.jobs} at a time, {args.budget} each)", flush=True)
    lock = threading.Lock()
    stop_at = None
    if args.stop_at:
        hh, mm = (int(x) for x in args.stop_at.split(":"))
        now = time.gmtime()
        stop_at = time.time() + ((hh * 60 + mm) - (now.tm_hour * 60 + now.tm_min)) * 60 - now.tm_sec

    def work(item):
        v, s, i, f = item
        if stop_at is not None and time.time() > stop_at:
            return
        row = run_task(v, s, i, f, out, args.budget, args.optimizer, args.seed, args.workers)
        with lock:
            with open(jsonl, "a") as fh:
                fh.write(json.dumps(row) + "\n")
                fh.flush()
                os.fsync(fh.fileno())
            rows.append(row)
            write_outputs(out, rows, meta)
            what = f"valid, cyc {row['cyc']:.3f} s" if row["valid"] else f"FAILED ({row['stopped_at']})"
            print(f"[{len(rows)}] {v} {s} {f.stem}: {what} ({row['evaluations']} evals, {row['optimize_s']} s)",
                  flush=True)

    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as ex:
        list(ex.map(work, todo))
    meta["load_avg_at_end"] = os.getloadavg()
    summary = write_outputs(out, rows, meta)
    print()
    print((out / "summary.md").read_text())
    for s in summary:
        print(f"{s['suite']:18s} {s['optimizer']:8s} {s['tasks']:3d} tasks  valid {cell('solved_pct', s['solved_pct'])}"
              f"  median {cell('', s['best_cost_median'])} s [min {cell('', s['best_cost_min'])}, max "
              f"{cell('', s['best_cost_max'])}]  ratio to {s['anchor_s']} s: {cell('', s['ratio_median_to_anchor'])}"
              + (f"  failures: {s['unsolved_stopped_at']}" if s["unsolved_stopped_at"] else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
