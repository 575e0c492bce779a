"""Print every evaluation's verdict for candidates that share module orders, to compare two checkouts (issue 25:
the per-process robot pool and the other front-end caches must not change any verdict).

    nice .venv/bin/python experiments/compare_verdicts_repeat.py --src . > after.txt
    nice .venv/bin/python experiments/compare_verdicts_repeat.py --src ../old_checkout > before.txt; diff before.txt after.txt

As experiments/compare_verdicts.py (same line format, same tasks: PTP_3 with IMPROV and every
results/tasks/profile_* task with the built-in set), but ``--orders`` random orders are each evaluated at
``--bases`` base poses, interleaved (every order at its first base, then every order at its second, ...), so
that a robot taken back from a cache meets another base pose and other robots came and went in between.
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
    ap.add_argument("--orders", type=int, default=12)
    ap.add_argument("--bases", type=int, default=4)
    args = ap.parse_args()
    use_checkout(args.src)
    import numpy as np

    from robodesign.design.evaluator import Evaluator, EvaluatorSpec
    from robodesign.design.search_space import Candidate
    runs = profile_runs()

    for name, p in runs:
        ev = Evaluator(EvaluatorSpec(p, seed=0))
        rng = np.random.default_rng(11)
        orders = [p.space.random_order(rng) for _ in range(args.orders)]
        if name == "PTP_3":
            orders[0] = ("1", "21", "4", "22", "5", "23", "12")
        bases = [[p.space.sample_base(rng, o) for o in orders] for _ in range(args.bases)]
        for k in range(args.bases):
            for i, o in enumerate(orders):
                e = ev.evaluate(Candidate(tuple(o), tuple(bases[k][i])))
                h = hashlib.md5(json.dumps(e.solution["trajectory"]).encode()).hexdigest()[:10] if e.solution else "-"
                print(name, i, k, e.stage, e.goals_reached, e.feasible, e.cost, e.score, e.shortfall, h,
                      e.message[:80], flush=True)


if __name__ == "__main__":
    main()
