"""Benchmark: what the judge's motion model costs (issue 22: torques between samples, the witness search).

    nice -n 10 .venv/bin/python experiments/bench_judge_motion.py [--repeat 15] [--solution FILE ...]

The 350-sample PTP_3 solution of `robodesign solve` (IMPROV arm 1,21,4,22,5,23,12, seed 0) and the same file with
dq/ddq refilled by numpy.gradient (the reference's way, which needs the witness search), each checked

* with everything (the default check), and without the between-sample torque certification
  (judge.arc_torques; the checker's previous behaviour: torques at the samples only);
* the witness search alone, with its scalar recurrence (judge.motion._passes_scalar) and with the array form
  it replaced (_passes_numpy: numpy calls on dof-element arrays per step).

``--solution FILE`` adds PTP_3 solution files (e.g. ``robodesign solve … --cost mechEnergy --out FILE``, a
trajectory-optimization output whose steps mostly have two arcs per joint) to the first comparison.

Prints medians over --repeat runs, the certification's pieces / exact evaluations / deepest split, and the
machine's load average (the machine is shared: absolute times vary with it, ratios much less).
"""
from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

import robodesign.judge.checker as checker
import robodesign.judge.motion as motion
from robodesign import load_module_set
from robodesign.design.solve import SolveSettings, solve
from robodesign.core.trajectory import Trajectory
from robodesign.formats.solution import load_solution
from robodesign.formats.task_io import load_task
from robodesign.judge.arc_torques import certify_arc_torques
from robodesign.judge.quantities import TrajectoryQuantities
from robodesign.model.cell import solution_robot

SHARED = Path(__file__).resolve().parents[2] / "shared" / "cobra"


def median_time(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--solution", action="append", default=[], help="more PTP_3 solution files to check")
    args = ap.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.2f} (2 cores)")
    task = load_task(SHARED / "tasks" / "simple" / "PTP_3.json")
    ms = load_module_set(SHARED / "modules" / "IMPROV")
    sol = solve(task, ms, ["1", "21", "4", "22", "5", "23", "12"], settings=SolveSettings(seed=0)).solution
    tr = sol.trajectory
    dq = np.gradient(tr.q, tr.t, axis=0)
    grad = sol.with_(trajectory=Trajectory(tr.t, tr.q, dq, np.gradient(dq, tr.t, axis=0), dict(tr.goal2time)))
    arc = checker._arc_torque_violations
    files = [("solver's file", sol), ("gradient-filled copy", grad)] + [(f, load_solution(f)) for f in args.solution]
    for name, s in files:
        checker.check(task, s, ms)  # warm-up
        with_, without = [], []
        for _ in range(args.repeat):  # interleaved, so that the machine's load drifts into both alike
            t, v = median_time(lambda: checker.check(task, s, ms), 1)
            with_.append(t)
            checker._arc_torque_violations = lambda *a: []
            try:
                without.append(median_time(lambda: checker.check(task, s, ms), 1)[0])
            finally:
                checker._arc_torque_violations = arc
        t_all, t_no = float(np.median(with_)), float(np.median(without))
        robot = solution_robot(task, s, ms)
        tq = TrajectoryQuantities.from_solution(robot, s, task)
        t_arc, rep = median_time(lambda: certify_arc_torques(robot, tq.motion, tq.external_wrenches,
                                                             np.arange(tq.n - 1), robot.tau_max * (1 + 1e-9),
                                                             sample_torques=tq.motion_torques), args.repeat)
        tr = s.trajectory
        print(f"{name} ({tr.n} samples, valid={v.valid}, violations {sorted({x.constraint for x in v.violations})}):"
              f" check {t_all * 1e3:.1f} ms with the between-sample torques, {t_no * 1e3:.1f} ms without; the "
              f"certification alone {t_arc * 1e3:.1f} ms ({rep.pieces} pieces, {rep.evaluations} exact evaluations, "
              f"deepest split {rep.depth})")
        A = tq.acceleration_bound
        h = np.diff(tr.t)
        h_adj = np.maximum(np.concatenate([h[:1], h]), np.concatenate([h, h[-1:]]))
        slack = A[None, :] * h_adj[:, None] / 2
        t_sc, (v1, _) = median_time(lambda: motion.witness_velocities(tr.t, tr.q, s.trajectory.dq, A, slack),
                                    args.repeat)
        scalar = motion._passes_scalar
        motion._passes_scalar = motion._passes_numpy
        try:
            t_np, (v2, _) = median_time(lambda: motion.witness_velocities(tr.t, tr.q, s.trajectory.dq, A, slack),
                                        args.repeat)
        finally:
            motion._passes_scalar = scalar
        print(f"  witness search: {t_sc * 1e3:.2f} ms scalar recurrence, {t_np * 1e3:.2f} ms array form "
              f"(max |difference| {np.max(np.abs(v1 - v2)):.1e})")
    print(f"load average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
