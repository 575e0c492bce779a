"""Print the judge's verdict on a fixed set of solution files, to compare two checkouts (issue 25: the checker's
speed-ups must not change any verdict).

    PYTHONPATH=<checkout>/src .venv/bin/python experiments/compare_checker_verdicts.py \\
        --solutions /work/main/docs/results/families_published_v4/solutions --tasks /work/main/results/tasks \\
        --work /tmp/verdicts > verdicts_<checkout>.txt

then ``diff`` the outputs of two checkouts. The files judged:

* every solution under ``--solutions`` (``<variant>/<module set>/<task>.json``, as experiments/bench_families.py
  writes them), on its task: ``<tasks>/<variant>_s<seed>_n*/<task>.json`` (the folders bench_families generates;
  a task not found there is generated the way bench_families does, into this checkout's results/tasks);
* the PTP_3 solutions of the tests and benchmarks (IMPROV 1,21,4,22,5,23,12 solved with seeds 0 and 1; the
  seed-1 solution stretched to 350 and 1,500 samples as experiments/bench_checker.py does, and its
  gradient-filled copy; the near-contact arm of bench_checker), solved once and kept in ``--work`` so that every
  checkout judges the same files;
* of each, three mutated copies: time-scaled faster (t × 0.7, dq / 0.7, ddq / 0.49), q shifted by a constant
  0.05 rad (or m) on every joint, and one sample moved into an obstacle (the first of a fixed list of single-joint
  moves of the middle sample that puts the robot into contact with an obstacle; "no nudge" when none does).

One line per file: name, valid, the number of violations, every violation (constraint, sample, joint, time
rounded to 1e-6 s, value to 9 significant digits, message) and the cost rounded to 1e-9.
"""
from __future__ import annotations

import argparse
import glob
import sys
from pathlib import Path
from typing import Iterator, Optional, Tuple

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
COBRA = ROOT.parent / "shared" / "cobra"
SETS = {"builtin": "robodesign_arm", "heavy": "robodesign_heavy", "IMPROV": str(COBRA / "modules" / "IMPROV")}
ORDER = ["1", "21", "4", "22", "5", "23", "12"]
NUDGES = [(j, d) for d in (0.3, -0.3, 0.6, -0.6, 1.0, -1.0, 1.5, -1.5) for j in range(12)]


def ptp3_files(work: Path) -> Iterator[Tuple[str, Path]]:
    """The PTP_3 solutions of the tests and benchmarks, solved once into ``work``."""
    from robodesign import load_module_set
    from robodesign.design.solve import SolveSettings, solve
    from robodesign.formats.solution import SolutionTrajectory
    from robodesign.formats.task_io import load_task
    names = ["ptp3_seed0", "ptp3_seed1", "ptp3_350", "ptp3_1500", "ptp3_350_gradient", "ptp3_near_contact"]
    if not all((work / f"{n}.json").is_file() for n in names):
        sys.path.insert(0, str(ROOT / "experiments"))
        from bench_checker import stretched
        task = load_task(COBRA / "tasks" / "simple" / "PTP_3.json")
        ms = load_module_set(SETS["IMPROV"])
        work.mkdir(parents=True, exist_ok=True)
        sols = {}
        for seed in (0, 1):
            res = solve(task, ms, ORDER, settings=SolveSettings(seed=seed))
            sols[f"ptp3_seed{seed}"] = res.solution
        for n in (350, 1500):
            sols[f"ptp3_{n}"] = stretched(sols["ptp3_seed1"], n, task.dt)
        tr = sols["ptp3_350"].trajectory
        dq = np.gradient(tr.q, tr.t, axis=0)
        sols["ptp3_350_gradient"] = sols["ptp3_350"].with_(trajectory=SolutionTrajectory(
            tr.t, tr.q, dq, np.gradient(dq, tr.t, axis=0), dict(tr.goal2time)))
        sols["ptp3_near_contact"] = _near_contact(task, ms)
        for n, s in sols.items():
            s.write(work / f"{n}.json")
    for n in names:
        yield n, work / f"{n}.json"


def _near_contact(task, ms):
    """bench_checker's near-contact motion: the arm whose link slides past a joint housing at µm."""
    from dataclasses import replace

    from robodesign.design.evaluator import candidate_seed, evaluation_settings
    from robodesign.design.search_space import Candidate
    from robodesign.design.solve import solve
    order = ("1", "22", "5", "23", "5", "29", "14", "16")
    settings = replace(evaluation_settings(), seed=candidate_seed(3, Candidate(order, ()).key()))
    return solve(task, ms, list(order), np.eye(4), cost="cyc", settings=settings).solution


def task_of(sol_file: Path, tasks_root: Path) -> Optional[Path]:
    """The task of a bench_families solution file (``<variant>/<set>/<task>.json``)."""
    variant, stem = sol_file.parent.parent.name, sol_file.stem
    seed = stem.rsplit("_", 2)[-2].lstrip("s")
    found = sorted(glob.glob(str(tasks_root / f"{variant}_s{seed}_n*" / f"{stem}.json")))
    if found:
        return Path(found[0])
    sys.path.insert(0, str(ROOT / "experiments"))
    from bench_families import task_files
    for f in task_files(variant, 50, int(seed)):
        if Path(f).stem == stem:
            return Path(f)
    return None


def mutations(task, sol, ms):
    """(suffix, mutated solution) of the three kinds in the module docstring."""
    from robodesign.formats.solution import SolutionTrajectory
    from robodesign.model.cell import solution_robot
    tr = sol.trajectory
    f = 0.7
    yield "faster", sol.with_(trajectory=SolutionTrajectory(tr.t * f, tr.q, tr.dq / f, tr.ddq / f ** 2,
                                                            {g: x * f for g, x in tr.goal2time.items()}))
    yield "shifted", sol.with_(trajectory=SolutionTrajectory(tr.t, tr.q + 0.05, tr.dq, tr.ddq, dict(tr.goal2time)))
    robot = solution_robot(task, sol, ms)
    k = tr.n // 2
    for j, d in NUDGES:
        if j >= robot.dof:
            continue
        q = tr.q.copy()
        q[k, j] += d
        if robot.collides_with_obstacles(q[k]):
            yield f"nudged(sample {k}, joint {j}, {d:+g})", sol.with_(
                trajectory=SolutionTrajectory(tr.t, q, tr.dq, tr.ddq, dict(tr.goal2time)))
            return
    yield "no nudge", None


def _r(x: Optional[float], digits: int) -> str:
    return "-" if x is None else repr(round(float(x), digits))


def _g(x: Optional[float]) -> str:
    return "-" if x is None else f"{float(x):.9g}"


def line(name: str, task, sol, ms) -> str:
    from robodesign.judge.checker import check
    if sol is None:
        return f"{name}: -"
    v = check(task, sol, ms)
    cost = "None" if v.cost is None else repr(round(float(v.cost), 9))
    viol = " | ".join(f"{x.constraint}@{x.sample}/{x.joint} t={_r(x.time, 6)} value={_g(x.value)}: {x.message}"
                      for x in v.violations)
    return f"{name}: valid={v.valid} violations={len(v.violations)} cost={cost} [{viol}]"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--solutions", default=str(ROOT / "docs" / "results" / "families_published_v4" / "solutions"))
    ap.add_argument("--tasks", default=str(ROOT / "results" / "tasks"))
    ap.add_argument("--work", default="/tmp/robodesign_checker_verdicts", help="where the PTP_3 solutions are kept")
    ap.add_argument("--no-mutations", action="store_true")
    args = ap.parse_args()
    from robodesign import load_module_set
    from robodesign.formats.solution import load_solution
    from robodesign.formats.task_io import load_task
    ptp3 = load_task(COBRA / "tasks" / "simple" / "PTP_3.json")
    runs = [(n, ptp3, f, SETS["IMPROV"]) for n, f in ptp3_files(Path(args.work))]
    for f in sorted(Path(args.solutions).rglob("*.json")):
        t = task_of(f, Path(args.tasks))
        if t is None:
            print(f"{f.relative_to(args.solutions)}: task not found")
            continue
        runs.append((str(f.relative_to(args.solutions)), load_task(t), f, SETS[f.parent.name]))
    sets = {}
    for name, task, f, ms_name in runs:
        ms = sets.setdefault(ms_name, load_module_set(ms_name))
        sol = load_solution(f)
        print(line(name, task, sol, ms), flush=True)
        if not args.no_mutations:
            for suffix, mut in mutations(task, sol, ms):
                print(line(f"{name} {suffix}", task, mut, ms), flush=True)


if __name__ == "__main__":
    main()
