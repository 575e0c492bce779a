"""Print every evaluation's verdict for a fixed set of candidates, to compare two checkouts (issue 25: the
solver speed-ups must not change any verdict).

    nice .venv/bin/python experiments/compare_verdicts.py --src . > after.txt
    nice .venv/bin/python experiments/compare_verdicts.py --src ../old_checkout > before.txt; diff before.txt after.txt

One line per evaluation: task, candidate index, stage reached, goals reached, feasible, cost and a hash of the
solution's trajectory. Candidates: ``--n`` random candidates (seeded) of PTP_3 with IMPROV and of every task
profile_evaluator.py generated (results/tasks/profile_*), with the built-in set; plus the known-good PTP_3
arm for three study seeds.
"""
from __future__ import annotations

import argparse
import hashlib
import json
from pathlib import Path

from verdict_runs import profile_runs, use_checkout

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--src", default=str(ROOT), help="the checkout whose src/ is evaluated")
    ap.add_argument("--n", type=int, default=40)
    args = ap.parse_args()
    use_checkout(args.src)
    import numpy as np

    from robodesign.design.evaluator import Evaluator, EvaluatorSpec
    from robodesign.design.search_space import Candidate
    runs = profile_runs()

    def line(name, i, e):
        h = hashlib.md5(json.dumps(e.solution["trajectory"]).encode()).hexdigest()[:10] if e.solution else "-"
        print(name, i, e.stage, e.goals_reached, e.feasible, e.cost, h, flush=True)

    for s in range(3):
        line("PTP_3 good", s, Evaluator(EvaluatorSpec(runs[0][1], seed=s)).evaluate(
            Candidate(("1", "21", "4", "22", "5", "23", "12"))))
    for name, p in runs:
        ev = Evaluator(EvaluatorSpec(p, seed=0))
        rng = np.random.default_rng(9)
        for i in range(args.n):
            line(name, i, ev.evaluate(p.space.random_candidate(rng)))


if __name__ == "__main__":
    main()
