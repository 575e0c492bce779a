"""Replay the recorded certificate-kernel calls (plan8_record_kernels.py) through variants of the kernels: their
outputs compared and their time (issue 25, round 13, plan8).

Usage: ``python plan8_kernel_replay.py CALLS.pkl [ROUNDS]``. Variants: ``old`` (71594ba's loops), ``skip`` (a
clearance at most slack sums no bound: this branch), ``skip_newest`` (also the kept certificates tried newest first).
Prints per kernel and variant the best-of-rounds seconds over all calls and whether every output equals ``old``'s."""
import pickle
import sys
import time

import numpy as np
from numba import njit

calls = pickle.load(open(sys.argv[1], "rb"))
rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 5


@njit(cache=False)
def _proves(free, R, r, a, W, k, slack):
    b = 0.0
    for i in range(R.shape[1]):
        b += abs(R[r, i] - a[i]) * W[i, k]
    return free - b > slack


@njit(cache=False)
def clear_old(P, R, anchors, frees, m, W, cols, slack, newest):
    for r in range(R.shape[0]):
        for k in cols:
            if not P[r, k]:
                continue
            for a in range(m):
                f = frees[a, k]
                if f == f and _proves(f, R, r, anchors[a], W, k, slack):
                    P[r, k] = False
                    break


@njit(cache=False)
def clear_skip(P, R, anchors, frees, m, W, cols, slack, newest):
    for r in range(R.shape[0]):
        for k in cols:
            if not P[r, k]:
                continue
            for a in range(m):
                f = frees[a, k]
                if f > slack and _proves(f, R, r, anchors[a], W, k, slack):
                    P[r, k] = False
                    break


@njit(cache=False)
def clear_skip_newest(P, R, anchors, frees, m, W, cols, slack, newest):
    for r in range(R.shape[0]):
        for k in cols:
            if not P[r, k]:
                continue
            for t in range(m):
                a = (newest - t) % m
                f = frees[a, k]
                if f > slack and _proves(f, R, r, anchors[a], W, k, slack):
                    P[r, k] = False
                    break


@njit(cache=False)
def keep_old(P, R, j, own, free, W, slack, anchors, frees, row):
    anchors[row, :] = R[j]
    frees[row, :] = np.nan
    q = anchors[row]
    for c in range(len(own)):
        k = own[c]
        frees[row, k] = free[c]
        if free[c] > slack:
            P[j, k] = False
        for r in range(j + 1, R.shape[0]):
            if P[r, k] and _proves(free[c], R, r, q, W, k, slack):
                P[r, k] = False


@njit(cache=False)
def keep_skip(P, R, j, own, free, W, slack, anchors, frees, row):
    anchors[row, :] = R[j]
    frees[row, :] = np.nan
    q = anchors[row]
    for c in range(len(own)):
        k = own[c]
        frees[row, k] = free[c]
        if not free[c] > slack:
            continue
        P[j, k] = False
        for r in range(j + 1, R.shape[0]):
            if P[r, k] and _proves(free[c], R, r, q, W, k, slack):
                P[r, k] = False


def run(fn, items):
    outs, spent = [], 0.0
    for args in items:
        a = [x.copy() if isinstance(x, np.ndarray) else x for x in args]
        t = time.perf_counter()
        fn(*a)
        spent += time.perf_counter() - t
        outs.append(a[0])
    return spent, outs


clears, keeps, last_row = [], [], 0
for name, args in calls:
    if name == "keep_and_clear":
        keeps.append(args)
        last_row = args[-1]
    else:
        P, R, anchors, frees, m, W, cols, slack = args
        clears.append((P, R, anchors, frees, m, W, cols, slack, last_row if m else 0))   # (newest: the row kept last)
for label, variants, items in (("clear_pending", [("old", clear_old), ("skip", clear_skip),
                                                  ("skip_newest", clear_skip_newest)], clears),
                               ("keep_and_clear", [("old", keep_old), ("skip", keep_skip)], keeps)):
    for _, fn in variants:
        run(fn, items[:3])
    best = {n: 1e9 for n, _ in variants}
    ref = None
    same = {}
    for _ in range(rounds):
        for n, fn in variants:
            t, outs = run(fn, items)
            best[n] = min(best[n], t)
            if ref is None:
                ref = outs
            same[n] = all(np.array_equal(x, y) for x, y in zip(outs, ref))
    print(label, len(items), "calls:", ", ".join(f"{n} {1e3 * best[n]:.1f} ms (same as old: {same[n]})"
                                                 for n, _ in variants), flush=True)
