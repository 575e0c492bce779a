"""µs per sample of pinocchio's RNEA batched (``pinocchio.rneaInParallel`` on a model pool, what
``model.rnea_batch.rnea_rows`` ran before) and of the compiled RNEA (``model.rnea_kernel``), on a 6- and a
7-joint IMPROV arm, alternating the two, CPU seconds (issue 25):

    OPENBLAS_NUM_THREADS=1 .venv/bin/python experiments/bench_rnea.py [--rows 1650] [--rounds 7]

Prints per arm and round both medians and checks the two agree bit for bit.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
ARMS = {"6-joint": ["1", "22", "5", "23", "15", "29", "101"], "7-joint": ["1", "21", "4", "22", "5", "23", "12"]}


def _cpu_per_row(f, n: int, reps: int) -> float:
    """Median CPU µs per row of ``f()`` (n rows) over ``reps`` calls."""
    times = []
    for _ in range(reps):
        t = time.process_time()
        f()
        times.append(time.process_time() - t)
    return float(np.median(times)) / n * 1e6


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", type=int, default=1650, help="samples per call (~ a feasible PTP_3 time scaling's)")
    ap.add_argument("--rounds", type=int, default=7)
    args = ap.parse_args()
    import pinocchio as pin

    from robodesign import Robot, load_module_set
    from robodesign.model import rnea_batch, rnea_kernel
    assert rnea_kernel.warm_up()
    ms, rng = load_module_set(ROOT.parent / "shared" / "cobra" / "modules" / "IMPROV"), np.random.default_rng(0)
    for name, order in ARMS.items():
        model = Robot.from_order(ms, order).model
        Q, V, A = (rng.uniform(-3, 3, (args.rows, model.nv)) for _ in range(3))
        pool, packed = rnea_batch._pool(model, False), rnea_kernel.pack(model)
        assert packed is not None

        def pinocchio():
            return pin.rneaInParallel(1, pool, Q.T, V.T, A.T).T

        def kernel():
            return rnea_kernel.rnea(*packed + (Q, V, A))
        assert np.ascontiguousarray(pinocchio()).tobytes() == kernel().tobytes()
        for r in range(args.rounds):
            a, b = _cpu_per_row(pinocchio, args.rows, 20), _cpu_per_row(kernel, args.rows, 20)
            print(f"{name} round {r}: pinocchio {a:.3f} µs/row, compiled {b:.3f} µs/row, ratio {b / a:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
