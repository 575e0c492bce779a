"""Benchmark: ``robodesign optimize --workers N`` on simple/PTP_3 with IMPROV.

    flock /tmp/robodesign-bench.lock nice -n 5 .venv/bin/python experiments/bench_optimize_workers.py \
        [--rate-evals 640] [--rounds 7] [--ablation] [--seeds 0,1,2,3,4] [--target 2.9] [--max-evals 600]

Every measurement runs in a fresh Python process (the same cold start for every worker count: imports,
loading the compiled IK kernels, task and modules) and starts from ``robodesign.design.solve.warm_up`` — what the
pool's workers do when they start — so that the rate compares steady states; the start-up is reported apart.

1. Throughput: evaluations per second of the random optimizer (batches of 16, the CLI's default) with
   1 worker (in-process, as ``--workers 1``) and 2 worker processes (``--workers 2``: chunked messages,
   random search asked ahead of its tells), round r with seed r for both worker counts (the same
   candidates), the order alternating; the median over the rounds of the per-round ratio, and the same
   ratio for the whole command (start-up included). Also the CPU seconds per evaluation (driver and
   workers, start-up excluded: a pool started and closed without work is measured in every round), which
   the machine's other load hardly changes. ``--ablation`` adds 2-worker rounds with one candidate per
   message (``chunk_size=1``) and with the batch barrier (no asking ahead), to show what each part gives.
2. Time to a good design: genetic (batches of 16) until its best checked cycle time is ≤ ``--target`` s
   (the best known design is 2.75 s), for each seed with 1 and with 2 workers; wall time from the start of
   the command (task, modules and pool start-up included), median over the seeds. A seed that does not get
   there within ``--max-evals`` evaluations counts as not reached (shown as "> t").

The searches are the ones the CLI runs (same evaluator spec, executors and batch size); with the same seed
and batch size both worker counts evaluate the same candidates, so the time ratio is the speed-up.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE.parent / "docs" / "results"  # the measured records behind docs/benchmarks.md
SHARED = HERE.parents[1] / "shared" / "cobra"
TASK = SHARED / "tasks" / "simple" / "PTP_3.json"
IMPROV = SHARED / "modules" / "IMPROV"
BATCH = 16


class _Reached(Exception):
    pass


def search(optimizer: str, seed: int, workers: int, evaluations: int, target=None, chunk_size=None,
           ask_ahead: bool = True) -> dict:
    """One search in this process, as ``robodesign optimize`` runs it."""
    t0 = time.perf_counter()
    from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
    from robodesign.experiment.executors import ProcessPool
    from robodesign.design.optimize import Budget, SerialExecutor, Study, create_optimizer
    from robodesign.design.problem import Problem
    from robodesign.design.solve import warm_up
    problem = Problem.build(str(TASK), str(IMPROV), "cyc")
    spec = EvaluatorSpec(problem, evaluation_settings(), seed=seed)
    pool = None
    if workers == 1:
        executor = SerialExecutor(Evaluator(spec))
        warm_up()  # what every pool worker does when it starts
    else:
        pool = ProcessPool({"s": spec}, workers, chunk_size)
        executor = pool.bind("s")
    startup = time.perf_counter() - t0
    opt = create_optimizer(optimizer, problem, seed=seed)
    if not ask_ahead:
        opt.independent_asks = False
    hit = {}

    def on_eval(i, e, best):
        if target is not None and best is not None and best.feasible and best.cost <= target:
            hit.update(evaluation=i + 1, seconds=time.perf_counter() - t0, cost=best.cost)
            raise _Reached

    ts, cpu = time.perf_counter(), time.process_time()
    n = None
    try:
        res = Study(opt, executor, Budget(evaluations=evaluations), batch_size=BATCH, on_evaluation=on_eval).run()
        n = len(res.history)
    except _Reached:
        pass
    finally:
        search_s = time.perf_counter() - ts
        messages = pool.messages if pool is not None else 0
        if pool is not None:
            pool.close()
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)  # the pool's workers, joined by close()
    return {"optimizer": optimizer, "seed": seed, "workers": workers, "chunk_size": chunk_size,
            "ask_ahead": ask_ahead, "startup_s": startup, "search_s": search_s,
            "parent_cpu_s": time.process_time() - cpu, "workers_cpu_s": kids.ru_utime + kids.ru_stime,
            "messages": messages,
            "evaluations": n if n is not None else hit["evaluation"], "reached": hit or None,
            "best": None if opt.best is None or not opt.best.feasible else opt.best.cost,
            "keys": [e.candidate.key() for e in opt.history], "eval_seconds": [e.seconds for e in opt.history]}


def makespan(seconds, workers: int = 2) -> float:
    """Wall time of evaluations taking ``seconds`` on ``workers`` that each take the next one when free."""
    free = [0.0] * workers
    for s in seconds:
        i = free.index(min(free))
        free[i] += s
    return max(free)


def ideal_ratios(seconds, batch: int = BATCH, workers: int = 2) -> tuple:
    """The best speed-up any executor could give on ``workers`` for evaluations taking ``seconds`` (as measured
    in one process), with free messages: waiting at the end of every batch for its slowest evaluation, and
    asking ahead (no wait)."""
    total = sum(seconds)
    barrier = sum(makespan(seconds[i:i + batch], workers) for i in range(0, len(seconds), batch))
    return total / barrier, total / makespan(seconds, workers)


def fresh(optimizer: str, seed: int, workers: int, evaluations: int, target=None, chunk_size=None,
          ask_ahead: bool = True) -> dict:
    """:func:`search` in a new Python process."""
    args = {"optimizer": optimizer, "seed": seed, "workers": workers, "evaluations": evaluations, "target": target,
            "chunk_size": chunk_size, "ask_ahead": ask_ahead}
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, __file__, "--one", json.dumps(args)], capture_output=True, text=True,
                       check=True)
    x = json.loads(r.stdout.strip().splitlines()[-1])
    x["process_s"] = time.perf_counter() - t0  # the whole command, Python's start included
    return x


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    # a 320-evaluation search lasts ~1 s on one worker: this VM's speed drifts by ±10 % over seconds, so
    # longer searches and more rounds make the median ratio steadier (all rounds are printed and stored)
    ap.add_argument("--rate-evals", type=int, default=640)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--ablation", action="store_true", help="also 2 workers with chunk_size=1 and without ask-ahead")
    ap.add_argument("--seeds", default="0,1,2,3,4")
    ap.add_argument("--target", type=float, default=2.9)
    ap.add_argument("--max-evals", type=int, default=600)
    ap.add_argument("--skip-rate", action="store_true")
    ap.add_argument("--skip-target", action="store_true")
    ap.add_argument("--one", help=argparse.SUPPRESS)
    ap.add_argument("--out", default=str(RESULTS / "optimize_workers.json"))
    a = ap.parse_args()
    if a.one:
        print(json.dumps(search(**json.loads(a.one))))
        return
    out = {"command": " ".join(sys.argv), "cpus": os.cpu_count(), "load_avg_start": os.getloadavg(),
           "rate": [], "target": []}
    print(f"load average at start: {out['load_avg_start']}", flush=True)
    variants = [("2 workers", dict(workers=2))]
    if a.ablation:
        variants += [("2 workers, chunk 1", dict(workers=2, chunk_size=1)),
                     ("2 workers, no ask-ahead", dict(workers=2, ask_ahead=False))]
    variants = [("1 worker", dict(workers=1))] + variants
    if not a.skip_rate:
        for r in range(a.rounds):
            order = variants if r % 2 == 0 else variants[::-1]
            # the CPU the pool's start-up takes (spawn, load, warm up), to count the workers' CPU per evaluation
            idle = fresh("random", r, 2, 0)
            row = {}
            for name, kw in order:
                x = fresh("random", r, evaluations=a.rate_evals, **kw)
                x["rate"] = x["evaluations"] / x["search_s"]
                x["variant"], x["round"] = name, r
                # CPU seconds per evaluation, start-up excluded (driver + workers): what the rate would be
                # on idle cores, whatever else the machine runs
                x["cpu_per_eval_ms"] = 1000 * (x["parent_cpu_s"] + (x["workers_cpu_s"] - idle["workers_cpu_s"]
                                                                     if x["workers"] > 1 else 0.0)) / x["evaluations"]
                keys = x.pop("keys")
                row[name] = x
                out["rate"].append(x)
                print(f"rate round {r}, {name}: {x['rate']:.1f} evaluations/s ({x['evaluations']} in "
                      f"{x['search_s']:.2f} s, start-up {x['startup_s']:.2f} s, {x['messages']} messages, parent CPU "
                      f"{x['parent_cpu_s']:.2f} s, CPU {x['cpu_per_eval_ms']:.2f} ms per evaluation, command "
                      f"{x['process_s']:.2f} s)", flush=True)
                row.setdefault("keys", keys)
                assert keys == row["keys"], "the worker counts evaluated different candidates"
        out["rate_summary"] = {}
        base = [x for x in out["rate"] if x["variant"] == "1 worker"]
        ideal = [ideal_ratios(b["eval_seconds"]) for b in base]
        out["ideal"] = {"batch_barrier": [i[0] for i in ideal], "ask_ahead": [i[1] for i in ideal]}
        print("ideal 2-worker ratios from the 1-worker evaluation times (free messages): waiting at batch ends "
              + ", ".join(f"{i[0]:.2f}" for i in ideal) + "x; asking ahead " + ", ".join(f"{i[1]:.2f}" for i in ideal)
              + "x", flush=True)
        for name, _ in variants[1:]:
            runs = {x["round"]: x for x in out["rate"] if x["variant"] == name}
            ratio = statistics.median(runs[b["round"]]["rate"] / b["rate"] for b in base)
            cmd = statistics.median(b["process_s"] / runs[b["round"]]["process_s"] for b in base)
            cpu = statistics.median(runs[b["round"]]["cpu_per_eval_ms"] / b["cpu_per_eval_ms"] for b in base)
            per_round = [runs[b["round"]]["rate"] / b["rate"] for b in base]
            # all rounds pooled: total evaluations over total search time, per variant
            pooled = (sum(x["evaluations"] for x in runs.values()) / sum(x["search_s"] for x in runs.values())) / \
                (sum(b["evaluations"] for b in base) / sum(b["search_s"] for b in base))
            out["rate_summary"][name] = {"ratio": ratio, "per_round": per_round, "pooled_ratio": pooled,
                                         "command_ratio": cmd, "cpu_per_eval_ratio": cpu,
                                         "median_rate": statistics.median(x["rate"] for x in runs.values())}
            print(f"throughput {name} / 1 worker: {ratio:.2f}x (median of {len(base)} rounds; target >= 1.8x), "
                  f"whole command {cmd:.2f}x; median rates {statistics.median(b['rate'] for b in base):.1f} vs "
                  f"{out['rate_summary'][name]['median_rate']:.1f}/s; CPU per evaluation {cpu:.2f}x 1 worker's; "
                  f"per round {', '.join(f'{r:.2f}' for r in per_round)}; all rounds pooled {pooled:.2f}x",
                  flush=True)
    if not a.skip_target:
        for seed in [int(s) for s in a.seeds.split(",")]:
            keys = {}
            for w in (1, 2) if seed % 2 == 0 else (2, 1):
                x = fresh("genetic", seed, w, a.max_evals, a.target)
                keys[w] = x.pop("keys")
                out["target"].append(x)
                h = x["reached"]
                print(f"genetic seed {seed}, {w} worker(s): " + (
                    f"cyc {h['cost']:.3f} <= {a.target} at evaluation {h['evaluation']}, {h['seconds']:.1f} s" if h else
                    f"not reached in {x['evaluations']} evaluations ({x['search_s'] + x['startup_s']:.1f} s, best "
                    f"{x['best']})") + f" (start-up {x['startup_s']:.1f} s)", flush=True)
            assert keys[1] == keys[2], f"seed {seed}: the worker counts evaluated different candidates"
            one = next(x for x in out["target"] if x["workers"] == 1 and x["seed"] == seed)
            print(f"  ideal 2-worker ratio of this search with batches of {BATCH}: "
                  f"{ideal_ratios(one['eval_seconds'])[0]:.2f}x", flush=True)
        for w in (1, 2):
            runs = [x for x in out["target"] if x["workers"] == w]
            times = [x["reached"]["seconds"] if x["reached"] else float("inf") for x in runs]
            med = statistics.median(times)
            out[f"target_median_{w}"] = med
            print(f"time to cyc <= {a.target}: {w} worker(s) median {med:.1f} s over {len(runs)} seeds "
                  f"({sum(x['reached'] is not None for x in runs)} reached)", flush=True)
    out["load_avg_end"] = os.getloadavg()
    print(f"load average at end: {out['load_avg_end']}")
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(out, indent=1, default=str))
    print(f"written {a.out}")


if __name__ == "__main__":
    main()
