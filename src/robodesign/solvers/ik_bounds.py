"""Provable reachability bounds of a robot's TCP chain (:class:`ChainBounds`): what no configuration reaches,
decided before any IK restart (:func:`robodesign.solvers.ik.provably_unreachable`; the method in
:mod:`robodesign.solvers.ik`'s docstring). Joint limits and collisions are ignored, so the bounds never reject a
reachable goal (tests/test_ik_bounds.py).
"""
from __future__ import annotations

import math
import weakref
from typing import Dict, Tuple

import numpy as np

from robodesign.model.robot import vector_norm
from robodesign.solvers.goal_terms import goal_terms, tcp_terms  # (what the goal gives, kept per goal)

__all__ = ["ChainBounds", "chain_bounds"]


def _circle_distance(x: np.ndarray, center: np.ndarray, axis: np.ndarray, radius: float) -> float:
    """Distance from point x to the circle (center, unit axis, radius)."""
    v = x - center
    h = float(v @ axis)
    return math.hypot(h, vector_norm(v - h * axis) - radius)


_REVOLUTE_AXES = {"JointModelRX": (1.0, 0.0, 0.0), "JointModelRY": (0.0, 1.0, 0.0), "JointModelRZ": (0.0, 0.0, 1.0)}


class ChainBounds:
    """What the TCP chain of a robot (at its base pose) can reach, as bounds that hold for every q.

    * the sphere of :meth:`Robot.reach_bound` (centre o₁, the first joint's origin, radius R);
    * when the first joint is revolute, the *torus*: the second joint's origin o₂ moves on a circle C₁
      about the first joint's axis, and the TCP lies within R' = R − |o₁o₂| of o₂, so within R' of C₁;
    * given the TCP's orientation (a goal bounding it), the origin of the last joint's moving frame is
      ``p − R·c`` (c: that origin seen from the TCP, fixed), within R'' = R' − |c| of C₁.

    ``circle`` is None when the first joint is not revolute or the chain has fewer than two joints."""

    _AXES = {name: np.array(v) for name, v in _REVOLUTE_AXES.items()}   # (read, never written)

    def __init__(self, robot):
        self._verdicts: Dict[int, Tuple[object, str]] = {}   # id(goal model) → (it, unreachable's answer)
        self.key = robot.base_pose.tobytes()   # (the base pose they hold for: chain_bounds' cache)
        self.o, self.R = robot.reach_bound()
        self.circle = None
        m = robot.kinematic_model
        chain = robot.tcp_chain()
        P = m.frames[robot.tcp_frame].placement
        t_tcp = P.translation
        self.c_tcp = P.rotation.T @ t_tcp
        if len(chain) < 2 or not math.isfinite(self.R):
            return
        j1, j2 = chain[0], chain[1]
        jm = m.joints[j1]
        name = jm.shortname()
        if name in self._AXES:   # (a unit axis: its norm is 1.0 exactly, dividing by it changes no bit)
            ax, unit = self._AXES[name], True
        elif name == "JointModelRevoluteUnaligned":
            ax, unit = np.asarray(jm.extract().axis if hasattr(jm, "extract") else jm.axis, float), False
        else:
            return
        parents = m.parents
        if parents[j1] != 0 or parents[j2] != j1:
            return
        F1 = m.jointPlacements[j1]            # the first joint's frame in the world (its parent is the world)
        R1 = F1.rotation
        t2 = m.jointPlacements[j2].translation
        along = float(ax @ t2)
        offset = ax * along
        self.circle = (F1.translation + R1 @ offset, R1 @ ax if unit else R1 @ ax / vector_norm(ax),
                       vector_norm(t2 - offset))
        self.R1 = self.R - vector_norm(t2)       # R'
        self.R2 = self.R1 - vector_norm(t_tcp)   # R''

    def unreachable(self, gm) -> str:
        """Why no configuration can put the TCP into the goal of ``gm`` (a :class:`robodesign.solvers.ik.GoalModel`;
        '' when the bounds allow it); remembered per goal model (the bounds and the goal are fixed: the IK stage asks
        once per goal, solve_ik again)."""
        hit = self._verdicts.get(id(gm))
        if hit is not None and hit[0] is gm:
            return hit[1]
        why = self._unreachable(gm)
        self._verdicts[id(gm)] = (gm, why)
        return why

    def _unreachable(self, gm) -> str:
        if gm.unconstrained:
            return ""
        rp, pn, _ = goal_terms(gm)
        if not self._surely_within(gm, pn) and gm.position_lower_bound(self.o) > self.R + 1e-9:
            return "out_of_reach"
        if self.circle is None:
            return ""
        if not math.isfinite(rp):
            return ""
        c, a, rho = self.circle
        if _circle_distance(pn, c, a, rho) - rp > self.R1 + 1e-9:
            return "out_of_reach"
        rs, w = tcp_terms(gm, self.c_tcp)
        if math.isfinite(rs):
            slack = rp + rs
            if _circle_distance(w, c, a, rho) - slack > self.R2 + 1e-9:
                return "out_of_orientation_reach"
        return ""

    def _surely_within(self, gm, pn: np.ndarray) -> bool:
        """Whether ``gm.position_lower_bound(o) > R + 1e-9`` is certainly False without computing it: the goal's
        nominal position pn lies in each of its position sets (:func:`_nominal_inside`), so the bound (the distance
        from o to a box, or |o − pn| − r) is at most |o − pn|, and that is at most R (< 100 m: the roundings of both
        sides and a box frame's Q off a rotation by 1e-12 stay far below the 1e-9 m)."""
        return _nominal_inside(gm) and vector_norm(self.o - pn) <= self.R < 100.0


_INSIDE: Dict[int, Tuple[object, bool]] = {}   # id(goal model) → (it, _nominal_inside's answer)


def _nominal_inside(gm) -> bool:
    """Whether the goal's nominal position lies in its position sets: every complete x/y/z box (in a frame whose Q
    is a rotation to 1e-12, or the nominal's) holds 0 and the r_sph bound is not negative; kept per goal model."""
    hit = _INSIDE.get(id(gm))
    if hit is None or hit[0] is not gm:   # (the model is held: its id is not reused while the entry lives)
        if len(_INSIDE) >= 4096:
            _INSIDE.clear()
        inside = not gm.sphere_hi < 0.0 and all(
            (Q is None or np.abs(Q.T @ Q - np.eye(3)).max() <= 1e-12) and (lo <= 0.0).all() and (hi >= 0.0).all()
            for Q, lo, hi in gm._position_boxes)
        hit = _INSIDE[id(gm)] = (gm, bool(inside))
    return hit[1]


_BOUNDS_CACHE: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def chain_bounds(robot) -> ChainBounds:
    """The robot's :class:`ChainBounds` (cached per robot and base pose)."""
    hit = _BOUNDS_CACHE.get(robot)
    if hit is not None and hit.key == robot.base_pose.tobytes():
        return hit
    cb = ChainBounds(robot)
    try:
        _BOUNDS_CACHE[robot] = cb
    except TypeError:
        pass
    return cb
