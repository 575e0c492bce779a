"""Where the IK failures of a genetic search's own stream spend their time (issue 25, fifteenth round).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python experiments/bench_ik_failures.py [--family whitman2020_g5o5_free]
        [--tasks 3] [--budget 20s] [--out FILE]

The genetic search (robodesign_arm, cost cyc, study seed 0, the evaluator's defaults) runs for ``--budget`` on each
of the first ``--tasks`` tasks of a family of ``bench_ik_saturate.FAMILIES``; every IK search it makes
(``solvers.ik.IKSearch``) is timed run by run. For the evaluations that failed at the ik stage, grouped by how many
goals they reached before the failing one: the count, the ik stage's median ms, the failing goal's search (median
ms, attempts, converged attempts, collision rejections, repairs, the reasons it ended) and the earlier goals' first
solutions (median ms and attempts of each). Printed and appended to ``--out``.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections import Counter, defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_ik_saturate import FAMILIES, family_tasks  # noqa: E402

from robodesign.design.optimize import optimize  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.solve import warm_up  # noqa: E402
from robodesign.solvers import ik  # noqa: E402


def failures(family: str, tasks: int, budget: str) -> list:
    """(goals reached, ik stage s, [(n asked, s, stats) of each run of its searches]) of every IK failure."""
    runs: list = []
    plain = ik.IKSearch

    class Timed(plain):
        def run(self, n):
            t = time.perf_counter()
            r = super().run(n)
            runs.append((n, time.perf_counter() - t, dict(r.stats)))
            return r
    out = []

    def record(i, e, best) -> None:
        if e.stage == "ik":
            ik_s = next(s["seconds"] for s in e.stages if s["name"] == "ik")
            out.append((e.goals_reached, ik_s, list(runs)))
        runs.clear()
    ik.IKSearch = Timed
    try:
        for f in family_tasks(family)[:tasks]:
            optimize(Problem.build(f, "robodesign_arm", "cyc"), "genetic", budget, seed=0, on_evaluation=record)
    finally:
        ik.IKSearch = plain
    return out


def table(family: str, rows: list) -> str:
    ms = 1e3
    lines = [f"{family}: {len(rows)} IK failures, ik stage median {ms * statistics.median(r[1] for r in rows):.2f} ms",
             "| goals reached | failures | ik stage ms | failing search: ms | attempts | converged | collisions | "
             "repairs | ended (most) | earlier goals' first solutions: ms | attempts |", "|" + "---|" * 11]
    by = defaultdict(list)
    for g, s, rs in rows:
        if rs:
            by[g].append((s, rs))
    for g in sorted(by):
        v = by[g]
        last = [rs[-1] for _, rs in v]
        first = [x for _, rs in v for x in rs[:-1]]

        def med(xs):
            return statistics.median(xs) if xs else float("nan")
        ends = ", ".join(f"{k} {n}" for k, n in Counter(x[2]["reason"] for x in last).most_common(2))
        lines.append(f"| {g} | {len(v)} | {ms * med([s for s, _ in v]):.2f} | {ms * med([x[1] for x in last]):.2f} | "
                     f"{med([x[2]['attempts'] for x in last]):.0f} | {med([x[2]['converged'] for x in last]):.0f} | "
                     f"{med([x[2]['rejected_collision'] for x in last]):.0f} | {med([x[2]['repairs'] for x in last]):.0f} | "
                     f"{ends} | {ms * med([x[1] for x in first]):.2f} | {med([x[2]['attempts'] for x in first]):.0f} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--family", default="whitman2020_g5o5_free", choices=sorted(FAMILIES))
    ap.add_argument("--tasks", type=int, default=3)
    ap.add_argument("--budget", default="20s")
    ap.add_argument("--out", type=Path, default=Path("docs/results/issue25_round15/ik_failures.md"))
    args = ap.parse_args()
    warm_up()
    text = table(args.family, failures(args.family, args.tasks, args.budget))
    print(text, flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("a") as fh:
        fh.write(text + "\n\n")


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:
        print("interrupted: nothing written for the family in progress", file=sys.stderr)
        sys.exit(130)
