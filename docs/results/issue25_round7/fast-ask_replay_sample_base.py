# Usage: PYTHONPATH=<checkout>/src .venv/bin/python fast-ask_replay_sample_base.py oven_hard,middle_oven,whitman2020_g5o5_xyz_any_rot_s0_0000 5
"""Replay recorded sample_base calls: check results and rng states, time them (geometry memo warmed first)."""

import pickle
import sys
import time

import numpy as np

tasks = sys.argv[1].split(",")
reps = int(sys.argv[2]) if len(sys.argv) > 2 else 5
for task in tasks:
    d = pickle.load(open(f"/tmp/fa/calls_{task}.pkl", "rb"))
    sp, calls = d["space"], d["calls"]
    for _, order, _, _ in calls:
        sp._order_geometry(order)
    rng = np.random.default_rng()
    best = []
    ok = True
    for r in range(reps):
        t = time.process_time()
        for s0, order, out, s1 in calls:
            rng.bit_generator.state = s0
            got = sp.sample_base(rng, order)
            if r == 0 and (got != out or rng.bit_generator.state != s1):
                ok = False
        best.append(time.process_time() - t)
    print(
        task,
        "identical" if ok else "DIFFERENT",
        "calls",
        len(calls),
        "cpu s per pass: min %.4f median %.4f" % (min(best), sorted(best)[len(best) // 2]),
    )
