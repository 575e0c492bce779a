"""How far the arms of a module set can reach: an admissible bound over every valid module order, and the
proof that a task's goals lie beyond it.

**The set's reach bound** (:func:`set_reach`). For every module, :func:`~robodesign.model.extent.module_extent` bounds the distance
between the connector it is attached by and the connector the next module attaches to (the TCP for an end
effector, the base connector for a base), over every joint configuration: a rigid path is its length; a path
over one revolute joint is exactly ``√(h² + (r_a + r_b)²)`` (h: the two points' distance along the axis, r_a,
r_b: their distances from it; the joint turns freely, limits ignored); a longer path sums the distances
between its joint origins (revolute joints keep them) plus the stroke of each prismatic joint. By the
triangle inequality, no TCP of an order is farther from its base pose's origin (the base connector's origin)
than the sum of its modules' extents. :func:`set_reach` maximises that sum over every order the
:class:`~robodesign.design.search_space.SearchSpace` allows (dynamic programming over its chaining states;
the states are a superset of the valid orders, so the maximum is still an upper bound) and returns the
longest order as the witness.

**The proof** (:func:`reach_proof`). A design solves a task only if every goal position lies within that
bound of one base position. With the base confined by the task's ``basePlacement`` (a box, cylinder or ball
around its nominal position), a goal farther than ``bound`` + its own position tolerance from every
allowed base position is out of reach; with any base placement, two goals farther apart than twice the
bound (plus their tolerances) cannot both be reached. A task without a ``basePlacement`` constraint
allows any base pose (as the reference judges it): only the second argument applies.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

import numpy as np

from robodesign.design.regions import distance_to_region, position_radius  # noqa: F401 - also imported from here
from robodesign.design.search_space import SearchSpace
from robodesign.design.solve import goal_poses
from robodesign.formats.module_spec import ModuleSet
from robodesign.formats.task_spec import Task


# -- per module set ------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SetReach:
    """``bound`` [m]: no TCP of any order the search space allows is farther than this from its base pose's
    origin; ``order``: an order whose module extents sum to it (the longest arm); ``extents``: per module."""
    bound: float
    order: Tuple[str, ...]
    extents: Dict[str, float] = field(default_factory=dict)


def set_reach(space: SearchSpace) -> SetReach:
    """The longest arm ``space`` allows: the largest sum of :func:`module_extent` over its valid orders
    (:meth:`SearchSpace.longest_order`, the dynamic programme behind :meth:`SearchSpace.max_reach`)."""
    bound, order = space.longest_order()
    return SetReach(bound=bound, order=order, extents={m.id: space.module_info(m.id).span for m in space.module_set})


def module_set_reach(ms: ModuleSet, **rules) -> SetReach:
    """:func:`set_reach` of ``ms`` under search-space ``rules`` (``min_dof``, ``max_dof``, ...)."""
    return set_reach(SearchSpace(ms, **rules))


def goal_points(task: Task) -> List[Tuple[str, np.ndarray, float]]:
    """(goal ID, nominal world position, position tolerance radius) of every pose a goal must reach."""
    out = []
    for g in task.goals:
        for tp in goal_poses(g):
            out.append((g.id, np.asarray(tp.nominal[:3, 3], dtype=float), position_radius(tp)))
    return out


def base_is_free(task: Task) -> bool:
    """Whether the task allows any base pose (no basePlacement, or one that constrains nothing)."""
    bp = task.base_placement
    return bp is None or bool(getattr(bp, "is_unconstrained", False))


# -- proof --------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ReachProof:
    """Why no design of the module set reaches the task: ``kind`` is ``"goal"`` (goal ``goals[0]`` is
    ``needed`` m from every allowed base position, counting its tolerance) or ``"spread"`` (goals ``goals[0]``
    and ``goals[1]`` are ``distance`` apart, ``2·needed`` counting their tolerances: any base is ``needed``
    from one of them); ``bound`` is the set's reach bound, ``order`` the longest arm. ``distance``: the
    nominal distance (goal: from the base region; spread: between the two goals)."""
    kind: str
    bound: float
    needed: float
    goals: Tuple[str, ...]
    order: Tuple[str, ...]
    distance: float = math.nan

    @property
    def message(self) -> str:
        arm = f"the longest arm of the module set reaches at most {self.bound:.3f} m from its base"
        if self.kind == "goal":
            return (f"provably out of reach: goal {self.goals[0]} is at least {self.needed:.3f} m from every "
                    f"allowed base position; {arm}")
        return (f"provably out of reach: goals {self.goals[0]} and {self.goals[1]} are {self.distance:.3f} m "
                f"apart, so one of them is at least {self.needed:.3f} m from any base (counting their tolerances); "
                f"{arm}")

    def to_json(self) -> dict:
        return {"kind": self.kind, "bound": self.bound, "needed": self.needed, "distance": self.distance,
                "goals": list(self.goals), "order": list(self.order), "message": self.message}


def reach_proof(task: Task, space: SearchSpace, reach: Optional[SetReach] = None) -> Optional[ReachProof]:
    """A proof that no order of ``space`` at any base pose the task allows reaches every goal, or None.
    The base region is the task's basePlacement (not the search space's bounds: the proof is about the task)."""
    reach = reach or set_reach(space)
    R = reach.bound
    if not math.isfinite(R):
        return None
    pts = goal_points(task)
    best: Optional[ReachProof] = None
    bp = task.base_placement
    if bp is not None and not base_is_free(task):  # (base_is_free when bp is None)
        for gid, p, tol in pts:
            dist = distance_to_region(bp, p)
            need = dist - tol
            if need > R and (best is None or need > best.needed):
                best = ReachProof("goal", R, need, (gid,), reach.order, dist)
    if best is None and len(pts) > 1:
        # every pair (a sound proof needs only one; beyond _MAX_SPREAD poses, evenly spaced ones are compared)
        sel = pts if len(pts) <= _MAX_SPREAD else [pts[int(i)] for i in np.linspace(0, len(pts) - 1, _MAX_SPREAD)]
        P = np.array([p for _, p, _ in sel])
        tols = np.array([t for _, _, t in sel])
        D = np.linalg.norm(P[:, None, :] - P[None, :, :], axis=2)
        needs = (D - tols[:, None] - tols[None, :]) / 2.0
        i, j = np.unravel_index(int(np.argmax(needs)), needs.shape)
        if needs[i, j] > R:
            best = ReachProof("spread", R, float(needs[i, j]), (sel[i][0], sel[j][0]), reach.order, float(D[i, j]))
    return best


_MAX_SPREAD = 1500  # goal poses compared pairwise by the spread proof
