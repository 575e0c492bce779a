"""The planner's static validity test (joint limits and torques, no collision query), for one configuration and for
many at once: the part of :func:`robodesign.solvers.planning._config_validator` before the collision query (its
decisions are in :mod:`robodesign.solvers.planning`'s docstring).
"""
from __future__ import annotations

import math
import weakref
from typing import List, Optional, Sequence, Tuple

import numpy as np

from robodesign.model.rnea_batch import rnea_rows
from robodesign.model.robot import Robot

#: rad (largest joint difference): around the configurations where a planned motion stands still (start, goals)
#: the friction headroom of the static-torque test is not asked (the robot starts and stops there)
REST_RADIUS = 0.05
_LIMIT_SLACK = 1e-9
#: pinocchio's revolute joints (the origin stays where the parent's placement puts it) and their axes (None: any)
_REVOLUTE = {"JointModelRX": np.array([1.0, 0.0, 0.0]), "JointModelRY": np.array([0.0, 1.0, 0.0]),
             "JointModelRZ": np.array([0.0, 0.0, 1.0]), "JointModelRevoluteUnaligned": None}
#: relative margin of :func:`gravity_bound` over the rounding of pinocchio's sums (~1e-15 relative)
_BOUND_MARGIN = 1e-6


def gravity_bound(model) -> Optional[np.ndarray]:
    """(nv,) an upper bound of |g(q)| (the gravity torques, pinocchio's RNEA at rest) over every configuration, or
    None unless every joint is revolute with one coordinate. Joint j holds the weight m_b·|g| of each body b of its
    subtree at a lever of at most the body's distance from j's origin, itself at most the sum of the joint
    placements' lengths from j to b plus b's centre-of-mass lever (revolute joints do not move their origins).
    A root joint's axis is fixed in the world: only the weight's part across it counts, |g × axis|. The margin
    ``_BOUND_MARGIN`` of the whole weight's bound covers the rounding of pinocchio's sums."""
    return _bound(model, _lever_sums(model))


def _lever_sums(model) -> Optional[Tuple[List[str], List[int], List[float]]]:
    """What :func:`gravity_bound` needs of the model besides its gravity and root placements: the joints' kinds,
    their parents and per joint Σ m_b·(the bound of b's lever about it) over its subtree (index 0: the universe);
    None unless every joint is revolute with one coordinate."""
    n = model.njoints
    if model.nq != model.nv or model.nv != n - 1:
        return None
    kinds = [j.shortname() for j in model.joints]
    bodies = [(y.mass, y.lever) for y in model.inertias]
    if any(k not in _REVOLUTE for k in kinds[1:]) or any(mass < 0 for mass, _ in bodies):
        return None
    parents = model.parents.tolist()
    link = np.linalg.norm([M.translation for M in model.jointPlacements], axis=1).tolist()
    lever = np.linalg.norm([c for _, c in bodies], axis=1).tolist()
    sums = [0.0] * n
    for b in range(1, n):
        mass, reach, j = bodies[b][0], lever[b], b
        while j > 0:           # up the tree from b: j's origin is reach away at most
            sums[j] += mass * reach
            reach += link[j]
            j = parents[j]
    return kinds, parents, sums


def _bound(model, lever_sums) -> Optional[np.ndarray]:
    """:func:`gravity_bound` from the model's gravity and root placements and its :func:`_lever_sums`."""
    if lever_sums is None:
        return None
    kinds, parents, sums = lever_sums
    gx, gy, gz = model.gravity.linear.tolist()
    g = math.sqrt(gx * gx + gy * gy + gz * gz)
    out = np.empty(len(sums) - 1)
    for j in range(1, len(sums)):
        whole = g * sums[j]
        part = whole
        axis = _REVOLUTE[kinds[j]]
        if axis is not None and parents[j] == 0 and g > 0:   # |g × axis| / |g|, the axis in the world
            ax, ay, az = (model.jointPlacements[j].rotation @ axis).tolist()
            part *= math.hypot(gy * az - gz * ay, gz * ax - gx * az, gx * ay - gy * ax) / g
        out[j - 1] = part + _BOUND_MARGIN * (whole + 1.0)
    return out


def _robot_bound(robot: Robot) -> Optional[np.ndarray]:
    """:func:`gravity_bound` of the robot's model, its :func:`_lever_sums` kept per robot and model: a robot's base
    pose and gravity change only its root placements and gravity, read at each call (the zero inertias its frames
    add change a lever by a rounding, far inside ``_BOUND_MARGIN``)."""
    model = robot.model
    hit = _LEVER_SUMS.get(robot)
    if hit is None or hit[0] is not model:
        hit = _LEVER_SUMS[robot] = (model, _lever_sums(model))
    return _bound(model, hit[1])


_LEVER_SUMS: "weakref.WeakKeyDictionary[Robot, tuple]" = weakref.WeakKeyDictionary()


def static_validator(robot, static_torque: bool = False, rest: Sequence = ()):
    """The part of the planner's validity test before the collision query
    (:func:`robodesign.solvers.planning._config_validator`): joint limits and, with ``static_torque``, the torque
    tests; ``ok(q)`` for one configuration, ``ok.rows(Q)`` for every row of ``Q``. A robot whose
    :func:`gravity_bound` is below its torque limits less Coulomb friction passes both torque tests everywhere: its
    tests ask no gravity torques (the same verdicts, tests/test_static_bound.py)."""
    lo = np.asarray(robot.q_lower, dtype=float) - _LIMIT_SLACK
    hi = np.asarray(robot.q_upper, dtype=float) + _LIMIT_SLACK
    tau_max = np.asarray(robot.tau_max, dtype=float)
    gravity = robot.gravity_torque if static_torque and np.isfinite(tau_max).any() else None
    moving_max = tau_max - np.asarray(getattr(robot, "friction_coulomb", np.zeros_like(tau_max)), dtype=float)
    if gravity is not None and isinstance(robot, Robot):   # no configuration needs more than the joints have
        bound = _robot_bound(robot)
        if bound is not None and np.all(bound < np.minimum(tau_max, moving_max)):
            gravity = None
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
