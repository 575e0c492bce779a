#!/usr/bin/env python
"""Task generators: time per generated task, and how many tasks the reference design solves when only the
goals of the easy variants (``--variant easy``) are verified (``--verify ik``) versus the whole task (``--verify solve``).

    flock /tmp/robodesign-bench.lock nice -n 5 .venv/bin/python experiments/bench_generate.py --count 10

Per variant: CPU seconds per task (process time, so a busy machine inflates it less than wall time) for
``--verify ik`` and ``--verify solve``, and the share of the ``ik`` tasks that robodesign.design.solve.solve with the
reference design (robodesign_arm, default order, nominal base, seed 0, default settings) solves and the checker
accepts. With ``--verify solve`` that share is 100 % by construction (up to planner time-outs on a busy machine).
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ASSETS = HERE.parent.parent / "shared" / "cobra" / "tasks" / "assets"

VARIANTS = {
    "whitman2020 3/3 fixed": ("whitman2020", {"goals": 3, "obstacles": 3}),
    "whitman2020 5/5 free": ("whitman2020", {"goals": 5, "obstacles": 5, "base": "xyz_any_rot"}),
    "liu2020 default machine": ("liu2020", {}),
    "liu2020 QUASER MV205": ("liu2020", {"machine": str(ASSETS / "QUASER_MV205_v3_compressed.stl")}),
    "liu2020 DMU 125P": ("liu2020", {"machine": str(ASSETS / "DMU_125P_compress.stl")}),
    "bpo2024 mixed": ("bpo2024", {}),
}


def solved_share(files) -> float:
    from robodesign.generate.common import REFERENCE_ORDER
    from robodesign.formats.module_io import load_module_set
    from robodesign.design.solve import solve
    from robodesign.formats.task_io import load_task
    ms = load_module_set("robodesign_arm")
    ok = sum(solve(load_task(f), ms, list(REFERENCE_ORDER)).feasible for f in files)
    return ok / len(files)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=10, help="tasks per variant and verify mode (default 10)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--only", help="comma-separated substrings of the variant names to run")
    a = ap.parse_args(argv)
    from robodesign.generate import generate
    print(f"{'variant':26s} {'ik: CPU s/task':>15s} {'solved by ref.':>15s} {'solve: CPU s/task':>18s} "
          f"{'wall s/task':>12s}")
    for name, (family, opts) in VARIANTS.items():
        if a.only and not any(s in name for s in a.only.split(",")):
            continue
        row = {}
        with tempfile.TemporaryDirectory() as tmp:
            for mode in ("ik", "solve"):
                t0, c0 = time.perf_counter(), time.process_time()
                files = generate(family, Path(tmp) / mode, a.count, a.seed, {**opts, "variant": "easy", "verify": mode})
                row[mode] = ((time.process_time() - c0) / a.count, (time.perf_counter() - t0) / a.count)
                if mode == "ik":
                    row["share"] = solved_share(files)
        print(f"{name:26s} {row['ik'][0]:15.2f} {100 * row['share']:14.0f}% {row['solve'][0]:18.2f} "
              f"{row['solve'][1]:12.2f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
