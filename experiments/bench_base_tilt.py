"""Would tilting the base help? For informed candidates of robodesign_heavy on Whitman2020 5/5 tasks (the base
free in x, y, z ±1 m and in rotation), the same first-joint position with three base orientations: upright as
searched (the candidate's yaw), a uniformly random rotation, and hanging (upside down). Counts how many designs
pass the IK and static-torque stages, and where the others stop.

    .venv/bin/python experiments/bench_base_tilt.py [--count 40] TASK.json ...
"""
import argparse
from collections import Counter

import numpy as np
from scipy.spatial.transform import Rotation

from robodesign.design.problem import Problem
from robodesign.design.solve import SolveSettings, solve, warm_up


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tasks", nargs="+")
    ap.add_argument("--count", type=int, default=40, help="informed candidates per task")
    args = ap.parse_args()
    warm_up()
    res: Counter = Counter()
    for path in args.tasks:
        pr = Problem.build(path, "robodesign_heavy", "cyc")
        rng = np.random.default_rng(0)
        for _ in range(args.count):
            cand = pr.space.informed_candidate(rng)
            T = pr.base_bounds.pose(cand.base)
            o_local, _ = pr.space._order_reach(tuple(cand.order))
            o = (T @ np.append(o_local, 1.0))[:3]  # the first joint stays where the informed sampler put it
            for variant in ("upright", "random tilt", "hanging"):
                T2 = T.copy()
                if variant == "random tilt":
                    T2[:3, :3] = Rotation.random(random_state=int(rng.integers(1 << 30))).as_matrix()
                elif variant == "hanging":
                    T2[:3, :3] = T[:3, :3] @ np.diag([1.0, -1.0, -1.0])
                T2[:3, 3] = o - T2[:3, :3] @ o_local
                r = solve(pr.task, pr.module_set, list(cand.order), T2, "cyc", SolveSettings(stop_after="static_torque"))
                res[(variant, "passed" if r.stage == "done" else r.stage)] += 1
    for variant in ("upright", "random tilt", "hanging"):
        row = {k[1]: v for k, v in res.items() if k[0] == variant}
        print(f"{variant:12s} " + ", ".join(f"{k} {v}" for k, v in sorted(row.items())))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
