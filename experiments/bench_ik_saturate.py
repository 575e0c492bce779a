"""Benchmark: IK restarts that stop when a goal's solutions stop growing (``SolveSettings.ik_saturate``, issue 25).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python experiments/bench_ik_saturate.py [--parts evals,share,kept,ga,families]
        [--saturate 0,8,12] [--out DIR]

``ik_saturate`` = k stops a goal's collecting once k converged restarts since its last new solution were
duplicates (0: every one of the 150 restarts runs, the evaluator's default). Five parts, each printed and written
to ``DIR/<part>.txt``:

* ``evals``: the known-good IMPROV arm on PTP_3 with 40 study seeds, and the feasible ones of PTP_3's first 900
  random candidates with 5 seeds each; every setting once to warm up, then two rounds, the settings in turn
  (reversed in the second). Per setting: feasible count, the paired cost (cycle time) ratio to the first setting,
  the median CPU ms per evaluation of each round and the median IK stage;
* ``share``: the same new arms with study seeds 1-20 and 21-40 (920 evaluations per setting): the feasible count,
  the median cost and the mean over the arms of each arm's best cost over the seeds;
* ``kept``: per goal search of those evaluations (3 seeds), the share of the full search's solutions and of its
  attempts each k keeps (the saturated search is the full one cut short, so both come from one run each);
* ``ga``: the genetic search on PTP_3 (600 evaluations, study seeds 0 to ``--ga-seeds`` - 1, default 6, the
  settings' order alternating): the best cycle time, feasible evaluations and CPU seconds of each run, and per
  setting the mean best, the runs worse and better than the first setting's and the summed CPU;
* ``families``: 10 generated tasks each of the published Whitman2020 5/5 (free base) and BPO24 families (seed 7;
  the robodesign_arm set; written to results/tasks/ once): the designs that passed IK in a 500-evaluation genetic search (at most 12 per task),
  evaluated with study seeds 1-4 at every setting: feasible count, failing stages, paired cost ratio, CPU.
"""
from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from bench_ik_restarts import evaluate, feasible_arms, ptp3_problem  # noqa: E402
from profile_evaluator import GOOD  # noqa: E402

import robodesign.solvers.ik as ik  # noqa: E402
from robodesign.design.evaluator import Candidate, evaluation_settings  # noqa: E402
from robodesign.design.optimize import optimize  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.solve import warm_up  # noqa: E402

FAMILIES = {"whitman2020_g5o5_free": ["whitman2020", "--goals", "5", "--obstacles", "5", "--base", "xyz_any_rot"],
            "bpo2024": ["bpo2024"]}


def cost_ratio(base: list, other: list) -> str:
    """Mean and median of other ÷ base over the pairs both found feasible, and how many got worse / better."""
    r = [b.cost / a.cost for (_, a), (_, b) in zip(base, other) if a.feasible and b.feasible]
    if not r:
        return "no pair feasible on both sides"
    return (f"cost ratio mean {statistics.mean(r):.4f} median {statistics.median(r):.4f} "
            f"(worse {sum(x > 1 for x in r)}, better {sum(x < 1 for x in r)} of {len(r)})")


def ik_ms(res: list) -> float:
    return 1e3 * statistics.median(next((s["seconds"] for s in e.stages if s["name"] == "ik"), 0.0) for _, e in res)


def part_evals(ptp3, fresh, ks, say) -> None:
    sets = {"known-good arm, 40 seeds": [(Candidate(GOOD), s) for s in range(1, 41)],
            f"{len(fresh)} feasible new arms, 5 seeds": [(c, s) for c in fresh for s in range(1, 6)]}
    for name, jobs in sets.items():
        for k in ks:
            evaluate(ptp3, 150, jobs, ik_saturate=k)
        rounds: dict = {k: [] for k in ks}
        for rnd in range(2):
            for k in ks if rnd == 0 else ks[::-1]:
                rounds[k].append(evaluate(ptp3, 150, jobs, ik_saturate=k))
        for k in ks:
            first = rounds[k][0]
            feas = [e.cost for _, e in first if e.feasible]
            say(f"{name}, ik_saturate {k}: feasible {len(feas)} of {len(first)}, median cost "
                f"{statistics.median(feas):.4f}; {cost_ratio(rounds[ks[0]][0], first)}; median CPU ms "
                + ", ".join(f"{1e3 * statistics.median(t for t, _ in r):.1f}" for r in rounds[k])
                + "; IK stage ms " + ", ".join(f"{ik_ms(r):.1f}" for r in rounds[k]))


def part_share(ptp3, fresh, ks, say) -> None:
    for seeds in (range(1, 21), range(21, 41)):
        for k in ks:
            res = evaluate(ptp3, 150, [(c, s) for c in fresh for s in seeds], ik_saturate=k)
            costs = np.array([e.cost if e.feasible else np.inf for _, e in res]).reshape(len(fresh), len(seeds))
            best = [row[np.isfinite(row)].min() for row in costs if np.isfinite(row).any()]
            say(f"seeds {seeds.start}-{seeds.stop - 1}, ik_saturate {k}: feasible {int(np.isfinite(costs).sum())} of "
                f"{costs.size}, median cost {np.median(costs[np.isfinite(costs)]):.4f}, each arm's best over the seeds: "
                f"mean {np.mean(best):.4f} ({len(best)} arms)")


def part_kept(ptp3, fresh, ks, say) -> None:
    plain = ik.solve_ik
    rows = []

    def both(robot, goal, rng=None, **kw):
        if kw.get("n_solutions", 1) == 1:
            return plain(robot, goal, rng, **kw)
        state = rng.bit_generator.state
        row = []
        for k in ks:
            rng.bit_generator.state = state
            r = plain(robot, goal, rng, **{**kw, "saturate": k})
            row += [len(r.solutions), r.stats["attempts"]]
        rng.bit_generator.state = state
        rows.append(row)
        return plain(robot, goal, rng, **{**kw, "saturate": 0})   # the evaluation goes on as without the setting
    ik.solve_ik = both
    try:
        for c in [Candidate(GOOD)] + fresh:
            for s in range(1, 4):
                evaluate(ptp3, 150, [(c, s)], ik_saturate=0)
    finally:
        ik.solve_ik = plain
    a = np.array(rows, dtype=float)
    full = ks.index(0)
    say(f"{len(a)} goal searches; the full one: {a[:, 2 * full].mean():.2f} solutions, "
        f"{a[:, 2 * full + 1].mean():.1f} attempts on average")
    for j, k in enumerate(ks):
        n, at = a[:, 2 * j], a[:, 2 * j + 1]
        say(f"ik_saturate {k}: solutions kept {n.sum() / a[:, 2 * full].sum():.3f}, searches that lose one "
            f"{np.mean(n < a[:, 2 * full]):.3f}, attempts {at.mean():.1f} ({at.sum() / a[:, 2 * full + 1].sum():.3f})")


def part_ga(ptp3, ks, say, seeds: int) -> None:
    bests: dict = {k: [] for k in ks}
    cpus: dict = {k: [] for k in ks}
    for seed in range(seeds):
        out = []
        for k in ks if seed % 2 == 0 else ks[::-1]:
            feasible = [0]
            t = time.process_time()
            r = optimize(ptp3, "genetic", "600evals", seed=seed, settings=evaluation_settings(ik_saturate=k),
                         on_evaluation=lambda i, e, best: feasible.__setitem__(0, feasible[0] + bool(e.feasible)))
            cpu = time.process_time() - t
            cost = r.best.cost if r.best is not None and r.best.feasible else float("nan")
            bests[k].append(cost)
            cpus[k].append(cpu)
            out.append((k, f"ik_saturate {k}: best {cost:.3f} s, {feasible[0]} feasible, CPU {cpu:.1f} s"))
        say(f"seed {seed}: " + " | ".join(text for _, text in sorted(out)))
    for k in ks:
        d = np.array(bests[k]) - np.array(bests[ks[0]])
        say(f"ik_saturate {k}: best mean {np.mean(bests[k]):.4f} s (against {ks[0]}: worse in {int((d > 0).sum())}, "
            f"better in {int((d < 0).sum())} of {seeds}), CPU sum {sum(cpus[k]):.1f} s")


def family_tasks(fam: str) -> list:
    """The 10 task files of family ``fam`` (:data:`FAMILIES`; generated into results/tasks/ on first use)."""
    folder = HERE.parent / "results" / "tasks" / f"bench_ik_saturate_{fam}_s7_n10"
    if not folder.is_dir():
        subprocess.run([str(Path(sys.executable).parent / "robodesign"), "generate", *FAMILIES[fam], "--variant",
                        "published", "--count", "10", "--seed", "7", "--out", str(folder), "-q"], check=True)
    return sorted(folder.glob("*.json"))


def part_families(ks, say) -> None:
    for fam in FAMILIES:
        res: dict = {k: [] for k in ks}
        for f in family_tasks(fam):
            problem = Problem.build(f, "robodesign_arm", "cyc")
            got: list = []
            optimize(problem, "genetic", "500evals", seed=0, on_evaluation=lambda i, e, best: got.append(e.candidate)
                     if e.stage_index > 3 and len(got) < 12 else None)
            for c in got:
                for s in range(1, 5):
                    for k in ks:
                        res[k] += evaluate(problem, 150, [(c, s)], ik_saturate=k)
        for k in ks:
            fails: dict = {}
            for _, e in res[k]:
                if not e.feasible:
                    fails[e.stage] = fails.get(e.stage, 0) + 1
            say(f"{fam}, ik_saturate {k}: feasible {sum(e.feasible for _, e in res[k])} of {len(res[k])}; failed at "
                f"{fails}; {cost_ratio(res[ks[0]], res[k])}; median CPU ms "
                f"{1e3 * statistics.median(t for t, _ in res[k]):.1f}, mean {1e3 * statistics.mean(t for t, _ in res[k]):.1f}; "
                f"IK stage ms {ik_ms(res[k]):.1f}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--parts", default="evals,share,kept,ga,families")
    ap.add_argument("--saturate", default="0,8,12", help="ik_saturate settings, the first the reference (0: off)")
    ap.add_argument("--ga-seeds", type=int, default=6, help="study seeds of the ga part (0, 1, ...)")
    ap.add_argument("--out", type=Path, default=Path("docs/results/issue25_round14/saturate"))
    args = ap.parse_args()
    ks = [int(x) for x in args.saturate.split(",")]
    args.out.mkdir(parents=True, exist_ok=True)
    warm_up()
    ptp3 = ptp3_problem()
    fresh = feasible_arms(ptp3, 900) if {"evals", "share", "kept"} & set(args.parts.split(",")) else []
    for part in args.parts.split(","):
        log = (args.out / f"{part}.txt").open("w")

        def say(line: str) -> None:
            print(f"[{part}] {line}", flush=True)
            log.write(line + "\n")
            log.flush()
        if part == "evals":
            part_evals(ptp3, fresh, ks, say)
        elif part == "share":
            part_share(ptp3, fresh, ks, say)
        elif part == "kept":
            part_kept(ptp3, fresh, sorted(set(ks) | {0, 8, 12, 16, 24}), say)
        elif part == "ga":
            part_ga(ptp3, ks, say, args.ga_seeds)
        elif part == "families":
            part_families(ks, say)
        else:
            sys.exit(f"unknown part {part!r}")
        log.close()


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:   # every line printed so far is already in its part's file
        print("interrupted: the lines printed so far are in the parts' files", file=sys.stderr)
        sys.exit(130)
