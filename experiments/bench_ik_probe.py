"""A/B of two checkouts' searches on the hard published families and PTP_3 (issue 25, fifteenth round: every goal's
first IK solution before any goal's others, and the static torque decided goal by goal).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python experiments/bench_ik_probe.py --a CHECKOUT_A --b CHECKOUT_B \
        [--parts families,random,ptp3] [--tasks 5] [--seeds 0,1] [--budget 30s] [--ptp3-seeds 20] [--out DIR]
        [--a-solve KEY=VALUE,...] [--b-solve KEY=VALUE,...]

``--a-solve``/``--b-solve``: solve settings of that side's evaluations besides the evaluator's defaults (e.g.
``plan_time=0.5``; numbers are read as numbers), so one checkout can be compared with itself under other settings.

Every job runs in a process of its own with its checkout's src/ first on the path (kernels warmed up first), one
job at a time, A and B in turn (B first on every other job). Each finished job is appended to ``DIR/jobs.jsonl``
at once; a rerun skips the jobs found there (a kill loses only the job in flight). Parts:

* ``families``: the genetic search (robodesign_arm, cost cyc, the evaluator's defaults) for ``--budget`` on the
  first ``--tasks`` tasks of each family of ``bench_ik_saturate.FAMILIES`` (Whitman2020 5/5 with a free base and
  BPO24, the published variant, generator seed 7), study seeds ``--seeds``. Per job: evaluations, process CPU
  seconds, feasible evaluations, the best cost, and each ending stage's count and median summed-stage ms.
* ``random``: the first 300 random candidates of each such task (generator seed 0, study seed 0): the IK failures'
  count and median ms (the issue's "a candidate that fails at IK on a 5-goal task").
* ``ptp3``: the genetic search on simple/PTP_3 with IMPROV (base pose searched), 600 evaluations, study seeds
  0 to ``--ptp3-seeds`` - 1: best cycle time, feasible evaluations, CPU seconds.

Printed and written to ``DIR/summary.md``: per family and side the tasks solved (a feasible design found) of the
task-seed runs, evaluations per CPU second, the medians of the IK-failure and static-torque-failure ms, and the
best costs' paired ratio B ÷ A where both sides solved; per side the PTP_3 bests (mean, median, B worse / better).
"""
from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

HERE = Path(__file__).resolve().parent
RANDOM = 300


def run_job(job: dict) -> dict:
    """One job in this process (its checkout's src/ is already first on the path)."""
    import numpy as np

    from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
    from robodesign.design.optimize import optimize
    from robodesign.design.problem import Problem
    from robodesign.design.solve import warm_up
    from robodesign.solvers import ik_kernel
    ik_kernel.warm_up()
    warm_up()
    each: dict = defaultdict(list)
    feasible = [0]

    def record(i, e, best) -> None:
        each[e.stage].append(sum(s["seconds"] for s in e.stages))
        feasible[0] += bool(e.feasible)
    if job["part"] == "ptp3":
        from profile_evaluator import SHARED
        problem = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
    else:
        problem = Problem.build(job["task"], "robodesign_arm", "cyc")
    t = time.process_time()
    settings = evaluation_settings(**job.get("solve", {}))
    if job["part"] == "random":
        rng = np.random.default_rng(0)
        ev = Evaluator(EvaluatorSpec(problem, settings=settings, seed=0))
        for i in range(RANDOM):
            record(i, ev.evaluate(problem.space.random_candidate(rng)), None)
        best = None
    else:
        budget = "600evals" if job["part"] == "ptp3" else job["budget"]
        r = optimize(problem, "genetic", budget, seed=job["seed"], on_evaluation=record, settings=settings)
        best = r.best.cost if r.best is not None and r.best.feasible else None
    cpu = time.process_time() - t
    return {**job, "evals": sum(map(len, each.values())), "cpu": cpu, "feasible": feasible[0], "best": best,
            "stages": {k: [len(v), 1e3 * statistics.median(v)] for k, v in each.items()},
            "ik_ms": [1e3 * x for x in each.get("ik", [])] if job["part"] == "random" else None}


def worker(src: str, job: dict) -> None:
    sys.path.insert(0, str(Path(src).resolve() / "src"))
    sys.path.insert(1, str(HERE))
    import robodesign
    assert Path(robodesign.__file__).resolve().is_relative_to(Path(src).resolve()), robodesign.__file__
    print("RESULT " + json.dumps(run_job(job)), flush=True)


def jobs_of(args) -> list:
    from bench_ik_saturate import FAMILIES, family_tasks
    jobs = []
    parts = args.parts.split(",")
    for fam in FAMILIES:
        tasks = family_tasks(fam)[:args.tasks]
        if "families" in parts:
            jobs += [{"part": "families", "family": fam, "task": str(t), "seed": s, "budget": args.budget}
                     for s in args.seeds for t in tasks]
        if "random" in parts:
            jobs += [{"part": "random", "family": fam, "task": str(t), "seed": 0} for t in tasks]
    if "ptp3" in parts:
        jobs += [{"part": "ptp3", "family": "PTP_3", "task": "simple/PTP_3", "seed": s} for s in range(args.ptp3_seeds)]
    return jobs


def key(job: dict, side: str) -> str:
    return json.dumps([job["part"], job["task"], job["seed"], job.get("budget"), side])


def run_all(args, out: Path) -> list:
    done = {}
    if out.exists():
        for line in out.read_text().splitlines():
            if line.strip():
                r = json.loads(line)
                done[key(r, r["side"])] = r
    jobs = jobs_of(args)
    for n, job in enumerate(jobs):
        for side in ("a", "b") if n % 2 == 0 else ("b", "a"):
            if key(job, side) in done:
                continue
            src = args.a if side == "a" else args.b
            solve = _overrides(args.a_solve if side == "a" else args.b_solve)
            p = subprocess.run([sys.executable, __file__, "--worker", json.dumps({**job, "solve": solve}), "--src", src],
                               capture_output=True, text=True)
            lines = [x for x in p.stdout.splitlines() if x.startswith("RESULT ")]
            if p.returncode != 0 or not lines:
                raise SystemExit(f"job {job} on {side} failed (exit {p.returncode}):\n{p.stderr[-2000:]}")
            r = {**json.loads(lines[-1][7:]), "side": side}
            done[key(job, side)] = r
            with out.open("a") as fh:
                fh.write(json.dumps(r) + "\n")
            print(f"[{n + 1}/{len(jobs)}] {side} {job['part']} {Path(job['task']).stem} seed {job['seed']}: "
                  f"{r['evals']} evals, {r['cpu']:.1f} s CPU, {r['feasible']} feasible, best {r['best']}", flush=True)
    return list(done.values())


def _overrides(text: str) -> dict:
    """``"plan_time=0.5,ik_restarts=100"`` → {"plan_time": 0.5, "ik_restarts": 100}."""
    out = {}
    for item in filter(None, (x.strip() for x in (text or "").split(","))):
        k, _, v = item.partition("=")
        try:
            out[k.strip()] = json.loads(v)
        except json.JSONDecodeError:
            out[k.strip()] = v.strip()
    return out


def _median(xs) -> str:
    return f"{statistics.median(xs):.1f}" if xs else "-"


def summary(rows: list) -> str:
    lines = []
    for side in ("a", "b"):
        solve = next((r.get("solve") for r in rows if r["side"] == side and r.get("solve")), None)
        if solve:
            lines += [f"Side {side.upper()}'s solve settings besides the evaluator's defaults: {solve}", ""]
    by = defaultdict(list)
    for r in rows:
        by[(r["part"], r["family"], r["side"])].append(r)
    for fam in sorted({r["family"] for r in rows if r["part"] == "families"}):
        lines += [f"## {fam}: genetic search, {rows[0].get('budget') or ''} per task and seed", "",
                  "| side | runs solved | evaluations per CPU s | IK failures: count, median ms | "
                  "static_torque failures: count, median ms | failed plans: count, median ms |", "|---|---|---|---|---|---|"]
        for side in ("a", "b"):
            rs = by[("families", fam, side)]
            if not rs:
                continue
            cells = []
            for stage in ("ik", "static_torque", "plan"):
                counts = [r["stages"][stage][0] for r in rs if stage in r["stages"]]
                meds = [r["stages"][stage][1] for r in rs if stage in r["stages"]]
                cells.append(f"{sum(counts)}, {_median(meds)} (median of the runs' medians)")
            rate = sum(r["evals"] for r in rs) / sum(r["cpu"] for r in rs)
            lines.append(f"| {side.upper()} | {sum(r['best'] is not None for r in rs)} of {len(rs)} | {rate:.1f} | "
                         + " | ".join(cells) + " |")
        lines += ["", paired(by[("families", fam, "a")], by[("families", fam, "b")]), ""]
        for side in ("a", "b"):
            ik = [x for r in by[("random", fam, side)] for x in (r["ik_ms"] or [])]
            if ik:
                lines.append(f"- random candidates, side {side.upper()}: {len(ik)} IK failures, median {_median(ik)} ms")
        lines.append("")
    a, b = by[("ptp3", "PTP_3", "a")], by[("ptp3", "PTP_3", "b")]
    if a or b:
        lines += ["## PTP_3 (IMPROV): genetic search, 600 evaluations", ""]
        for side, rs in (("A", a), ("B", b)):
            bests = [r["best"] for r in rs if r["best"] is not None]
            lines.append(f"- {side}: {len(rs)} runs, best mean {statistics.mean(bests):.4f} s, median "
                         f"{statistics.median(bests):.3f} s, feasible evaluations {sum(r['feasible'] for r in rs)}, "
                         f"CPU {sum(r['cpu'] for r in rs):.1f} s" if bests else f"- {side}: no feasible run")
        lines.append("- " + paired(a, b))
    return "\n".join(lines) + "\n"


def paired(a: list, b: list) -> str:
    """B's best against A's on the runs both solved, and the runs only one side solved."""
    ia = {(r["task"], r["seed"]): r["best"] for r in a}
    ib = {(r["task"], r["seed"]): r["best"] for r in b}
    both = [(ia[k], ib[k]) for k in ia.keys() & ib.keys() if ia[k] is not None and ib[k] is not None]
    only_a = sum(1 for k in ia.keys() & ib.keys() if ia[k] is not None and ib[k] is None)
    only_b = sum(1 for k in ia.keys() & ib.keys() if ia[k] is None and ib[k] is not None)
    if not both:
        return f"best cost: no run solved by both; solved by A only {only_a}, by B only {only_b}"
    ratios = [y / x for x, y in both]
    return (f"best cost B ÷ A over the {len(both)} runs both solved: median {statistics.median(ratios):.3f}, "
            f"B worse in {sum(y > x for x, y in both)}, better in {sum(y < x for x, y in both)}; "
            f"solved by A only {only_a}, by B only {only_b}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--a")
    ap.add_argument("--b")
    ap.add_argument("--parts", default="families,random,ptp3")
    ap.add_argument("--tasks", type=int, default=5)
    ap.add_argument("--seeds", type=lambda s: [int(x) for x in s.split(",")], default=[0, 1])
    ap.add_argument("--budget", default="30s")
    ap.add_argument("--ptp3-seeds", type=int, default=20)
    ap.add_argument("--out", type=Path, default=HERE.parent / "docs" / "results" / "issue25_round15" / "probe")
    ap.add_argument("--a-solve", default="", help="solve settings of side A's evaluations, KEY=VALUE,...")
    ap.add_argument("--b-solve", default="", help="solve settings of side B's evaluations, KEY=VALUE,...")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    ap.add_argument("--src", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        return worker(args.src, json.loads(args.worker))
    if not (args.a and args.b):
        ap.error("--a and --b are required")
    args.out.mkdir(parents=True, exist_ok=True)
    rows = run_all(args, args.out / "jobs.jsonl")
    text = summary(rows)
    (args.out / "summary.md").write_text(text)
    print(text)


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:   # every finished job is in jobs.jsonl; a rerun goes on from there
        print("interrupted: the finished jobs are in jobs.jsonl (a rerun skips them)", file=sys.stderr)
        sys.exit(130)
