"""The genetic search's evaluations per second (issue 25), in one process, with its per-stage time.

    nice .venv/bin/python experiments/bench_front_ga.py --src . [--budget 300evals] [--tasks 2] [--seed 0]

Runs ``optimize``'s study (optimizer ``genetic``, the optimizers' evaluation settings, ``--seed``, one
process, batches of 16) on ``--tasks`` generated tasks of whitman2020 g5o5 (free base) and bpo2024
(mixed), the profile tasks of experiments/profile_evaluator.py, with the built-in module set. ``--src``: the
checkout whose src/ is evaluated (to compare two checkouts in one run). Prints per task: evaluations,
seconds, evaluations/s (wall and process CPU time), how many stopped at each stage, the summed seconds of every stage,
the seconds spent in the optimizer's ``ask`` (its own work, outside the evaluations), the best score
and a hash of every evaluation's (stage, goals reached, feasible, cost, score) in ask order: equal hashes
mean the search took the same path with the same verdicts.
"""
from __future__ import annotations

import argparse
import cProfile
import hashlib
import json
import pstats
import sys
import time
from collections import Counter, defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--src", default=str(ROOT), help="the checkout whose src/ is evaluated")
    ap.add_argument("--budget", default="300evals")
    ap.add_argument("--tasks", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--only", default="", help="whitman2020_g5o5 or bpo2024")
    ap.add_argument("--profile", type=int, default=0, help="print the cProfile's top N functions")
    ap.add_argument("--sort", default="cumulative", help="the profile's order (cumulative, tottime)")
    args = ap.parse_args()
    sys.path.insert(0, str(Path(args.src).resolve() / "src"))

    from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
    from robodesign.design.optimize import Budget, SerialExecutor, Study, create_optimizer
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
        # the tasks of experiments/profile_evaluator.py --tasks N (generated there, or here when missing; that
        # script puts the same --src first)
        from profile_evaluator import family_tasks
        for f in family_tasks(name, args.tasks, 0):
            problem = Problem.build(f, "robodesign_arm", "cyc")
            ev = Evaluator(EvaluatorSpec(problem, evaluation_settings(), seed=args.seed))
            opt = create_optimizer("genetic", problem, seed=args.seed, options={})
            prof = cProfile.Profile() if args.profile else None
            asked = _timed_ask(opt)
            c0 = time.process_time()
            t0 = time.perf_counter()
            if prof:
                prof.enable()
            res = Study(opt, SerialExecutor(ev), Budget.parse(args.budget), batch_size=16).run()
            dt = time.perf_counter() - t0
            cpu = time.process_time() - c0
            if prof:
                prof.disable()
                pstats.Stats(prof).sort_stats(args.sort).print_stats(args.profile)
            stops = Counter(e.stage for e in res.history)
            secs: dict = defaultdict(float)
            for e in res.history:
                for s in e.stages:
                    secs[s["name"]] += s["seconds"]
            h = hashlib.md5(json.dumps([(e.candidate.key(), e.stage, e.goals_reached, e.feasible, e.cost, e.score)
                                        for e in res.history]).encode()).hexdigest()[:12]
            n = len(res.history)
            print(json.dumps({"task": f.name, "evaluations": n, "seconds": round(dt, 2),
                              "evals_per_s": round(n / dt, 2),
                              "cpu_seconds": round(cpu, 2), "evals_per_cpu_s": round(n / cpu, 2), "stopped_at": dict(stops),
                              "stage_seconds": {k: round(v, 2) for k, v in secs.items()},
                              "ask_seconds": round(asked[0], 2),
                              "best": None if res.best is None else res.best.score, "hash": h}), flush=True)


def _timed_ask(opt) -> list:
    """Wrap ``opt.ask`` so that the seconds spent in it (the optimizer's own work: breeding, base sampling,
    the search space's reach bounds) add up in the returned one-element list."""
    spent = [0.0]
    ask = opt.ask

    def timed():
        t = time.perf_counter()
        try:
            return ask()
        finally:
            spent[0] += time.perf_counter() - t
    opt.ask = timed
    return spent


if __name__ == "__main__":
    main()
