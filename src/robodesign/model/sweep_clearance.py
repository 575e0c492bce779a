"""Lower bounds of the clearances of the certified sweep's pairs (:mod:`robodesign.model.sweep`) at the samples, so
that coal is asked only about the steps these bounds do not certify (issue 25: on the 350-sample PTP_3 check a
convex piece of the arm against the CNC mesh cost coal ~50 µs a query, the self pairs 216 queries).

At every sample, robot geometry g is inside a sphere (:mod:`robodesign.model.collision_cull`'s: its local box's
centre, the half diagonal plus coal's swept-sphere radius). A **robot–obstacle** pair's distance is bounded below
by the sphere centre's distance to the obstacle's box or, where larger, by its
:class:`~robodesign.model.collision_cull.DistanceField` (the exact distance of the centre's grid cell less the
centre's distance to the cell's centre: distance is 1-Lipschitz), less the radius (compiled:
:func:`robodesign.model.sweep_kernel.obstacle_bounds`; the field's cells met unknown are computed first, once per
obstacle shape and pose for the process, as the culler does). A **self** pair's by the distance between its two
spheres' centres less both radii. Both keep :data:`~robodesign.model.collision_cull.SLACK` (1e-4 m, far above coal's
tolerances) and are taken at the geometries' poses of batched FK (pinocchio's to ~1e-15 m). Less the pair's margin:
the clearance bound F_k at sample k. Over step k the pair's distance changes by at most the schedule's bound S_k,
linearly in the step's fraction (:class:`~robodesign.model.sweep_bounds.PosedArms`), so the clearance stays above
(F_k + F_k+1 − S_k)/2 over the whole step. A step is **certified** when that exceeds both 4·tolerance and 1/500 of
(a bound on) the step's static bound, what :meth:`SweepChecker._advance <robodesign.model.sweep.SweepChecker._advance>`
steps with: no sample query inside such a step could find a contact, no sub-step of ``_advance`` could report one
or run out of sub-steps (each advances at least 1/500 of the step). The sweep skips a pair's queries over its
certified steps and asks coal at the first step that is not (:func:`due_pairs`), so a contact is found from the
same sample with the same sub-steps as before; only fewer queries are made. Without the compiled kernels (before
their compilation) nothing is skipped.
"""
from __future__ import annotations

import heapq
from typing import List, Optional, Sequence, Tuple

import numpy as np

from robodesign.model.collision_cull import SLACK, bounding_sphere, distance_field
from robodesign.model.sweep_bounds import BOUND_SLACK, _kernel

#: a certified step keeps a clearance above this fraction of its static bound (at most 1/ADVANCE_SHARE sub-steps
#: of SweepChecker._advance in it, far below its max_substeps)
ADVANCE_SHARE = 500.0


def robot_spheres(geometries: Sequence) -> Tuple[np.ndarray, np.ndarray]:
    """(centres (G, 3) in each geometry's frame, radii (G,)): the spheres of the collision culler around the robot's
    collision geometries (their coal shapes)."""
    spheres = [bounding_sphere(geo) for geo in geometries]
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


def self_bounds(TG: np.ndarray, a: np.ndarray, b: np.ndarray, spheres) -> np.ndarray:
    """(n, len(a)) lower bounds of the distance between robot geometries a[i] and b[i] at the samples whose geometry
    poses are TG: the distance of their spheres' centres less both radii and SLACK (compiled)."""
    cen, rad = spheres
    out = np.empty((len(TG), len(a)))
    _kernel(count=False).sphere_gaps(TG, cen, a, b, rad[a] + rad[b] + SLACK, out)
    return out


def open_steps(checker, TG: Optional[np.ndarray], sched: np.ndarray, dQ: np.ndarray, ext: float) \
        -> Optional[np.ndarray]:
    """(P, n − 1): per pair c of ``checker`` (a SweepChecker with the posed bounds), entry k the first step ≥ k its
    clearance bounds (:func:`clearance_bounds` of a robot–obstacle pair, :func:`self_bounds` of a self pair) do not
    certify (n − 1: none to the end), from the geometry poses TG at the samples, the schedule's step bounds ``sched``
    (n − 1, P), the joints' step bounds ``dQ`` (n − 1, dof: the static bound is dQ @ W) and ``ext`` (module
    docstring). None without poses or kernel."""
    spheres = getattr(checker, "_spheres", None)
    kernel = _kernel(count=False)
    if TG is None or spheres is None or len(TG) < 2 or kernel is None:
        return None
    n, P = len(TG), len(checker.pairs)
    obstacles = np.array(checker._obst, dtype=np.int64)
    mov, ref = (np.array(x, dtype=np.int64) for x in (checker._mov, checker._ref))
    groups = [(c, clearance_bounds(checker.robot, TG, mov[c], ob, spheres))
              for ob in np.unique(obstacles[obstacles >= 0]).tolist() for c in [np.flatnonzero(obstacles == ob)]]
    c = np.flatnonzero(obstacles < 0)
    if len(c):
        groups.append((c, self_bounds(TG, mov[c], ref[c], spheres)))
    if len(groups) == 1:  # (the judge's: the self pairs, or the pairs with its one obstacle)
        F = groups[0][1]
    else:
        F = np.empty((n, P))
        for c, lb in groups:
            F[:, c] = lb
    F -= checker.margins
    fastest = dQ.max(axis=1) * (1 + 1e-9)  # static bound dQ @ W ≤ max_j |Δq_j| · Σ_j W[j]
    out = np.empty((P, n - 1), np.int64)
    kernel.open_steps(F, np.ascontiguousarray(sched), fastest, checker.W.sum(axis=0), ext, BOUND_SLACK,
                      ADVANCE_SHARE, out)
    return out


def due_pairs(heap: list, k: int, n: int, skip: Optional[np.ndarray]) -> List[int]:
    """Pop the pairs due at sample k from the sweep's ``heap`` ((sample, pair), the earliest first): those to query
    there; a pair whose clearance bounds certify from k (``skip``: :func:`open_steps`) is pushed back at the first
    step they do not certify (to query its first sample), or dropped when they certify it to the end."""
    due = []
    while heap and heap[0][0] == k:
        c = heapq.heappop(heap)[1]
        j = int(skip[c, k]) if skip is not None and k < n - 1 else k
        if j == k:
            due.append(c)
        elif j < n - 1:
            heapq.heappush(heap, (j, c))
    return due


__all__ = ["ADVANCE_SHARE", "clearance_bounds", "due_pairs", "open_steps", "robot_spheres", "self_bounds"]
