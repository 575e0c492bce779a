"""Benchmark: checking a 1,500-sample PTP_3 solution with all its constraints (joint limits incl.
torque, self-collision and obstacle collision *between samples too*, goals, order, base placement).

    .venv/bin/python experiments/bench_checker.py [--repeat 5]

The solution is produced by robodesign solve for an IMPROV arm and then slowed down in time so that
it has ~1,500 samples (a uniform time stretch keeps it valid). Prints samples per second.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from robodesign import load_module_set
from robodesign.checker import CheckSettings, check
from robodesign.solution import SolutionTrajectory
from robodesign.solve import SolveSettings, solve
from robodesign.task_io import load_task

SHARED = Path(__file__).resolve().parents[2] / "shared" / "cobra"


def stretched(sol, n_target: int, dt: float):
    tr = sol.trajectory
    k = (n_target - 1) * dt / tr.t[-1]
    t_new = np.arange(n_target) * dt
    q = np.stack([np.interp(t_new / k, tr.t, tr.q[:, j]) for j in range(tr.q.shape[1])], axis=1)
    # exact derivatives of the stretched motion: dq(t) = q'(t/k)/k, ddq = q''(t/k)/k²
    dq = np.stack([np.interp(t_new / k, tr.t, tr.dq[:, j]) for j in range(tr.q.shape[1])], axis=1) / k
    ddq = np.stack([np.interp(t_new / k, tr.t, tr.ddq[:, j]) for j in range(tr.q.shape[1])], axis=1) / k ** 2
    g2t = {g: round(v * k / dt) * dt for g, v in tr.goal2time.items()}
    # snap the goal samples exactly onto the original rest states
    for g, v in tr.goal2time.items():
        i = int(round(g2t[g] / dt))
        j = int(np.argmin(np.abs(tr.t - v)))
        q[i], dq[i], ddq[i] = tr.q[j], tr.dq[j] / k, tr.ddq[j] / k ** 2
    return sol.with_(trajectory=SolutionTrajectory(t_new, q, dq, ddq, g2t))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--samples", type=int, default=1500)
    args = ap.parse_args()
    task = load_task(SHARED / "tasks" / "simple" / "PTP_3.json")
    ms = load_module_set(SHARED / "modules" / "IMPROV")
    res = solve(task, ms, ["1", "21", "4", "22", "5", "23", "12"], settings=SolveSettings(seed=1))
    assert res.feasible, res.message
    sol = stretched(res.solution, args.samples, task.dt)
    v = check(task, sol, ms)  # warm-up (meshes, imports)
    print(f"solution: {sol.trajectory.n} samples, {sol.trajectory.t[-1]:.2f} s, valid={v.valid} "
          f"{[str(x) for x in v.violations][:3]}")
    for mode, settings in (("with between-sample collision certification", CheckSettings()),
                           ("samples only (what the reference checks)", CheckSettings(between_samples=False))):
        times = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            v = check(task, sol, ms, settings)
            times.append(time.perf_counter() - t0)
        t = float(np.median(times))
        print(f"check {mode}: median {t * 1e3:.1f} ms -> {sol.trajectory.n / t:,.0f} samples/s "
              f"(valid={v.valid}; stages {', '.join(f'{k} {x * 1e3:.1f} ms' for k, x in v.timings.items())})")


if __name__ == "__main__":
    main()
