"""The DoF rule of a search, A/B on given tasks: ``robodesign optimize`` per task and per ``--dof`` setting
(genetic, cyc, robodesign_heavy, one seed, one process per run, ``--jobs`` runs at a time); prints and appends
one JSON line per run to OUT (a re-run skips the (setting, task) pairs OUT holds).

    .venv/bin/python experiments/bench_dof_screen.py OUT.jsonl --budget 60s --seed 1 \\
        --settings d6=6,d7=7,d67=6-7 TASK.json ...

Each line: setting, task, whether a checked-valid design was found, its cycle time, the evaluations, the
seconds to the first valid design and, when none was found, how many candidates each stage stopped.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Optional

ROOT = Path(__file__).resolve().parents[1]


def run(setting: str, dof: str, task: str, budget: str, seed: int) -> Optional[dict]:
    exe = Path(sys.executable).with_name("robodesign")
    rd = [str(exe)] if exe.is_file() else [sys.executable, "-m", "robodesign.cli"]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src"), str(ROOT / "optimizers"),
                                                        os.environ.get("PYTHONPATH", "")]))
    with tempfile.TemporaryDirectory() as d:  # optimize's journal lives beside --out, one folder per run
        t0 = time.time()
        p = subprocess.run(rd + ["optimize", task, "--modules", "robodesign_heavy", "--optimizer", "genetic",
                                 "--cost", "cyc", "--budget", budget, "--seed", str(seed), "--workers", "1",
                                 "--json", "--out", str(Path(d) / "best.json")] + (["--dof", dof] if dof else []),
                           capture_output=True, text=True, cwd=d, env=env)
    if p.returncode in (130, -2):  # interrupted (Ctrl-C): not a result; a re-run searches the task again
        return None
    try:
        j = json.loads(p.stdout[p.stdout.index("{"):])
    except ValueError:
        j = {"error": p.stderr.strip()[-300:] or f"exit {p.returncode}"}
    return {"config": setting, "dof": dof, "task": Path(task).name, "seed": str(seed), "feasible": j.get("feasible"),
            "cost": (j.get("best") or {}).get("cost"), "evals": j.get("evaluations"),
            "first": j.get("first_feasible_seconds"), "stage_counts": j.get("stage_counts"),
            "stopped_at": j.get("stopped_at"), "wall": time.time() - t0, "err": j.get("error")}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("tasks", nargs="+")
    ap.add_argument("--budget", default="60s")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--settings", default="d6=6,d7=7,d67=6-7",
                    help="name=--dof value, comma-separated (an empty value: the task's default)")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args(argv)
    settings = dict(s.split("=", 1) for s in a.settings.split(","))
    out = Path(a.out)
    done = set()
    if out.exists():
        done = {(r["config"], r["task"]) for r in map(json.loads, out.read_text().splitlines()) if r}
    todo = [(s, t) for t in a.tasks for s in settings if (s, Path(t).name) not in done]

    def one(st):
        r = run(st[0], settings[st[0]], st[1], a.budget, a.seed)
        if r is None:
            return
        with out.open("a") as f:
            f.write(json.dumps(r) + "\n")
        print(r["config"], r["task"], "valid" if r["feasible"] else "not found", r["cost"], r["evals"], r["first"],
              r["stage_counts"] or "", flush=True)
    try:
        with ThreadPoolExecutor(a.jobs) as ex:
            list(ex.map(one, todo))
    except KeyboardInterrupt:
        print("interrupted: the finished runs are in", out, file=sys.stderr)
        return 130
    rows = [json.loads(x) for x in out.read_text().splitlines() if x]
    for s in settings:
        rs = [r for r in rows if r["config"] == s]
        print(f"{s}: {sum(bool(r['feasible']) for r in rs)} of {len(rs)} tasks solved")
    return 0


if __name__ == "__main__":
    sys.exit(main())
