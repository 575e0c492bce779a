"""Benchmark: random valid 6-DoF IMPROV assemblies turned into full robot models per second (one core),
and robodesign's FK / RNEA calls against raw pinocchio.

    .venv/bin/python experiments/bench_models.py [--n 500] [--seed 0]

Prints the figures recorded in docs/benchmarks.md.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

from robodesign import Robot, load_module_set
from robodesign.formats.assembly import random_serial_order

IMPROV = Path(__file__).resolve().parents[2] / "shared" / "cobra" / "modules" / "IMPROV"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=500)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--modules", default=str(IMPROV))
    args = ap.parse_args()
    ms = load_module_set(args.modules)
    rng = np.random.default_rng(args.seed)
    orders = [random_serial_order(ms, rng, dof=6) for _ in range(args.n)]
    Robot.from_order(ms, orders[0])  # warm the mesh cache (meshes are loaded once per process)
    t0 = time.perf_counter()
    robots = [Robot.from_order(ms, o) for o in orders]
    dt = time.perf_counter() - t0
    geoms = np.mean([r.n_collision_geometries for r in robots])
    pairs = np.mean([r.n_self_collision_pairs for r in robots])
    print(f"models: {args.n} random valid 6-DoF assemblies of {ms.name} in {dt:.3f} s -> {args.n / dt:.0f} models/s "
          f"({dt / args.n * 1e3:.2f} ms each; mean {geoms:.1f} collision geometries, {pairs:.1f} self-collision pairs)")

    r = robots[0]
    Q = rng.uniform(-1, 1, (2000, 6))
    m, d = r.model, r.model.createData()
    t0 = time.perf_counter()
    for q in Q:
        pin.framesForwardKinematics(m, d, q)
        d.oMf[r.tcp_frame]
    raw_fk = time.perf_counter() - t0
    t0 = time.perf_counter()
    for q in Q:
        r.fk(q)
    rd_fk = time.perf_counter() - t0
    V, A = rng.uniform(-1, 1, (2000, 6)), rng.uniform(-1, 1, (2000, 6))
    t0 = time.perf_counter()
    for q, v, a in zip(Q, V, A):
        pin.rnea(m, d, q, v, a)
    raw_id = time.perf_counter() - t0
    t0 = time.perf_counter()
    for q, v, a in zip(Q, V, A):
        r.rnea(q, v, a)
    rd_rnea = time.perf_counter() - t0
    t0 = time.perf_counter()
    for q, v, a in zip(Q, V, A):
        r.drivetrain_torques(q, v, a)
    rd_id = time.perf_counter() - t0
    print(f"FK:   raw pinocchio {raw_fk / 2000 * 1e6:.2f} us, robodesign Robot.fk {rd_fk / 2000 * 1e6:.2f} us "
          f"-> ratio {rd_fk / raw_fk:.2f}x")
    print(f"RNEA: raw pinocchio {raw_id / 2000 * 1e6:.2f} us, robodesign Robot.rnea {rd_rnea / 2000 * 1e6:.2f} us "
          f"-> ratio {rd_rnea / raw_id:.2f}x; Robot.drivetrain_torques per sample (RNEA + motor inertia + friction) "
          f"{rd_id / 2000 * 1e6:.2f} us -> ratio {rd_id / raw_id:.2f}x")


if __name__ == "__main__":
    main()
