"""Trajectories built the way the reference (Timor) builds them, to prove that the checker's one-motion
rules accept them: ``Trajectory.from_mstraj`` (Robotics Toolbox ``mstraj``: straight joint-space segments at
the slowest axis' speed, joined by constant-acceleration blends of ``t_acc`` around each via point, sampled
every ``dt``) with ``dq`` and ``ddq`` left to ``numpy.gradient``, as Timor's Trajectory fills them.

Written from that description (no toolbox dependency): positions are exact samples of the piecewise-quadratic
motion, so the motion itself is known (``max_acceleration`` per joint).
"""
from __future__ import annotations

import numpy as np


def mstraj_like(via, qd_max: float, t_acc: float, dt: float):
    """(t, q, dq, ddq, max_acceleration per joint, blend centre times) of a rest-to-rest multi-segment motion
    through ``via`` (rows). Segment durations are rounded up to multiples of ``dt`` and are at least ``t_acc``;
    the motion starts at rest at t = 0 and ends at rest."""
    P = np.asarray(via, dtype=float)
    seg = [max(t_acc, dt * np.ceil(np.max(np.abs(b - a)) / qd_max / dt - 1e-9)) for a, b in zip(P, P[1:])]
    V = np.vstack([np.zeros(P.shape[1])] + [(b - a) / T for a, b, T in zip(P, P[1:], seg)] + [np.zeros(P.shape[1])])
    centres = t_acc / 2 + np.concatenate([[0.0], np.cumsum(seg)])
    t_end = centres[-1] + t_acc / 2
    t = dt * np.arange(int(np.floor(t_end / dt + 1e-9)) + 1)

    def velocity(x):
        j = int(np.argmin(np.abs(centres - x)))
        if abs(x - centres[j]) <= t_acc / 2:  # blend j: linear from V[j] to V[j + 1]
            return V[j] + (x - centres[j] + t_acc / 2) / t_acc * (V[j + 1] - V[j])
        return V[int(np.searchsorted(centres, x))]

    # q: exact integral of the piecewise-linear velocity (trapezoid rule is exact between breakpoints)
    bps = np.unique(np.concatenate([centres - t_acc / 2, centres + t_acc / 2, t]))
    bps = bps[(bps >= 0) & (bps <= t[-1])]
    vb = np.array([velocity(x) for x in bps])
    qb = P[0] + np.vstack([np.zeros((1, P.shape[1])),
                           np.cumsum((vb[1:] + vb[:-1]) / 2 * np.diff(bps)[:, None], axis=0)])
    q = qb[np.searchsorted(bps, t)]
    dq = np.gradient(q, t, axis=0)
    ddq = np.gradient(dq, t, axis=0)
    return t, q, dq, ddq, np.max(np.abs(np.diff(V, axis=0)), axis=0) / t_acc, centres
