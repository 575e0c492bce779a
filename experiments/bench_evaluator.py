"""Benchmark: evaluator throughput on simple/PTP_3 with IMPROV up to (and including) the IK stage —
the cheap stages of the hierarchical elimination (assembly + model, base, reach bound, collision-checked
IK of every goal) — on one core, for random candidates of the default search space.

    .venv/bin/python experiments/bench_evaluator.py [--n 600] [--restarts 20,60,150,300,1000] [--solutions 1]

``--solutions``: distinct IK solutions collected per goal. 1 screens reachability only; the evaluator's
full pipeline collects ``SolveSettings.ik_solutions`` (48) for the sequencing, which costs extra restarts
on the candidates that reach every goal (``--solutions 48`` measures that).

Also reports how many candidates each stage eliminates and whether fewer IK restarts lose any
candidate that the largest budget finds (false negatives). ``ROBODESIGN_JIT=0`` measures the pure-Python
IK loop instead of the compiled one.
"""
from __future__ import annotations

import argparse
import time
from collections import Counter
from pathlib import Path

import numpy as np

from robodesign import load_module_set
from robodesign.design.search_space import SearchSpace
from robodesign.design.solve import SolveSettings, solve
from robodesign.formats.task_io import load_task

SHARED = Path(__file__).resolve().parents[2] / "shared" / "cobra"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=600)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--restarts", default="20,60,150,300,1000", help="IK restarts per goal to compare")
    ap.add_argument("--solutions", type=int, default=1, help="distinct IK solutions collected per goal")
    args = ap.parse_args()
    task = load_task(SHARED / "tasks" / "simple" / "PTP_3.json")
    ms = load_module_set(SHARED / "modules" / "IMPROV")
    space = SearchSpace(ms)
    rng = np.random.default_rng(args.seed)
    cands = [space.random_order(rng) for _ in range(args.n)]
    from robodesign.solvers import ik_kernel
    ik_kernel.warm_up()  # the compiled IK from the start, also on a cold cache (no-op with ROBODESIGN_JIT=0)
    solve(task, ms, cands[0], settings=SolveSettings(stop_after="ik"))  # warm-up (meshes)
    passed = {}
    for r in [int(x) for x in args.restarts.split(",")]:
        st = Counter()
        ok = set()
        t0 = time.perf_counter()
        for i, order in enumerate(cands):
            res = solve(task, ms, order, settings=SolveSettings(seed=i, stop_after="ik", ik_restarts=r,
                                                                ik_solutions=args.solutions))
            st[res.stage] += 1
            if res.stage == "done":
                ok.add(i)
        dt = time.perf_counter() - t0
        passed[r] = ok
        print(f"IK restarts {r:4d}: {args.n} candidates in {dt:.2f} s -> {args.n / dt:.0f} candidates/s; "
              f"eliminated by stage: {dict(st)}")
    rs = sorted(passed)
    if len(rs) > 1:
        for r in rs[:-1]:
            lost = passed[rs[-1]] - passed[r]
            print(f"candidates passing IK with {rs[-1]} restarts but not with {r}: {len(lost)} of {len(passed[rs[-1]])}")


if __name__ == "__main__":
    main()
