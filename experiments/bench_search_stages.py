"""Where a genetic search's time goes on the hard published families: the evaluations grouped by the stage that
ended them (issue 25).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python experiments/bench_search_stages.py [--tasks 5] [--budget 30s] [--out FILE]

For each family of ``bench_ik_saturate.FAMILIES`` (Whitman2020 5/5 with a free base and BPO24, the published
variant, generator seed 7, written to results/tasks/ once), the first ``--tasks`` tasks are each searched by the
genetic optimizer (robodesign_arm, cost cyc, study seed 0, the evaluator's default settings) for ``--budget``.
Printed per family and ending stage ("done" = feasible): the evaluations, their summed stage seconds, the share of
the family's total and the mean, median and 90th percentile per evaluation; then how many goals the IK failures
had reached, for the search and for 300 random candidates per task (their median stage seconds too). Each family's table is appended to ``--out`` when it is done.
"""
from __future__ import annotations

import argparse
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_ik_saturate import FAMILIES, family_tasks  # noqa: E402

from robodesign.design.evaluator import Evaluator, EvaluatorSpec  # noqa: E402
from robodesign.design.optimize import optimize  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.solve import warm_up  # noqa: E402


RANDOM = 300   # random candidates per task, for the IK failures of the search space itself


def family_table(fam: str, tasks: int, budget: str) -> str:
    each: dict = defaultdict(list)   # ending stage -> each evaluation's summed stage seconds
    reached: list = []   # goals reached by the candidates that failed at IK
    random_ik: list = []  # (goals reached, seconds) of the IK failures among random candidates

    def record(i, e, best) -> None:
        each[e.stage].append(sum(s["seconds"] for s in e.stages))
        if e.stage == "ik":
            reached.append(e.goals_reached)
    for f in family_tasks(fam)[:tasks]:
        problem = Problem.build(f, "robodesign_arm", "cyc")
        optimize(problem, "genetic", budget, seed=0, on_evaluation=record)
        rng = np.random.default_rng(0)
        ev = Evaluator(EvaluatorSpec(problem, seed=0))
        for _ in range(RANDOM):
            e = ev.evaluate(problem.space.random_candidate(rng))
            if e.stage == "ik":
                random_ik.append((e.goals_reached, sum(s["seconds"] for s in e.stages)))
    secs = {stage: sum(v) for stage, v in each.items()}
    total = sum(secs.values())
    lines = [f"{fam}: {sum(map(len, each.values()))} evaluations, {total:.1f} s of stages ({tasks} tasks x {budget})",
             "| ended at | evaluations | seconds | share | ms per evaluation: mean | median | 90th percentile |",
             "|---|---|---|---|---|---|---|"]
    for stage in sorted(secs, key=secs.get, reverse=True):
        ms = 1e3 * np.array(each[stage])
        lines.append(f"| {stage} | {len(ms)} | {secs[stage]:.1f} | {100 * secs[stage] / total:.1f} % | "
                     f"{ms.mean():.1f} | {np.median(ms):.1f} | {np.percentile(ms, 90):.1f} |")
    rr = [g for g, _ in random_ik]
    lines += ["", f"IK failures by goals reached before the failing goal (0, 1, ...): the search's {goal_counts(reached)}; "
              f"{RANDOM} random candidates per task: {goal_counts(rr)}, median "
              f"{1e3 * np.median([t for _, t in random_ik]):.1f} ms"]
    return "\n".join(lines)


def goal_counts(values: list) -> str:
    return ", ".join(f"{values.count(k)}" for k in range(max(values) + 1)) if values else "none"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--tasks", type=int, default=5)
    ap.add_argument("--budget", default="30s")
    ap.add_argument("--out", type=Path, default=Path("docs/results/issue25_round14/search_stages.md"))
    args = ap.parse_args()
    warm_up()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("")
    for fam in FAMILIES:
        table = family_table(fam, args.tasks, args.budget)
        print(table + "\n", flush=True)
        with args.out.open("a") as fh:
            fh.write(table + "\n\n")


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:   # the families done so far are in --out
        print("interrupted: the families done so far are in the output file", file=sys.stderr)
        sys.exit(130)
