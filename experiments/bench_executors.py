"""Benchmark: parallel efficiency of the process and Ray executors with 2 workers, and the overhead the
experiment runner adds per evaluation.

    .venv/bin/python experiments/bench_executors.py [--n 40]

The same fixed list of candidates (random *feasible* designs for robodesign/pick_and_place with the built-in
module set, so that every evaluation runs the whole pipeline and costs about the same) is evaluated by a bare evaluator loop (T_serial), by each executor with 2 workers (efficiency =
T_serial / (2·T_parallel)), and by the full runner (storage, progress, ask/tell) with the serial executor
(overhead = T_runner / T_serial − 1; the report writing at the end is excluded).
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
os.environ.setdefault("RAY_AUTH_MODE", "disabled")


def main():
    from robodesign.evaluator import Evaluator, EvaluatorSpec
    from robodesign.experiment.executors import ProcessPool, RayPool
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=40)
    args = ap.parse_args()
    spec = EvaluatorSpec(task="robodesign/pick_and_place", module_set="robodesign_arm", cost="cyc", seed=0)
    ev = Evaluator(spec)
    space = ev.search_space()
    rng = np.random.default_rng(0)
    # candidates of similar cost: designs that go through every stage (feasible), as the issue asks
    cands = []
    while len(cands) < args.n:
        c = space.random_candidate(rng)
        if ev(c, space.base_bounds).feasible:
            cands.append(c)
    ev.cache.clear()
    t0 = time.perf_counter()
    ref = [ev.evaluate(c) for c in cands]
    t_serial = time.perf_counter() - t0
    print(f"serial bare loop: {args.n} evaluations in {t_serial:.2f} s ({t_serial / args.n * 1e3:.0f} ms each, "
          f"{sum(e.feasible for e in ref)} feasible)")
    for name, cls in (("process", ProcessPool), ("ray", RayPool)):
        pool = cls({"s": spec}, workers=2)
        try:
            pool.map("s", cands[:2])  # start-up and warm-up of the workers, not timed
            t0 = time.perf_counter()
            out = pool.map("s", cands)
            t = time.perf_counter() - t0
        finally:
            pool.close()
        same = all(a.candidate.key() == b.candidate.key() and a.cost == b.cost and a.stage == b.stage
                   for a, b in zip(out, ref))
        print(f"{name:7s} executor, 2 workers: {t:.2f} s -> parallel efficiency {t_serial / (2 * t) * 100:.0f} % "
              f"(results identical to serial: {same})")
    # runner overhead: the full experiment loop (random optimizer asks, ask/tell bookkeeping, SQLite commit per
    # evaluation, progress) minus the time spent inside Evaluator.evaluate, relative to the latter; the
    # second of two runs is reported (the first pays one-off imports)
    import robodesign.evaluator as evm
    from robodesign.experiment.config import load_experiment
    from robodesign.experiment.runner import make_progress, run_experiment
    from robodesign.optimize import load_optimizer
    inside = [0.0, 0.0]  # seconds inside Evaluator.evaluate, inside the optimizer's ask()
    original = evm.Evaluator.evaluate
    opt_cls = load_optimizer("random")
    original_ask = opt_cls.ask

    def timed(self, *a, **k):
        t = time.perf_counter()
        try:
            return original(self, *a, **k)
        finally:
            inside[0] += time.perf_counter() - t

    def timed_ask(self):
        t = time.perf_counter()
        try:
            return original_ask(self)
        finally:
            inside[1] += time.perf_counter() - t
    evm.Evaluator.evaluate = timed
    opt_cls.ask = timed_ask
    with tempfile.TemporaryDirectory() as tmp:
        cfg = Path(tmp) / "bench.yaml"
        cfg.write_text(f"name: bench\nmodules: robodesign_arm\ntasks: [robodesign/pick_and_place]\ncost: cyc\n"
                       f"optimizers: [random]\nbudget: {args.n}evals\nseeds: [0]\nexecutor: serial\n")
        exp, text = load_experiment(cfg)
        for rep in range(2):
            inside[0] = inside[1] = 0.0
            t0 = time.perf_counter()
            run_experiment(exp, Path(tmp) / f"out{rep}", config_text=text, config_path=cfg, executor="serial",
                           progress=make_progress("none"), report=False)
            total = time.perf_counter() - t0
    evm.Evaluator.evaluate = original
    opt_cls.ask = original_ask
    runner = total - inside[0] - inside[1]
    print(f"runner overhead: {total:.2f} s for {args.n} evaluations: {inside[0]:.2f} s inside the evaluator, "
          f"{inside[1]:.2f} s in the optimizer's ask() -> the runner adds {100 * runner / inside[0]:.1f} % per "
          f"evaluation ({runner / args.n * 1e3:.1f} ms each; with the optimizer {100 * (total - inside[0]) / inside[0]:.1f} %)")


if __name__ == "__main__":
    main()
