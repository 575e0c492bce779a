"""timing5's copy of experiments/bench_paired.py (adds the timing stage's paired ratio and sums). Paired A/B of the evaluator (issue 25): two checkouts evaluate the same candidates in turn, candidate by candidate.

    OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_paired.py \
        --a CHECKOUT_A --b CHECKOUT_B [--only good,whitman2020_g5o5,bpo2024] [--feasible 20] [--candidates 300]

This machine's speed swings by up to 1.7× within a minute, so two checkouts measured one after the other (as
``profile_evaluator.py`` does, a few seconds per run) differ by more than most changes. Here each checkout runs in
a worker process of its own (its src/ first on the path, the kernels warmed up); both workers are pinned to the
same core, and the parent hands them the same job in turn (A then B, B then A on the next); each times its
evaluation with its own CPU clock. A swing of the machine's speed then hits both sides of a pair alike, and the
per-job ratio B ÷ A cancels it. Run with A and B the same checkout, the ratios come out 0.97–1.04. The absolute
times are higher than ``profile_evaluator``'s: each worker finds the core's caches filled by the other.

Jobs: ``good``, the known-good IMPROV arm on PTP_3 at the nominal base with study seeds 0, 1, …; ``ptp3`` (only when
named in ``--only``), PTP_3's first ``--ptp3-candidates`` random candidates, each a new arm (about 1 in 40
feasible: the feasible group is then random feasible arms, not the one known-good arm again); per family
(``profile_evaluator``'s generated task, seed 0), the first ``--candidates`` random candidates of its search space.
Both workers must stop every job at the same stage (else the script stops: the checkouts do not give the same
results). Printed per scenario and group: the jobs' count, the median CPU ms of A and B, the median of the per-job
ratios B ÷ A, and the stages' medians of each side.
"""
from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

HERE = Path("/work/main/experiments")
GOOD = ("1", "21", "4", "22", "5", "23", "12")


def worker(src: str, only: list, feasible: int, candidates: int, ptp3_candidates: int) -> None:
    """Read job numbers from stdin, evaluate each, print one JSON line per job (stage, feasible, CPU s, stages)."""
    import os
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})   # both workers on one core: a core's own speed cancels
    sys.path.insert(0, str(HERE))
    sys.argv[1:] = ["--src", src]   # (profile_evaluator puts the src/ of its --src first on the path when imported)
    import numpy as np
    from profile_evaluator import SHARED, family_tasks

    import robodesign
    assert Path(robodesign.__file__).resolve().is_relative_to(Path(src).resolve()), robodesign.__file__

    from robodesign.design.evaluator import Evaluator, EvaluatorSpec
    from robodesign.design.problem import Problem
    from robodesign.design.search_space import Candidate
    from robodesign.design.solve import warm_up
    from robodesign.solvers import ik_kernel
    ik_kernel.warm_up()
    warm_up()
    ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
    Evaluator(EvaluatorSpec(ptp3)).evaluate(Candidate(GOOD))   # warm-up: meshes, toppra, OMPL
    jobs = []
    for name in only:
        if name == "good":
            jobs += [(name, lambda s=s: Evaluator(EvaluatorSpec(ptp3, seed=s)).evaluate(Candidate(GOOD)))
                     for s in range(feasible)]
            continue
        # ptp3: PTP_3's random candidates as profile_evaluator draws them (about 1 in 40 feasible, each a new arm)
        problem = ptp3 if name == "ptp3" else Problem.build(family_tasks(name, 1, 0)[0], "robodesign_arm", "cyc")
        n = ptp3_candidates if name == "ptp3" else candidates
        ev = Evaluator(EvaluatorSpec(problem, seed=0))
        rng = np.random.default_rng(0)
        jobs += [(name, lambda c=problem.space.random_candidate(rng), ev=ev: ev.evaluate(c)) for _ in range(n)]
    print(json.dumps({"jobs": len(jobs)}), flush=True)
    for line in sys.stdin:
        name, run = jobs[int(line)]
        t = time.process_time()
        e = run()
        cpu = time.process_time() - t
        print(json.dumps({"scenario": name, "stage": e.stage, "feasible": bool(e.feasible), "cpu": cpu,
                          "stages": {s["name"]: s["seconds"] for s in e.stages}}), flush=True)


def group(r: dict) -> str:
    return "feasible" if r["feasible"] else ("failed at ik" if r["stage"] == "ik" else "failed elsewhere")


def report(pairs) -> None:
    by = defaultdict(list)
    for a, b in pairs:
        by[(a["scenario"], group(a))].append((a, b))
    for (scenario, g), rows in by.items():
        ms = [(1e3 * a["cpu"], 1e3 * b["cpu"]) for a, b in rows]
        ratios = [y / x for x, y in ms if x > 0]
        stages = sorted({k for a, b in rows for k in a["stages"]})
        med = {side: {k: 1e3 * statistics.median([r[i]["stages"].get(k, 0.0) for r in rows]) for k in stages}
               for i, side in enumerate("AB")}
        print(f"{scenario} / {g}: n {len(rows)}, CPU ms A {statistics.median([x for x, _ in ms]):.2f}, "
              f"B {statistics.median([y for _, y in ms]):.2f}, B/A per job median {statistics.median(ratios):.3f}")
        for side in "AB":
            print(f"    {side} stages (median ms): " + ", ".join(f"{k} {v:.2f}" for k, v in med[side].items()))
        if any(a["stages"].get("timing", 0.0) > 0 for a, _ in rows):   # (timing5: the time scaling's stage per job, paired; and the sums)
            tm = [(a["stages"].get("timing", 0.0), b["stages"].get("timing", 0.0)) for a, b in rows]
            print(f"    timing stage: B/A per job median {statistics.median([y / x for x, y in tm if x > 0]):.3f}, "
                  f"sum A {1e3 * sum(x for x, _ in tm):.0f} ms, B {1e3 * sum(y for _, y in tm):.0f} ms")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--a", required=True, help="checkout A (its src/ is evaluated)")
    ap.add_argument("--b", required=True, help="checkout B")
    ap.add_argument("--only", default="good,whitman2020_g5o5,bpo2024")
    ap.add_argument("--feasible", type=int, default=20, help="evaluations of the good PTP_3 arm")
    ap.add_argument("--candidates", type=int, default=300, help="random candidates per family task")
    ap.add_argument("--ptp3-candidates", type=int, default=900,
                    help="random PTP_3 candidates of the ptp3 jobs (not in the default --only; ~20 feasible of 900)")
    ap.add_argument("--worker", default="", help=argparse.SUPPRESS)
    args = ap.parse_args()
    only = [s for s in args.only.split(",") if s]
    if args.worker:
        try:
            worker(args.worker, only, args.feasible, args.candidates, args.ptp3_candidates)
        except (KeyboardInterrupt, BrokenPipeError):   # (Ctrl-C reaches the workers too: the parent reports)
            pass
        return
    cmd = [sys.executable, __file__, "--a", args.a, "--b", args.b, "--only", args.only,
           "--feasible", str(args.feasible), "--candidates", str(args.candidates),
           "--ptp3-candidates", str(args.ptp3_candidates), "--worker"]
    procs = [subprocess.Popen(cmd + [src], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
             for src in (args.a, args.b)]
    pairs: list = []
    try:
        n = [json.loads(p.stdout.readline())["jobs"] for p in procs]   # type: ignore[union-attr]
        assert n[0] == n[1], n
        for i in range(n[0]):
            out = [None, None]
            for k in ((0, 1) if i % 2 == 0 else (1, 0)):
                procs[k].stdin.write(f"{i}\n")   # type: ignore[union-attr]
                procs[k].stdin.flush()           # type: ignore[union-attr]
                out[k] = json.loads(procs[k].stdout.readline())   # type: ignore[union-attr]
            a, b = out
            if (a["stage"], a["feasible"]) != (b["stage"], b["feasible"]):
                sys.exit(f"job {i}: A stopped at {a['stage']}, B at {b['stage']}: not the same results")
            pairs.append((a, b))
    except KeyboardInterrupt:   # Ctrl-C: the jobs paired so far are reported
        print(f"# stopped after {len(pairs)} jobs")
    finally:
        for p in procs:
            p.kill()
    print(f"# A: {args.a}\n# B: {args.b}")
    report(pairs)


if __name__ == "__main__":
    main()
