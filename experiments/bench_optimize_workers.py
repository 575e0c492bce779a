"""Benchmark: ``robodesign optimize --workers N`` on simple/PTP_3 with IMPROV.

    flock /tmp/robodesign-bench.lock nice -n 5 .venv/bin/python experiments/bench_optimize_workers.py \
        [--rate-evals 160] [--rounds 2] [--seeds 0,1,2,3,4] [--target 2.9] [--max-evals 600]

1. Throughput: evaluations per second of the random optimizer (batches of 16, the CLI's default) with
   1 worker (in-process, as ``--workers 1``) and 2 worker processes (``--workers 2``), in alternating rounds;
   the ratio of the medians. Pool start-up (spawning the workers, loading task and modules) is reported
   separately and not counted in the rate.
2. Time to a good design: genetic (batches of 16) until its best checked cycle time is ≤ ``--target`` s
   (the best known design is 2.75 s), for each seed with 1 and with 2 workers; wall time from the start of
   the search (pool start-up included), median over the seeds. A seed that does not get there within
   ``--max-evals`` evaluations counts as not reached (shown as "> t").

The searches are the ones the CLI runs (same evaluator spec, executors and batch size); with the same seed
and batch size both worker counts evaluate the same candidates, so the time ratio is the speed-up.
"""
from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

from robodesign.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
from robodesign.experiment.executors import ProcessPool
from robodesign.optimize import Budget, SerialExecutor, Study, create_optimizer
from robodesign.problem import Problem

HERE = Path(__file__).resolve().parent
SHARED = HERE.parents[1] / "shared" / "cobra"
TASK = SHARED / "tasks" / "simple" / "PTP_3.json"
IMPROV = SHARED / "modules" / "IMPROV"
BATCH = 16


class _Reached(Exception):
    pass


def search(optimizer: str, seed: int, workers: int, evaluations: int, target=None) -> dict:
    t0 = time.perf_counter()
    problem = Problem.build(str(TASK), str(IMPROV), "cyc")
    spec = EvaluatorSpec(problem, evaluation_settings(), seed=seed)
    pool = None
    if workers == 1:
        executor = SerialExecutor(Evaluator(spec))
    else:
        pool = ProcessPool({"s": spec}, workers)
        executor = pool.bind("s")
    startup = time.perf_counter() - t0
    opt = create_optimizer(optimizer, problem, seed=seed)
    hit = {}

    def on_eval(i, e, best):
        if target is not None and best is not None and best.feasible and best.cost <= target:
            hit.update(evaluation=i + 1, seconds=time.perf_counter() - t0, cost=best.cost)
            raise _Reached

    ts = time.perf_counter()
    n = None
    try:
        res = Study(opt, executor, Budget(evaluations=evaluations), batch_size=BATCH, on_evaluation=on_eval).run()
        n = len(res.history)
    except _Reached:
        pass
    finally:
        if pool is not None:
            pool.close()
    search_s = time.perf_counter() - ts
    return {"optimizer": optimizer, "seed": seed, "workers": workers, "startup_s": startup, "search_s": search_s,
            "evaluations": n if n is not None else hit["evaluation"], "reached": hit or None,
            "best": None if n is None or opt.best is None or not opt.best.feasible else opt.best.cost}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rate-evals", type=int, default=160)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--seeds", default="0,1,2,3,4")
    ap.add_argument("--target", type=float, default=2.9)
    ap.add_argument("--max-evals", type=int, default=600)
    ap.add_argument("--skip-rate", action="store_true")
    ap.add_argument("--out", default=str(HERE / "results" / "optimize_workers.json"))
    a = ap.parse_args()
    out = {"rate": [], "target": []}
    if not a.skip_rate:
        for r in range(a.rounds):
            for w in (1, 2) if r % 2 == 0 else (2, 1):
                x = search("random", 0, w, a.rate_evals)
                x["rate"] = x["evaluations"] / x["search_s"]
                out["rate"].append(x)
                print(f"rate round {r}: {w} worker(s) {x['rate']:.1f} evaluations/s ({x['evaluations']} in "
                      f"{x['search_s']:.1f} s, start-up {x['startup_s']:.1f} s)", flush=True)
        med = {w: statistics.median(x["rate"] for x in out["rate"] if x["workers"] == w) for w in (1, 2)}
        print(f"throughput: 1 worker {med[1]:.1f}/s, 2 workers {med[2]:.1f}/s, ratio {med[2] / med[1]:.2f}x "
              f"(target >= 1.8x)", flush=True)
        out["rate_median"] = med
    for seed in [int(s) for s in a.seeds.split(",")]:
        for w in (1, 2) if seed % 2 == 0 else (2, 1):
            x = search("genetic", seed, w, a.max_evals, a.target)
            out["target"].append(x)
            h = x["reached"]
            print(f"genetic seed {seed}, {w} worker(s): " + (
                f"cyc {h['cost']:.3f} <= {a.target} at evaluation {h['evaluation']}, {h['seconds']:.1f} s" if h else
                f"not reached in {x['evaluations']} evaluations ({x['search_s'] + x['startup_s']:.1f} s, best "
                f"{x['best']})"), flush=True)
    for w in (1, 2):
        runs = [x for x in out["target"] if x["workers"] == w]
        times = [x["reached"]["seconds"] if x["reached"] else float("inf") for x in runs]
        med = statistics.median(times)
        print(f"time to cyc <= {a.target}: {w} worker(s) median {med:.1f} s over {len(runs)} seeds "
              f"({sum(x['reached'] is not None for x in runs)} reached)")
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(out, indent=1, default=str))
    print(f"written {a.out}")


if __name__ == "__main__":
    main()
