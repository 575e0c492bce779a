"""Profile of the evaluator, stage by stage (issue 25): where a candidate's time goes.

    nice .venv/bin/python experiments/profile_evaluator.py [--feasible 20] [--failing 40] [--tasks 2] [--seed 0]
        [--src CHECKOUT]

Scenarios (one process, one core, the compiled IK loop warmed up first):

* ``PTP_3``: simple/PTP_3 with the IMPROV set, cost ``cyc``, random candidates of the default search space
  (base within the task's tolerance) evaluated by :class:`robodesign.design.evaluator.Evaluator` (the
  optimizers' settings: 150 IK restarts, 48 IK solutions per goal) until ``--feasible`` of them are feasible;
  then ``--feasible`` evaluations of the known-good arm ``1,21,4,22,5,23,12`` at the nominal base with
  different study seeds (a feasible candidate for sure).
* ``whitman2020 g5o5`` (5 goals, 5 obstacles, free base) and ``bpo2024`` (mixed): ``--tasks`` generated tasks
  each (seeded, cached in results/tasks/), the built-in module set, random candidates until ``--failing``
  failed at the IK stage (and every feasible one on the way is kept).

Per scenario and group (feasible / failed at IK / failed elsewhere) it prints the median milliseconds of
every stage (assembly = model build, base, reach, ik, static_torque, plan, timing, trajopt, check), its
share of the summed medians, the median total evaluation time, the median CPU time of the process per
evaluation (steadier than wall time on a shared machine) and the count. ``--src``
evaluates another checkout's src/ on this checkout's tasks (an A/B in one command line per side). Timings come from the
evaluator's own stage records (``Evaluation.stages``), so they are what an optimizer pays.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
# --src CHECKOUT: evaluate that checkout's src/ (an A/B on the same tasks, from this script); default: this one
_SRC = Path(sys.argv[sys.argv.index("--src") + 1]) if "--src" in sys.argv[:-1] else ROOT
sys.path.insert(0, str(_SRC.resolve() / "src"))

from robodesign.design.evaluator import Evaluator, EvaluatorSpec  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.search_space import Candidate  # noqa: E402
from robodesign.design.solve import STAGES, warm_up  # noqa: E402

SHARED = ROOT.parent / "shared" / "cobra"
GOOD = ("1", "21", "4", "22", "5", "23", "12")
FAMILIES = {"whitman2020_g5o5": ("whitman2020", {"goals": 5, "obstacles": 5, "base": "xyz_any_rot"}),
            "bpo2024": ("bpo2024", {"structure": "mixed", "difficulty": "mixed"})}


def family_tasks(name: str, count: int, seed: int):
    from robodesign.generate.registry import generate
    family, options = FAMILIES[name]
    folder = ROOT / "results" / "tasks" / f"profile_{name}_s{seed}_n{count}"
    files = sorted(folder.glob("*.json")) if folder.is_dir() else []
    if len(files) < count:
        files = generate(family, folder, count, seed, options)
    return files[:count]


def group_of(ev) -> str:
    if ev.feasible:
        return "feasible"
    return "failed at ik" if ev.stage == "ik" else "failed elsewhere"


def record(ev, groups, cpu: float = float("nan")) -> None:
    st = {s["name"]: s["seconds"] for s in ev.stages}
    groups[group_of(ev)].append((st, ev.seconds, ev.stage, cpu))


def table(title: str, groups) -> str:
    lines = [f"\n### {title}\n", "| group | n | " + " | ".join(STAGES) + " | total (median) | CPU (median) |",
             "|---|---:|" + "---:|" * len(STAGES) + "---:|---:|"]
    for g in ("feasible", "failed at ik", "failed elsewhere"):
        rows = groups.get(g, [])
        if not rows:
            continue
        med = {s: statistics.median([r[0].get(s, 0.0) for r in rows]) * 1e3 for s in STAGES}
        tot = sum(med.values())
        cells = []
        for s in STAGES:
            cells.append(f"{med[s]:.2f} ({100 * med[s] / tot:.0f} %)" if tot > 0 and med[s] >= 0.005 else "–")
        total = statistics.median([r[1] for r in rows]) * 1e3
        cpu = statistics.median([r[3] for r in rows]) * 1e3
        lines.append(f"| {g} | {len(rows)} | " + " | ".join(cells) + f" | {total:.1f} ms | {cpu:.1f} ms |")
        if g == "failed elsewhere":
            stages = defaultdict(int)
            for r in rows:
                stages[r[2]] += 1
            lines.append(f"| (stopped at: {dict(stages)}) |" + " |" * (len(STAGES) + 2))
    return "\n".join(lines)


def run_random(problem: Problem, seed: int, want_feasible: int, want_failing: int, max_candidates: int):
    ev = Evaluator(EvaluatorSpec(problem, seed=seed))
    rng = np.random.default_rng(seed)
    groups = defaultdict(list)
    n = 0
    t0 = time.perf_counter()
    while n < max_candidates:
        if len(groups["feasible"]) >= want_feasible and len(groups["failed at ik"]) >= want_failing:
            break
        c = problem.space.random_candidate(rng)
        t = time.process_time()
        e = ev.evaluate(c)
        record(e, groups, time.process_time() - t)
        n += 1
    return groups, n, time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--feasible", type=int, default=20, help="feasible candidates wanted per scenario")
    ap.add_argument("--failing", type=int, default=40, help="candidates failing at IK wanted per family task")
    ap.add_argument("--tasks", type=int, default=2, help="generated tasks per family")
    ap.add_argument("--max", type=int, default=400, help="at most this many random candidates per task")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--src", default=str(ROOT), help="the checkout whose src/ is evaluated (default: this one)")
    ap.add_argument("--only", default="", help="comma-separated subset: ptp3, good, whitman2020_g5o5, bpo2024")
    args = ap.parse_args()
    only = set(filter(None, args.only.split(",")))
    from robodesign.solvers import ik_kernel
    # the compiled IK loop, compiled in this process if the cache is cold (before solve's warm_up, which would
    # otherwise start the background compilation and run the Python loop for the whole process)
    if not ik_kernel.warm_up():
        print("note: ROBODESIGN_JIT=0 or no numba: the Python IK loop runs")
    import robodesign
    print(f"# src: {Path(robodesign.__file__).parent}", flush=True)
    warm_up()
    out = []

    ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
    Evaluator(EvaluatorSpec(ptp3)).evaluate(Candidate(GOOD))   # warm-up: meshes, toppra, OMPL
    if not only or "ptp3" in only:
        groups, n, dt = run_random(ptp3, args.seed, args.feasible, args.failing, args.max * 3)
        out.append(table(f"PTP_3, IMPROV, random candidates ({n} evaluated in {dt:.1f} s, "
                         f"{n / dt:.1f} candidates/s)", groups))
        print(out[-1], flush=True)
    if not only or "good" in only:
        groups = defaultdict(list)
        for s in range(args.feasible):
            ev = Evaluator(EvaluatorSpec(ptp3, seed=args.seed + s))
            t = time.process_time()
            e = ev.evaluate(Candidate(GOOD))
            record(e, groups, time.process_time() - t)
        out.append(table(f"PTP_3, IMPROV {','.join(GOOD)} at the nominal base, {args.feasible} study seeds", groups))
        print(out[-1], flush=True)
    for name in FAMILIES:
        if only and name not in only:
            continue
        groups = defaultdict(list)
        n_all, dt_all = 0, 0.0
        for f in family_tasks(name, args.tasks, args.seed):
            problem = Problem.build(f, "robodesign_arm", "cyc")
            g, n, dt = run_random(problem, args.seed, 0, args.failing, args.max)
            for k, v in g.items():
                groups[k].extend(v)
            n_all, dt_all = n_all + n, dt_all + dt
        out.append(table(f"{name}, built-in set, random candidates on {args.tasks} generated tasks "
                         f"({n_all} evaluated in {dt_all:.1f} s, {n_all / dt_all:.1f} candidates/s)", groups))
        print(out[-1], flush=True)


if __name__ == "__main__":
    main()
