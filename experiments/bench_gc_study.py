"""The garbage collector's share of a genetic search (issue 25): per task of experiments/bench_front_ga.py (200
evaluations, seed 0, batches of 16), the process CPU seconds and, per generation, how many collections ran and the
seconds they took (``gc.callbacks``), with the number of objects the collector tracks at the end.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python experiments/bench_gc_study.py --src CHECKOUT [--rounds 3]

Checkouts before core/gc_heap.py run their studies with the whole heap in the collector's generations; later
ones freeze the heap the process started with for each study (:func:`robodesign.core.gc_heap.startup_heap_frozen`).
The search's path hash is printed too: the collector's timing must not change it.
"""
from __future__ import annotations

import argparse
import gc
import hashlib
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--src", default=str(ROOT), help="the checkout whose src/ is evaluated")
    ap.add_argument("--tasks", type=int, default=2)
    ap.add_argument("--budget", default="200evals")
    args = ap.parse_args()
    sys.path.insert(0, str(Path(args.src).resolve() / "src"))
    sys.path.insert(1, str(ROOT / "experiments"))
    from profile_evaluator import family_tasks

    from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
    from robodesign.design.optimize import Budget, SerialExecutor, Study, create_optimizer
    from robodesign.design.problem import Problem
    from robodesign.design.solve import warm_up
    from robodesign.solvers import ik_kernel
    ik_kernel.warm_up()
    warm_up()
    import robodesign
    print("# src:", Path(robodesign.__file__).parent, flush=True)
    spent = {g: [0, 0.0] for g in range(3)}
    started = [0.0]

    def timer(phase, info):
        if phase == "start":
            started[0] = time.perf_counter()
        else:
            s = spent[info["generation"]]
            s[0] += 1
            s[1] += time.perf_counter() - started[0]
    gc.callbacks.append(timer)
    for name in ("whitman2020_g5o5", "bpo2024"):
        for f in family_tasks(name, args.tasks, 0):
            problem = Problem.build(f, "robodesign_arm", "cyc")
            ev = Evaluator(EvaluatorSpec(problem, evaluation_settings(), seed=0))
            opt = create_optimizer("genetic", problem, seed=0, options={})
            for s in spent.values():
                s[:] = [0, 0.0]
            c0 = time.process_time()
            res = Study(opt, SerialExecutor(ev), Budget.parse(args.budget), batch_size=16).run()
            cpu = time.process_time() - c0
            h = hashlib.md5(json.dumps([(e.candidate.key(), e.stage, e.goals_reached, e.feasible, e.cost, e.score)
                                        for e in res.history]).encode()).hexdigest()[:12]
            print(json.dumps({"task": f.name, "cpu_seconds": round(cpu, 3),
                              "collections": {g: s[0] for g, s in spent.items()},
                              "collection_seconds": {g: round(s[1], 3) for g, s in spent.items()},
                              "gc_seconds": round(sum(s[1] for s in spent.values()), 3),
                              "tracked_objects": len(gc.get_objects()), "hash": h}), flush=True)


if __name__ == "__main__":
    main()
