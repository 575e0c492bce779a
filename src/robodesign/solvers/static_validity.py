"""The planner's static validity test (joint limits and torques, no collision query), for one configuration and for
many at once: the part of :func:`robodesign.solvers.planning._config_validator` before the collision query (its
decisions are in :mod:`robodesign.solvers.planning`'s docstring).
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from robodesign.model.rnea_batch import rnea_rows
from robodesign.model.robot import Robot

#: rad (largest joint difference): around the configurations where a planned motion stands still (start, goals)
#: the friction headroom of the static-torque test is not asked (the robot starts and stops there)
REST_RADIUS = 0.05
_LIMIT_SLACK = 1e-9


def static_validator(robot, static_torque: bool = False, rest: Sequence = ()):
    """The part of the planner's validity test before the collision query
    (:func:`robodesign.solvers.planning._config_validator`): joint limits and, with ``static_torque``, the torque
    tests; ``ok(q)`` for one configuration, ``ok.rows(Q)`` for every row of ``Q``."""
    lo = np.asarray(robot.q_lower, dtype=float) - _LIMIT_SLACK
    hi = np.asarray(robot.q_upper, dtype=float) + _LIMIT_SLACK
    tau_max = np.asarray(robot.tau_max, dtype=float)
    gravity = robot.gravity_torque if static_torque and np.isfinite(tau_max).any() else None
    moving_max = tau_max - np.asarray(getattr(robot, "friction_coulomb", np.zeros_like(tau_max)), dtype=float)
    R = np.vstack([np.asarray(q, dtype=float) for q in rest]) if len(rest) and gravity is not None else None

    def ok(q: np.ndarray) -> bool:
        if (q < lo).any() or (q > hi).any():
            return False
        if gravity is not None:
            g = np.abs(gravity(q))
            if (g > tau_max).any():
                return False
            if R is not None and (g > moving_max).any() and np.min(np.max(np.abs(R - q), axis=1)) > REST_RADIUS:
                return False
        return True

    def rows_ok(Q: np.ndarray) -> np.ndarray:
        """``ok`` of every row of ``Q`` (the same elementwise tests, vectorised)."""
        out: np.ndarray = np.asarray(~((Q < lo).any(axis=1) | (Q > hi).any(axis=1)))
        if gravity is not None and out.any():
            idx = out.nonzero()[0]
            Qi = Q[idx]
            if isinstance(robot, Robot):   # Robot.gravity_torque of every row in one call: pinocchio's RNEA at
                Z = np.zeros(Qi.shape)     # rest, the same |τ| bit for bit (tests/test_planning.py)
                G = np.abs(rnea_rows(robot.model, Qi, Z, Z))
            else:
                G = np.abs(np.array([gravity(q) for q in Qi]).reshape(len(idx), -1))
            bad = (G > tau_max).any(axis=1)
            if R is not None:   # the rows held, but without room for friction: bad where far from every rest
                t = ((G > moving_max).any(axis=1) & ~bad).nonzero()[0]
                if len(t):
                    bad[t[np.min(np.max(np.abs(R[None, :, :] - Qi[t][:, None, :]), axis=2), axis=1) > REST_RADIUS]] = True
            out[idx[bad]] = False
        return out
    ok.rows = rows_ok  # type: ignore[attr-defined]
    return ok


__all__ = ["REST_RADIUS", "static_validator"]
