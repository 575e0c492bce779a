"""Benchmark: what fewer IK restarts per goal would save and cost on PTP_3 (issue 25, an owner's decision).

    .venv/bin/python experiments/bench_ik_restarts.py [--restarts 150,100,60] [--n 900] [--rounds 3]

The evaluator runs ``ik_restarts`` = 150 LM restarts per goal (``design.evaluator.evaluation_settings``), and on a
feasible arm all of them (it wants ``ik_solutions`` = 48 distinct solutions, which a six-joint arm never has).
Two sets of feasible candidates, each evaluated at every ``--restarts`` setting:

* the known-good IMPROV arm at the nominal base with 20 study seeds;
* the candidates among PTP_3's first ``--n`` random ones (generator seed 0, as ``bench_fresh_stream.py``) that
  are feasible at 150 restarts.

Each set is first evaluated once at every setting (warm: the culler's proofs, the distance fields, the kernels),
then ``--rounds`` times, the settings in turn (reversed every other round). Printed per set and setting: how many
candidates stay feasible and their median cost (cycle time, s) in the first round, and the median CPU ms per
evaluation of each round.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from profile_evaluator import GOOD, SHARED  # noqa: E402

from robodesign.design.evaluator import Candidate, Evaluator, EvaluatorSpec, evaluation_settings  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.solve import warm_up  # noqa: E402


def evaluate(problem, restarts: int, jobs, **overrides) -> list:
    """(CPU seconds, evaluation) of each (candidate, study seed) in ``jobs`` at ``restarts`` IK restarts per goal
    (and the other solve settings ``overrides``)."""
    out = []
    for cand, seed in jobs:
        settings = evaluation_settings(ik_restarts=restarts, **overrides)
        ev = Evaluator(EvaluatorSpec(problem, settings=settings, seed=seed))
        t = time.process_time()
        e = ev.evaluate(cand)
        out.append((time.process_time() - t, e))
    return out


def ptp3_problem() -> Problem:
    return Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")


def feasible_arms(ptp3: Problem, n: int) -> list:
    """The candidates among PTP_3's first ``n`` random ones (generator seed 0) feasible with the evaluator's
    settings (study seed 0)."""
    rng = np.random.default_rng(0)
    drawn = [ptp3.space.random_candidate(rng) for _ in range(n)]
    ev = Evaluator(EvaluatorSpec(ptp3, seed=0))
    return [c for c in drawn if ev.evaluate(c).feasible]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--restarts", default="150,100,60")
    ap.add_argument("--n", type=int, default=900, help="random PTP_3 candidates to draw the feasible ones from")
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    settings = [int(x) for x in args.restarts.split(",")]
    warm_up()
    ptp3 = ptp3_problem()
    fresh = feasible_arms(ptp3, args.n)
    sets = {"known-good arm": [(Candidate(GOOD), s) for s in range(1, 21)],
            f"feasible of {args.n} random": [(c, 1) for c in fresh]}
    for name, jobs in sets.items():
        for r in settings:
            evaluate(ptp3, r, jobs)
        cpu: dict = {r: [] for r in settings}
        for rnd in range(args.rounds):
            for r in settings if rnd % 2 == 0 else settings[::-1]:
                res = evaluate(ptp3, r, jobs)
                cpu[r].append(1e3 * statistics.median(t for t, _ in res))
                if rnd == 0:
                    costs = [e.cost for _, e in res if e.feasible]
                    print(f"{name}, {r} restarts: feasible {len(costs)} of {len(res)}, median cost "
                          f"{statistics.median(costs) if costs else float('nan'):.4f}", flush=True)
        for r in settings:
            print(f"{name}, {r} restarts: median CPU ms per evaluation by round: "
                  + ", ".join(f"{x:.1f}" for x in cpu[r]), flush=True)


if __name__ == "__main__":
    main()
