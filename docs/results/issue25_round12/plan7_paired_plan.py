"""Paired A/B of the plan stage on PTP_3's feasible fresh arms (issue 25, round 12, plan7).

Usage: ``python plan7_paired_plan.py A B FEAS_PKL [PASSES]``: per pass two fresh worker processes
(plan7_plan_stage.py --serve, one per checkout, both pinned to CPU 0) evaluate the same candidates in turn, candidate
by candidate (A first on even candidates, B first on odd ones). Prints per pass the plan CPU sums, their ratio B/A
and the median of the per-candidate ratios, then over all passes the same, and whether every pass planned the same
paths on both sides.
"""
import json
import os
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np

a_src, b_src, feas_pkl = sys.argv[1:4]
passes = int(sys.argv[4]) if len(sys.argv) > 4 else 3
here = Path(__file__).with_name("plan7_plan_stage.py")
n = len(pickle.loads(Path(feas_pkl).read_bytes()))
env = dict(os.environ, OPENBLAS_NUM_THREADS="1")


def worker(src):
    p = subprocess.Popen(["taskset", "-c", "0", sys.executable, "-W", "ignore", str(here), src, feas_pkl, "--serve"],
                         stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
    while p.stdout.readline().strip() != "ready":
        pass
    return p


def ask(p, i):
    p.stdin.write(f"{i}\n")
    p.stdin.flush()
    return json.loads(p.stdout.readline())


all_a, all_b = [], []
for k in range(passes):
    A, B = worker(a_src), worker(b_src)
    ta, tb, ha, hb = [], [], None, None
    for i in range(1, n):
        first, second = (A, B) if i % 2 == 0 else (B, A)
        r1, r2 = ask(first, i), ask(second, i)
        (ra, rb) = (r1, r2) if first is A else (r2, r1)
        ta.append(ra[0])
        tb.append(rb[0])
        ha, hb = ra[1], rb[1]
    for p in (A, B):
        p.stdin.close()
        p.wait()
    ta, tb = np.array(ta), np.array(tb)
    all_a.append(ta)
    all_b.append(tb)
    print(f"pass {k + 1}: plan CPU A {ta.sum():.3f} s, B {tb.sum():.3f} s, sum B/A {tb.sum() / ta.sum():.3f}, "
          f"per-candidate B/A median {np.median(tb / ta):.3f}; medians A {1e3 * np.median(ta):.2f} ms, "
          f"B {1e3 * np.median(tb):.2f} ms; paths {'same' if ha == hb else 'DIFFERENT'} ({ha} {hb})", flush=True)
ta, tb = np.concatenate(all_a), np.concatenate(all_b)
print(f"all: sum B/A {tb.sum() / ta.sum():.3f}, per-candidate B/A median {np.median(tb / ta):.3f}, "
      f"mean A {1e3 * ta.mean():.2f} ms, B {1e3 * tb.mean():.2f} ms")
