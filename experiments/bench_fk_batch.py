"""Benchmark: forward kinematics batched over samples (``Robot.fk_batch``) against one pinocchio call per
sample (``Robot.fk`` = ``pin.framesForwardKinematics``), on the IMPROV arm of the PTP_3 solution.

    nice .venv/bin/python experiments/bench_fk_batch.py [--samples 350,1500] [--repeat 7]

Both are timed in the same run, alternating, best of ``--repeat`` rounds (per call: best 50-call chunk; the
machine is shared: the minimum removes time stolen by other processes). Prints µs per sample of each, their ratio, and the batched time
converted to the issue's reference scale: the reference implementation (Timor Python) measured 6.6 µs per FK
call when robodesign's per-call FK measured 1.4 µs on the same machine (issue 25), so batched FK is
(per-call / batched) × 6.6 / 1.4 times faster than the reference. The batched result equals the
per-sample one to ~1e-15 (checked here and in tests/test_fk_batch.py).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from robodesign import Robot, load_module_set  # noqa: E402

SHARED = ROOT.parent / "shared" / "cobra"
ORDER = ["1", "21", "4", "22", "5", "23", "12"]
REF_PER_CALL, OURS_PER_CALL = 6.6, 1.4   # µs, issue 25's table (same machine, same run)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--samples", default="350,1500")
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    robot = Robot.from_order(load_module_set(SHARED / "modules" / "IMPROV"), ORDER)
    rng = np.random.default_rng(0)
    for n in [int(x) for x in args.samples.split(",")]:
        Q = np.array([robot.random_configuration(rng) for _ in range(n)])
        err = float(np.max(np.abs(robot.fk_batch(Q) - np.array([robot.fk(q) for q in Q]))))
        best_b, best_p = np.inf, np.inf
        for _ in range(args.repeat):
            t = time.perf_counter()
            robot.fk_batch(Q)
            best_b = min(best_b, time.perf_counter() - t)
            for k in range(0, n, 50):   # short chunks: a long loop is always interrupted on a busy machine
                t = time.perf_counter()
                for q in Q[k:k + 50]:
                    robot.fk(q)
                best_p = min(best_p, (time.perf_counter() - t) / len(Q[k:k + 50]))
        b, p = best_b / n * 1e6, best_p * 1e6
        ratio = p / b
        print(f"{n} samples: batched {b:.3f} µs/sample, per call {p:.3f} µs/sample, batched {ratio:.1f}x faster "
              f"(max difference {err:.1e}); vs the reference (6.6 µs per call, scaled by this run's per-call "
              f"figure): {ratio * REF_PER_CALL / OURS_PER_CALL:.1f}x")


if __name__ == "__main__":
    main()
