"""Robot–obstacle clearances of the certified sweep (:mod:`robodesign.model.sweep`) bounded from the obstacles' distance
fields, so that coal is asked only about the steps these bounds do not certify (issue 25: on the 350-sample PTP_3
check, a convex piece of the arm against the CNC mesh costs coal ~50 µs a query, most of the sweep's time).

At every sample k, robot geometry g is inside a sphere (:func:`robodesign.model.collision_cull` 's: its local box's
centre, the half diagonal plus coal's swept-sphere radius) whose centre's distance to the obstacle is bounded below
by the obstacle's box and by its :class:`~robodesign.model.collision_cull.DistanceField` (the exact distance of the
centre's grid cell, less the centre's distance to the cell's centre: distance is 1-Lipschitz); less the radius and
:data:`~robodesign.model.collision_cull.SLACK` (1e-4 m, far above coal's tolerances) that bounds the pair's distance,
and less the pair's margin its clearance F_k (compiled: :func:`robodesign.model.sweep_kernel.obstacle_bounds`; the
field's cells met unknown are computed first, once per obstacle shape and pose for the process, as the culler
does). Over step k the pair's distance changes by at most the schedule's bound S_k, linearly in the step's
fraction (:class:`~robodesign.model.sweep_bounds.PosedArms`), so the clearance stays above (F_k + F_k+1 − S_k)/2
over the whole step. A step is **certified** when that exceeds both 4·tolerance and 1/500 of the step's static
bound (what :meth:`SweepChecker._advance <robodesign.model.sweep.SweepChecker._advance>` steps with): no sample
query inside such a step could find a contact, no sub-step of ``_advance`` could report one or run out of sub-steps
(each advances at least 1/500 of the step). The sweep skips a pair's queries over its certified steps and asks coal
at the first step that is not (:meth:`SweepChecker.check <robodesign.model.sweep.SweepChecker.check>`), so a
contact is found from the same sample with the same sub-steps as before; only fewer queries are made. Without the
compiled kernels (before their compilation) nothing is skipped.
"""
from __future__ import annotations

import heapq
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from robodesign.model.collision_cull import SLACK, _bounding_sphere, distance_field
from robodesign.model.sweep_bounds import BOUND_SLACK, _kernel

#: a certified step keeps a clearance above this fraction of its static bound (at most 1/ADVANCE_SHARE sub-steps
#: of SweepChecker._advance in it, far below its max_substeps)
ADVANCE_SHARE = 500.0


def robot_spheres(geometries: Sequence) -> Tuple[np.ndarray, np.ndarray]:
    """(centres (G, 3) in each geometry's frame, radii (G,)): the spheres of the collision culler around the robot's
    collision geometries (their coal shapes)."""
    spheres = [_bounding_sphere(geo) for geo in geometries]
    return (np.array([c for c, _ in spheres], dtype=float).reshape(len(spheres), 3),
            np.array([r for _, r in spheres], dtype=float))


def clearance_bounds(robot, TG: np.ndarray, geo: np.ndarray, obstacle: int, spheres) -> Optional[np.ndarray]:
    """(n, len(geo)) lower bounds of the distance from robot geometries ``geo`` to the robot's geometry object
    ``obstacle`` (a static obstacle) at the samples whose geometry poses are TG, less SLACK; None without the
    compiled kernel. The obstacle's distance-field cells met unknown are computed first."""
    kernel = _kernel(count=False)
    if kernel is None:
        return None
    o = robot.geom_model.geometryObjects[obstacle]
    field = distance_field(o.geometry, o.placement.homogeneous)
    cen, rad = spheres[0][geo], spheres[1][geo] + SLACK
    out = np.empty((len(TG), len(geo)))
    unknown = np.empty(len(TG) * len(geo), np.int64)
    args = (TG, geo, cen, rad, field.R_inv, field.t, field.box_lo, field.box_hi, field.grid_lo, field.grid_dim,
            field.cell, field.values, out, unknown)
    nu = kernel.obstacle_bounds(*args)
    if nu:
        field.fill(unknown[:nu])
        kernel.obstacle_bounds(*args)
    return out


def open_steps(checker, TG: Optional[np.ndarray], sched: np.ndarray, dQ: np.ndarray, ext: float) \
        -> Dict[int, np.ndarray]:
    """Per robot–obstacle pair c of ``checker`` (a SweepChecker with the posed bounds): row (n − 1,) whose entry k is
    the first step ≥ k its clearance bounds do not certify (n − 1: none to the end), from the geometry poses TG at
    the samples, the schedule's step bounds ``sched`` (n − 1, P), the joints' step bounds ``dQ`` (n − 1, dof: the
    static bound is dQ @ W) and ``ext`` (module docstring). Empty without poses or kernel."""
    out: Dict[int, np.ndarray] = {}
    spheres = getattr(checker, "_spheres", None)
    if TG is None or spheres is None or len(TG) < 2:
        return out
    n = len(TG)
    obstacles = np.array(checker._obst, dtype=np.int64)
    geo = np.array(checker._mov, dtype=np.int64)
    for ob in np.unique(obstacles[obstacles >= 0]).tolist():
        c = np.flatnonzero(obstacles == ob)
        lb = clearance_bounds(checker.robot, TG, geo[c], ob, spheres)
        if lb is None:
            return out
        F = lb - checker.margins[c]
        W = checker.W[:, c]
        static = sum(dQ[:, j, None] * W[j] for j in range(len(W)))  # (a few ulps from dQ @ W: far below 1/500)
        keep = np.maximum(ext, static / ADVANCE_SHARE)
        with np.errstate(invalid="ignore", over="ignore"):
            ok = ((F[:-1] + F[1:]) - sched[:, c] * BOUND_SLACK) * 0.5 - 1e-12 > keep
        first = np.where(ok, n - 1, np.arange(n - 1)[:, None])  # the step itself where it is not certified
        first = np.minimum.accumulate(first[::-1], axis=0)[::-1]
        for i, cc in enumerate(c.tolist()):
            out[cc] = first[:, i].copy()
    return out


def due_pairs(heap: list, k: int, n: int, skip: Dict[int, np.ndarray]) -> List[int]:
    """Pop the pairs due at sample k from the sweep's ``heap`` ((sample, pair), the earliest first): those to query
    there; a pair whose clearance bounds certify from k (``skip``: :func:`open_steps`) is pushed back at the first
    step they do not certify (to query its first sample), or dropped when they certify it to the end."""
    due = []
    while heap and heap[0][0] == k:
        c = heapq.heappop(heap)[1]
        j = int(skip[c][k]) if c in skip and k < n - 1 else k
        if j == k:
            due.append(c)
        elif j < n - 1:
            heapq.heappush(heap, (j, c))
    return due


__all__ = ["ADVANCE_SHARE", "clearance_bounds", "due_pairs", "open_steps", "robot_spheres"]
