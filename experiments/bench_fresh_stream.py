"""Fresh arms: PTP_3's random candidates evaluated in one process, each a new IMPROV arm (issue 25, eleventh round).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python experiments/bench_fresh_stream.py --src CHECKOUT [--n 900] [--prof FILE]
    OPENBLAS_NUM_THREADS=1 .venv/bin/python experiments/bench_fresh_stream.py --src CHECKOUT --ga 300

The stream: the first ``--n`` random candidates of simple/PTP_3 with IMPROV (the draws of ``bench_paired.py``'s
``ptp3`` scenario; 23 of the first 900 are feasible), evaluated one after the other by one evaluator. Prints the
stream's CPU seconds, the feasible candidates' median CPU time and stage medians, and a signature of every result
(stage, verdict and cost of each candidate: it must not change with a change meant to be exact; 1e23828eaa for 900
under evaluation rules 2, 7c060069b7 under rules 1).
``--prof FILE`` dumps a cProfile of the stream. ``--ga N``: instead, the genetic search on PTP_3 with IMPROV and the
base pose searched, N evaluations (evaluations per CPU second, the best cost, the results' signature: 34fcbf1b19
for 300 under evaluation rules 2, 2fba5125a3 under rules 1).
"""
from __future__ import annotations

import argparse
import hashlib
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def _signature(rows) -> str:
    return hashlib.sha1(repr(rows).encode()).hexdigest()[:10]


def _row(e) -> tuple:
    return e.stage, bool(e.feasible), round(e.cost, 9) if e.feasible else None


def stream(ptp3, n: int, prof: str) -> None:
    import numpy as np

    from robodesign.design.evaluator import Evaluator, EvaluatorSpec
    ev = Evaluator(EvaluatorSpec(ptp3, seed=0))
    rng = np.random.default_rng(0)
    cands = [ptp3.space.random_candidate(rng) for _ in range(n)]
    stages, feasible, rows = {}, [], []
    if prof:
        import cProfile
        pr = cProfile.Profile()
        pr.enable()
    t0 = time.process_time()
    try:
        for c in cands:
            t = time.process_time()
            e = ev.evaluate(c)
            dt = time.process_time() - t
            rows.append(_row(e))
            if e.feasible:
                feasible.append(dt)
                for s in e.stages:
                    stages.setdefault(s["name"], []).append(s["seconds"])
    except KeyboardInterrupt:   # Ctrl-C: the candidates evaluated so far are reported
        print(f"# stopped after {len(rows)} of {n} candidates")
    total = time.process_time() - t0
    if prof:
        pr.disable()
        pr.dump_stats(prof)
    if not feasible:
        print(f"stream cpu {total:.2f} s, {len(rows)} candidates, none feasible, signature {_signature(rows)}")
        return
    print(f"stream cpu {total:.2f} s, feasible {len(feasible)}, median feasible {np.median(feasible) * 1e3:.1f} ms "
          f"(mean {np.mean(feasible) * 1e3:.1f}), signature {_signature(rows)}")
    print("  stage medians (ms): " + "  ".join(f"{k} {np.median(v) * 1e3:.1f}" for k, v in stages.items()))


def genetic(ptp3_base, budget: int) -> None:
    from robodesign.design.evaluator import Evaluator, EvaluatorSpec
    from robodesign.design.optimize import Budget, SerialExecutor, Study, create_optimizer
    rows = []
    study = Study(create_optimizer("genetic", ptp3_base, seed=0), SerialExecutor(Evaluator(EvaluatorSpec(ptp3_base, seed=0))),
                  Budget(evaluations=budget), on_evaluation=lambda i, e, best: rows.append(_row(e)))
    t = time.process_time()
    try:
        res = study.run()
    except KeyboardInterrupt:   # Ctrl-C: nothing to report but how far it got
        print(f"# stopped after {len(rows)} of {budget} evaluations")
        return
    cpu = time.process_time() - t
    best = res.best.cost if res.best is not None and res.best.feasible else None
    print(f"genetic {budget}: cpu {cpu:.2f} s, {len(rows) / cpu:.1f} evaluations per CPU s, feasible "
          f"{sum(r[1] for r in rows)}, best {best}, signature {_signature(rows)}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--src", default=str(HERE.parent), help="the checkout whose src/ is evaluated")
    ap.add_argument("--n", type=int, default=900, help="random candidates of the stream")
    ap.add_argument("--prof", default="", help="dump the stream's cProfile to this file")
    ap.add_argument("--ga", type=int, default=0, help="run the genetic search on PTP_3 for this many evaluations instead")
    args = ap.parse_args()
    sys.path.insert(0, str(Path(args.src) / "src"))
    from robodesign.design.problem import Problem
    from robodesign.design.solve import warm_up
    from robodesign.solvers import ik_kernel
    ik_kernel.warm_up()
    warm_up()
    shared = HERE.parents[1] / "shared" / "cobra"
    task, modules = shared / "tasks" / "simple" / "PTP_3.json", shared / "modules" / "IMPROV"
    print(f"# src: {sys.modules['robodesign'].__file__}")
    if args.ga:
        genetic(Problem.build(task, modules, "cyc", base_search=True), args.ga)
    else:
        stream(Problem.build(task, modules, "cyc"), args.n, args.prof)


if __name__ == "__main__":
    main()
