"""Instruction counts of the house redesign's hot paths, each commit against its parent (issue 23: no slowdown
over 5 %). Wall-clock medians on the shared 2-core machine vary by 15–40 % per round (docs/benchmarks.md "The
house redesign, A/B"); the number of instructions a piece of work executes does not depend on the load.

    nice .venv/bin/python experiments/bench_house_ir.py [--pair A:B[:op,op...]] ... [--out FILE]

Every count is valgrind's cachegrind ``I refs`` (instructions executed in user space, the Python interpreter,
numpy, pinocchio and coal included) of a fresh process of this file with ``PYTHONPATH=<checkout>/src`` (the
``ab_<sha>`` worktrees of bench_house_ab.py). The process loads the problem, runs the operation once to warm
every cache, then runs it ``reps`` more times; it is run with two values of ``reps``, and the per-operation count
is the difference divided by the difference of ``reps`` (imports and set-up cancel out). Numba compiles the IK
kernels anew for valgrind's emulated CPU: one uncounted run per checkout fills that cache first. ``PYTHONHASHSEED=0``
and seeded random numbers make the work the same in both runs and in both checkouts.

Operations (GOOD = the IMPROV arm 1,21,4,22,5,23,12 on PTP_3):

* ``solve``: ``solve`` of GOOD with the evaluator's settings (cost cyc, study seed 0): what an optimizer pays;
* ``check``: the checker on GOOD's solution (seed 1) with the between-sample certification;
* ``models``: ``Robot.from_order`` of 20 random 6-joint IMPROV orders (seeded);
* ``fk``: 500 ``Robot.fk`` calls; ``rnea``: 500 ``Robot.rnea`` calls;
* ``screen``: 20 random candidates solved up to the IK stage;
* ``urdf``: ``export_urdf`` of GOOD; ``viewer``: ``build_scene`` of PTP_3 with GOOD and its trajectory.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import bench_house_ab as ab

DEFAULT_PAIRS = ["7312ff5:ca91683:solve,check,models,fk,rnea", "8204881:9caa54a:check,urdf,viewer",
                 "da28b26:d29a2b8:solve,screen"]
REPS = (1, 3)


# ------------------------------------------------------------------------------------------------------------
# worker side
# ------------------------------------------------------------------------------------------------------------
def _op(name: str, shared: Path):
    """(set-up, operation): the operation is a no-argument callable doing the same work each call."""
    import numpy as np

    import robodesign
    task, ms = ab._problem(shared)
    if name in ("solve", "check", "screen", "viewer"):
        ab._warm_ik()
    if name == "solve":
        from dataclasses import replace
        sv, ev = ab.rd("design.solve", "solve"), ab.rd("design.evaluator", "evaluator")
        key = ab.rd("design.search_space", "search_space").Candidate(ab.GOOD, ()).key()
        settings = replace(ev.evaluation_settings(), seed=ev.candidate_seed(0, key))
        return lambda: sv.solve(task, ms, list(ab.GOOD), cost="cyc", settings=settings).cost
    if name == "check":
        checker = ab.rd("judge.checker", "checker")
        sol = ab._good_solution(task, ms)
        return lambda: checker.check(task, sol, ms).valid
    if name in ("models", "fk", "rnea"):
        assembly = ab.rd("formats.assembly", "assembly")
        rng = np.random.default_rng(0)
        orders = [assembly.random_serial_order(ms, rng, dof=6) for _ in range(20)]
        if name == "models":
            return lambda: [round(sum(i.mass for i in robodesign.Robot.from_order(ms, o).model.inertias), 9) for o in orders]
        r = robodesign.Robot.from_order(ms, ab.GOOD)
        Q, V, A = (rng.uniform(-1, 1, (500, 6)) for _ in range(3))
        if name == "fk":
            return lambda: [r.fk(q) for q in Q]
        return lambda: [r.rnea(q, v, a) for q, v, a in zip(Q, V, A)]
    if name == "screen":
        sv, sp = ab.rd("design.solve", "solve"), ab.rd("design.search_space", "search_space")
        rng = np.random.default_rng(1)
        cands = [sp.SearchSpace(ms).random_order(rng) for _ in range(20)]
        return lambda: [sv.solve(task, ms, o, settings=sv.SolveSettings(seed=i, stop_after="ik")).stage
                        for i, o in enumerate(cands)]
    if name == "urdf":
        urdf = ab.rd("formats.urdf", "urdf")
        robot = robodesign.Robot.from_order(ms, ab.GOOD)
        out = Path(tempfile.mkdtemp(prefix="rd-ir-")) / "r.urdf"
        return lambda: (urdf.export_urdf(robot, out), out.stat().st_size)[1]
    if name == "viewer":
        cell, scene = ab.rd("model.cell", "cell"), ab.rd("viewer.scene")
        sol = ab._good_solution(task, ms)
        robot = cell.build_robot(task, ms, sol.assembly(ms), sol.base_pose)
        return lambda: len(scene.build_scene(task, robot, sol.trajectory))
    raise SystemExit(f"unknown operation {name}")


def work(name: str, reps: int, shared: Path) -> None:
    import warnings
    warnings.simplefilter("ignore", DeprecationWarning)
    if name == "warm":  # numba compiles the IK kernels anew for valgrind's CPU: once, into the cache, not counted
        ab._warm_ik()
        print("RESULT " + json.dumps({"op": name, "reps": 0, "result": "", "robodesign": str(Path(
            ab.rd("solvers.ik_kernel").__file__).parents[1])}), flush=True)
        return
    op = _op(name, shared)
    first = op()  # warms every cache
    if os.environ.get("RD_IR_NO_GC"):  # count the operation without the cyclic garbage collector's passes
        import gc
        gc.collect()
        gc.disable()
    for _ in range(reps):
        if repr(op()) != repr(first):
            raise SystemExit(f"{name}: a repetition gave {op()!r}, the first {first!r}")
    import robodesign
    print("RESULT " + json.dumps({"op": name, "reps": reps, "result": repr(first)[:200],
                                  "robodesign": str(Path(robodesign.__file__).parent)}), flush=True)


# ------------------------------------------------------------------------------------------------------------
# driver side
# ------------------------------------------------------------------------------------------------------------
def count(wt: Path, name: str, reps: int, shared: str) -> tuple:
    with tempfile.TemporaryDirectory() as tmp:
        cmd = ["valgrind", "--tool=cachegrind", "--cache-sim=no", f"--cachegrind-out-file={tmp}/cg.out",
               sys.executable, str(Path(__file__).resolve()), "--work", name, "--reps", str(reps), "--shared", shared]
        p = subprocess.run(cmd, env=ab.env_for(wt, name), capture_output=True, text=True, cwd=wt)
    refs = re.search(r"I\s+refs:\s+([\d,]+)", p.stderr)
    res = [x for x in p.stdout.splitlines() if x.startswith("RESULT ")]
    if p.returncode != 0 or not refs or not res:
        raise SystemExit(f"{name} on {wt} failed ({p.returncode}):\n{p.stdout[-1500:]}\n{p.stderr[-2500:]}")
    got = json.loads(res[-1][7:])
    if Path(got["robodesign"]).resolve() != (wt / "src" / "robodesign").resolve():
        raise SystemExit(f"{name}: imported {got['robodesign']}, not {wt}")
    return int(refs.group(1).replace(",", "")), got["result"]


def drive(a) -> None:
    base = Path(a.worktrees)
    rows, out = [], Path(a.out) if a.out else ab.ROOT / "docs" / "results" / "house_ab" / "instructions.json"
    for pair in a.pair or DEFAULT_PAIRS:
        sha_a, sha_b, ops = (pair.split(":") + ["solve,check"])[:3]
        wts = {s: ab.worktree(s, base) for s in (sha_a, sha_b)}
        for wt in wts.values():
            ab.prepare(wt)
            count(wt, "warm", 0, a.shared)
        for name in ops.split(","):
            per, results = {}, {}
            for sha, wt in wts.items():
                lo, r_lo = count(wt, name, REPS[0], a.shared)
                hi, r_hi = count(wt, name, REPS[1], a.shared)
                per[sha], results[sha] = (hi - lo) / (REPS[1] - REPS[0]), r_hi
            row = {"pair": f"{sha_a}:{sha_b}", "op": name, "instructions_A": per[sha_a], "instructions_B": per[sha_b],
                   "change": per[sha_b] / per[sha_a] - 1, "same_result": results[sha_a] == results[sha_b],
                   "result_A": results[sha_a], "result_B": results[sha_b]}
            rows.append(row)
            print(f"{row['pair']} {name:7s} A {per[sha_a] / 1e6:10.2f} M  B {per[sha_b] / 1e6:10.2f} M  "
                  f"change {100 * row['change']:+6.2f} %  same result: {row['same_result']}", flush=True)
            out.parent.mkdir(parents=True, exist_ok=True)
            out.write_text(json.dumps({"reps": REPS, "rows": rows}, indent=1) + "\n")
    print("\n| pair | operation | instructions A | instructions B | change |\n|---|---|---:|---:|---:|")
    for r in rows:
        print(f"| `{r['pair']}` | {r['op']} | {r['instructions_A'] / 1e6:,.1f} M | {r['instructions_B'] / 1e6:,.1f} M "
              f"| {100 * r['change']:+.2f} % |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pair", action="append", help="A:B[:op,op...] (default: the redesign's commits)")
    ap.add_argument("--worktrees", default=str(ab.ROOT.parent))
    ap.add_argument("--shared", default=str(ab.SHARED))
    ap.add_argument("--out", help="JSON file (default docs/results/house_ab/instructions.json)")
    ap.add_argument("--no-gc", action="store_true", help="count with the cyclic garbage collector off")
    ap.add_argument("--work", help=argparse.SUPPRESS)
    ap.add_argument("--reps", type=int, default=1, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.work:
        work(a.work, a.reps, Path(a.shared))
    else:
        if a.no_gc:
            os.environ["RD_IR_NO_GC"] = "1"
        drive(a)


if __name__ == "__main__":
    main()
