"""The genetic search's ask alone (issue 25): the optimizer's own work, replayed on recorded evaluations.

    .venv/bin/python experiments/bench_ask_replay.py --src CHECKOUT [--tasks 2] [--budget 200evals] [--repeat 3]

Runs the search of experiments/bench_front_ga.py (optimizer ``genetic``, seed 0, batches of 16) on its family
tasks once with the real evaluator of ``--src`` and records every evaluation; then runs it ``--repeat`` more
times, each in a fresh problem (its search space's memos empty) and optimizer, with an evaluator that returns
the recorded evaluation of the candidate it is given (no evaluation work). Prints per task the CPU seconds of
the replays' asks (each, and their median) and the hash of the candidates asked with their scores (the same as
bench_front_ga's: the same search path).
"""
from __future__ import annotations

import argparse
import hashlib
import json
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--src", default=str(ROOT), help="the checkout whose src/ runs the search")
    ap.add_argument("--budget", default="200evals")
    ap.add_argument("--tasks", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--only", default="", help="whitman2020_g5o5 or bpo2024")
    args = ap.parse_args()
    sys.path.insert(0, str(Path(args.src).resolve() / "src"))
    sys.path.insert(1, str(Path(__file__).resolve().parent))
    from profile_evaluator import family_tasks

    from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
    from robodesign.design.problem import Problem
    from robodesign.design.solve import warm_up
    from robodesign.solvers import ik_kernel
    ik_kernel.warm_up()
    warm_up()
    import robodesign
    print("# src:", Path(robodesign.__file__).parent, flush=True)
    for name in ("whitman2020_g5o5", "bpo2024"):
        if args.only and name != args.only:
            continue
        for f in family_tasks(name, args.tasks, 0):
            problem = Problem.build(f, "robodesign_arm", "cyc")
            ev = Evaluator(EvaluatorSpec(problem, evaluation_settings(), seed=0))
            seen: dict = {}

            def recording(c, ev=ev, seen=seen):
                seen[c.key()] = e = ev(c)
                return e
            _, h0 = _search(problem, recording, args.budget)
            runs = [_search(Problem.build(f, "robodesign_arm", "cyc"), lambda c, seen=seen: seen[c.key()], args.budget)
                    for _ in range(args.repeat)]
            print(json.dumps({"task": f.name, "ask_cpu_seconds": [round(s, 3) for s, _ in runs],
                              "median": round(statistics.median(s for s, _ in runs), 3),
                              "hash": h0, "same_path": all(h == h0 for _, h in runs)}), flush=True)


def _search(problem, evaluator, budget: str):
    """(CPU seconds spent in the optimizer's ask, hash of the evaluations in ask order) of one search."""
    from robodesign.design.optimize import Budget, SerialExecutor, Study, create_optimizer
    opt = create_optimizer("genetic", problem, seed=0, options={})
    spent = [0.0]
    ask = opt.ask

    def timed():
        t = time.process_time()
        try:
            return ask()
        finally:
            spent[0] += time.process_time() - t
    opt.ask = timed
    res = Study(opt, SerialExecutor(evaluator), Budget.parse(budget), batch_size=16).run()
    h = hashlib.md5(json.dumps([(e.candidate.key(), e.stage, e.goals_reached, e.feasible, e.cost, e.score)
                                for e in res.history]).encode()).hexdigest()[:12]
    return spent[0], h


if __name__ == "__main__":
    main()
