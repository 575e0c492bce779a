"""Figure for docs/checker.md: the motion the judge reads between samples.

    .venv/bin/python experiments/plot_motion_model.py [--out docs/img/motion_model.png]

Left: robodesign-style samples (constant acceleration per step): the judged motion is exactly that motion.
Right: the rest-sampled cheat of issue 22 (case 2): samples at rest every 0.155 s; the least-acceleration
motion through them (two arcs per step) needs 4·Δq/h² — far above the limit — and a file claiming those
samples claims that motion.
"""
from __future__ import annotations

import argparse

import numpy as np

from robodesign.judge.motion import StepMotion


def dense(m: StepMotion, n: int = 60):
    ts, qs, accs = [], [], []
    for k in range(len(m.h)):
        for s in np.linspace(0, 1, n, endpoint=False):
            x = s * m.h[k, 0]
            ts.append(m.t[k] + x)
            qs.append(m.at(k, s)[0])
            accs.append(m.a1[k, 0] if x < m.tau[k, 0] else m.a2[k, 0])
    return np.array(ts), np.array(qs), np.array(accs)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default="docs/img/motion_model.png")
    args = ap.parse_args()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(2, 2, figsize=(10, 5.5), sharex="col")
    # honest: bang-bang 0 -> 0.439 rad in 0.31 s at A = 18.3 rad/s^2, sampled every 10 ms
    A, D = 34.1, 0.439
    T = 2 * np.sqrt(D / A) * 1.0
    t = 0.01 * np.arange(int(np.ceil(T / 0.01)) + 1)
    T = t[-1]
    a = 4 * D / T ** 2
    q = np.where(t <= T / 2, a * t ** 2 / 2, D - a * (T - t) ** 2 / 2)
    v = np.where(t <= T / 2, a * t, a * (T - t))
    m = StepMotion.through(t, q[:, None], v[:, None])
    tt, qq, aa = dense(m)
    axes[0, 0].plot(tt, qq, "-", label="judged motion")
    axes[0, 0].plot(t, q, "o", ms=3, label="samples (q, dq)")
    axes[1, 0].step(tt, aa, where="post", label="its acceleration")
    axes[1, 0].axhline(A, color="r", ls="--", label=f"limit {A} rad/s²")
    axes[1, 0].axhline(-A, color="r", ls="--")
    axes[0, 0].set_title("honest samples (10 ms): the motion is theirs")
    # cheat: the same displacement in 0.155 s, at rest at both samples
    t2 = np.array([0.0, 0.155])
    m2 = StepMotion.through(t2, np.array([[0.0], [D]]), np.zeros((2, 1)))
    tt, qq, aa = dense(m2, 200)
    axes[0, 1].plot(tt, qq, "-", label="least-acceleration motion")
    axes[0, 1].plot(t2, [0, D], "o", ms=5, label="samples at rest (dq = 0)")
    axes[1, 1].step(tt, aa, where="post", label=f"needs ±{m2.peak_acceleration[0, 0]:.1f} rad/s²")
    axes[1, 1].axhline(A, color="r", ls="--", label=f"limit {A} rad/s²")
    axes[1, 1].axhline(-A, color="r", ls="--")
    axes[0, 1].set_title("rest-sampled cheat (issue 22, case 2)")
    for ax in axes.flat:
        ax.legend(fontsize=8, loc="best")
        ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("q [rad]")
    axes[1, 0].set_ylabel("q̈ [rad/s²]")
    axes[1, 0].set_xlabel("t [s]")
    axes[1, 1].set_xlabel("t [s]")
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}; cheat step needs {m2.peak_acceleration[0, 0]:.1f} rad/s² (4·Δq/h²)")


if __name__ == "__main__":
    main()
