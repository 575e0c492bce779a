"""Where the checker's one-motion tolerances come from (docs/checker.md, "One motion").

For every step the checker compares Δq with the trapezoid rule h·(dq_k + dq_k+1)/2 and Δdq with
h·(ddq_k + ddq_k+1)/2 (robodesign.judge.quantities.step_residuals). This script measures, relative to a joint's
largest acceleration A in the file (max |ddq|, max |Δdq|/h):

1. reference-style trajectories (Timor's Trajectory.from_mstraj: straight segments, constant-acceleration
   blends, dq/ddq by numpy.gradient) over random via points, step sizes, speeds and blend times:
   max |r_q| / (A·h²) and max (|r_dq| − h·|Δddq|/2) / (A·h);
2. every solution robodesign's solvers write for the built-in tasks (TOPP-RA), PTP_3 with ruckig and with
   trajectory optimization: the largest residual / tolerance ratio (must be ≪ 1).

    PYTHONPATH=src:optimizers python experiments/consistency_tolerances.py [--trials 2000]
"""
from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from reference_trajectories import mstraj_like  # noqa: E402

from robodesign.judge.quantities import DQ_RULE_FACTOR, Q_RULE_FACTOR, step_residuals  # noqa: E402


def reference_style(trials: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    worst_q = worst_dq = 0.0
    for _ in range(trials):
        dt = float(rng.choice([0.001, 0.004, 0.01, 0.02, 0.05]))
        via = rng.uniform(-2, 2, (int(rng.integers(2, 6)), 3))
        t_acc = float(rng.uniform(dt, 1.0) if rng.random() < 0.5 else dt * rng.uniform(1, 3))
        t, q, dq, ddq, _, _ = mstraj_like(via, float(rng.uniform(0.3, 3.0)), t_acc, dt)
        h = np.diff(t)[:, None]
        A = np.max(np.abs(np.concatenate([ddq, np.diff(dq, axis=0) / h])), axis=0)
        r_q = np.diff(q, axis=0) - h * (dq[1:] + dq[:-1]) / 2
        r_dq = np.diff(dq, axis=0) - h * (ddq[1:] + ddq[:-1]) / 2
        worst_q = max(worst_q, float(np.max(np.abs(r_q) / (A * h ** 2))))
        excess = np.abs(r_dq) - h * np.abs(np.diff(ddq, axis=0)) / 2
        worst_dq = max(worst_dq, float(np.max(excess / (A * h))))
    return worst_q, worst_dq


def robodesign_outputs():
    spec = importlib.util.spec_from_file_location("make_tasks", ROOT / "assets" / "tasks" / "make_tasks.py")
    mt = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mt)
    from robodesign.formats.module_io import load_module_set
    from robodesign.design.solve import SolveSettings, solve
    from robodesign.formats.task_io import load_task
    rows = []
    for name in sorted(mt.TASKS):
        _, res, _ = mt.solve_builtin(name)
        rows.append((f"{name} (toppra)", res))
    cobra = ROOT.parent / "shared" / "cobra"
    task = load_task(cobra / "tasks" / "simple" / "PTP_3.json")
    ms = load_module_set(cobra / "modules" / "IMPROV")
    order = ["1", "21", "4", "22", "5", "23", "12"]
    for label, settings, cost in (("toppra", SolveSettings(), "cyc"), ("ruckig", SolveSettings(timing="ruckig"), "cyc"),
                                  ("trajopt", SolveSettings(optimize_trajectory=True), "mechEnergy")):
        rows.append((f"PTP_3 ({label}, {cost})", solve(task, ms, order, cost=cost, settings=settings)))
    out = []
    for label, res in rows:
        tr = res.solution.trajectory
        out.append((label, res.feasible, *step_residuals(tr.t, tr.q, tr.dq, tr.ddq).worst_ratio))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trials", type=int, default=2000)
    a = ap.parse_args(argv)
    wq, wdq = reference_style(a.trials)
    print(f"reference-style (from_mstraj + numpy.gradient), {a.trials} random trajectories:")
    print(f"  max |r_q| / (A h^2) = {wq:.4f}   (tolerance factor {Q_RULE_FACTOR})")
    print(f"  max (|r_dq| - h |d ddq| / 2) / (A h) = {wdq:.4f}   (tolerance factor {DQ_RULE_FACTOR})")
    print("robodesign solver outputs: largest residual / tolerance (q rule, dq rule):")
    for label, valid, rq, rdq in robodesign_outputs():
        print(f"  {label:34s} valid={valid}  {rq:.2e}  {rdq:.2e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
