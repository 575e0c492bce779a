"""The time scaling alone (issue 25): every ``time_parameterize`` call of feasible PTP_3 evaluations, replayed.

    nice .venv/bin/python experiments/bench_timing.py [--src CHECKOUT ...] [--rounds 2] [--seeds 20] [--repeat 5]

For each checkout (default: this one) and round, alternating, a fresh process evaluates the known-good IMPROV arm
``1,21,4,22,5,23,12`` on simple/PTP_3 at the nominal base for ``--seeds`` study seeds (as
``profile_evaluator.py --only good``), records the (robot, joint path, options) of every ``time_parameterize`` call
the goal planner makes, then times ``--repeat`` replays of all of them (process CPU time) and prints the median
and best per evaluation in ms, with a hash of every replayed trajectory (t, q, dq, ddq bytes): equal hashes mean
the checkouts time the same paths into the same trajectories bit for bit. The compiled kernels of each checkout
must be in its numba cache (``python -m robodesign.solvers.topp_kernel`` etc.); a checkout without
``robodesign.solvers.topp_kernel`` is timed as it is.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "cobra"
GOOD = ("1", "21", "4", "22", "5", "23", "12")


def child(seeds: int, repeat: int) -> dict:
    import numpy as np

    from robodesign.design import goal_planner
    from robodesign.design.evaluator import Evaluator, EvaluatorSpec
    from robodesign.design.problem import Problem
    from robodesign.design.search_space import Candidate
    from robodesign.design.solve import warm_up
    from robodesign.solvers import ik_kernel, timing
    ik_kernel.warm_up()
    try:
        from robodesign.solvers import topp_kernel
        topp_kernel.warm_up()
    except ImportError:
        pass
    warm_up()
    ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
    Evaluator(EvaluatorSpec(ptp3)).evaluate(Candidate(GOOD))   # warm-up
    calls = []
    real = goal_planner.time_parameterize

    def record(robot, path, **kw):
        calls.append((robot, np.array(path, dtype=float), kw))
        return real(robot, path, **kw)
    goal_planner.time_parameterize = record
    for s in range(seeds):
        Evaluator(EvaluatorSpec(ptp3, seed=s)).evaluate(Candidate(GOOD))
    goal_planner.time_parameterize = real
    digest = hashlib.sha256()
    for robot, path, kw in calls:
        tr = timing.time_parameterize(robot, path, **kw)
        for x in (tr.t, tr.q, tr.dq, tr.ddq):
            digest.update(x.tobytes())
    cpu = []
    for _ in range(repeat):
        t = time.process_time()
        for robot, path, kw in calls:
            timing.time_parameterize(robot, path, **kw)
        cpu.append((time.process_time() - t) / seeds * 1e3)
    import robodesign
    return {"src": str(Path(robodesign.__file__).parent), "calls": len(calls), "median": statistics.median(cpu),
            "best": min(cpu), "hash": digest.hexdigest()[:16]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--src", nargs="+", default=[str(ROOT)], help="checkouts whose src/ is timed (alternating)")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(child(args.seeds, args.repeat)))
        return
    print("| checkout | round | calls | ms per evaluation (median) | best | trajectories' hash |\n|---|---:|---:|---:|---:|---|")
    for r in range(args.rounds):
        for src in args.src:
            env_path = str(Path(src).resolve() / "src")
            out = subprocess.run([sys.executable, __file__, "--child", "--seeds", str(args.seeds), "--repeat",
                                  str(args.repeat)], capture_output=True, text=True,
                                 env={**__import__("os").environ, "PYTHONPATH": env_path})
            if out.returncode:
                print(out.stderr[-2000:], file=sys.stderr)
                continue
            d = json.loads(out.stdout.strip().splitlines()[-1])
            print(f"| {src} | {r + 1} | {d['calls']} | {d['median']:.2f} | {d['best']:.2f} | {d['hash']} |", flush=True)


if __name__ == "__main__":
    main()
