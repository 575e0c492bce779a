"""Lower bounds of the clearances of the certified sweep's pairs (:mod:`robodesign.model.sweep`) at the samples, so
that coal is asked only about the steps these bounds do not certify (issue 25: on the 350-sample PTP_3 check a
convex piece of the arm against the CNC mesh cost coal ~50 µs a query, the self pairs 216 queries).

At every sample, robot geometry g is inside a sphere (:mod:`robodesign.model.collision_cull`'s: its local box's
centre, the half diagonal plus coal's swept-sphere radius). A **robot–obstacle** pair's distance is bounded below
by the sphere centre's distance to the obstacle's box or, where larger, by its
:class:`~robodesign.model.collision_cull.DistanceField` (the exact distance of the centre's grid cell less the
centre's distance to the cell's centre: distance is 1-Lipschitz), less the radius (compiled:
:func:`robodesign.model.sweep_kernel.obstacle_bounds`; a field's cell is computed once per obstacle shape and
pose for the process, as the culler does, and the sweep computes only the unknown cells it needs: those at the samples
next to a step that the bounds without them do not certify, since a cell can only raise the bounds at its samples;
on PTP_3's new arms 105 of the 1,718 cells met). A **self** pair's by the distance between its two
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


class _FieldBounds:
    """The bounds of :func:`clearance_bounds` (``out``) of robot geometries ``geo`` against one static obstacle at the
    samples whose geometry poses are TG, taken with the field's cells known so far, and the cells met unknown with
    where each was met (``met``: how many; so that only those some use needs are computed)."""

    def __init__(self, kernel, robot, TG: np.ndarray, geo: np.ndarray, obstacle: int, spheres):
        o = robot.geom_model.geometryObjects[obstacle]
        self.field = f = distance_field(o.geometry, o.placement.homogeneous)
        self.out = np.empty((len(TG), len(geo)))
        self._unknown, self._where = np.empty((2, len(TG) * len(geo)), np.int64)
        self._kernel = kernel
        self._args = (TG, geo, spheres[0][geo], spheres[1][geo] + SLACK, f.R_inv, f.t, f.box_lo, f.box_hi, f.grid_lo,
                      f.grid_dim, f.cell, f.values, self.out, self._unknown, self._where)
        self.met = kernel.obstacle_bounds(*self._args)

    def fill(self, need: Optional[np.ndarray] = None) -> bool:
        """Whether cells met unknown where ``need`` (booleans shaped as ``out``; None: everywhere) were computed; then
        ``out`` is taken again with them (elsewhere a cell left unknown gives the bound without it, a lower one)."""
        cells = self._unknown[:self.met]
        if need is not None:
            cells = cells[need.ravel()[self._where[:self.met]]]
        if not len(cells):
            return False
        self.field.fill(cells)
        self.met = self._kernel.obstacle_bounds(*self._args)
        return True


def clearance_bounds(robot, TG: np.ndarray, geo: np.ndarray, obstacle: int, spheres) -> Optional[np.ndarray]:
    """(n, len(geo)) lower bounds of the distance from robot geometries ``geo`` to the robot's geometry object
    ``obstacle`` (a static obstacle) at the samples whose geometry poses are TG, less SLACK; None without the
    compiled kernel. The obstacle's distance-field cells met unknown are computed first."""
    kernel = _kernel(count=False)
    if kernel is None:
        return None
    bounds = _FieldBounds(kernel, robot, TG, geo, obstacle, spheres)
    bounds.fill()
    return bounds.out


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
    n = len(TG)
    obstacles = np.array(checker._obst, dtype=np.int64)
    mov, ref = (np.array(x, dtype=np.int64) for x in (checker._mov, checker._ref))
    fields = [(c, _FieldBounds(kernel, checker.robot, TG, mov[c], ob, spheres))
              for ob in np.unique(obstacles[obstacles >= 0]).tolist() for c in [np.flatnonzero(obstacles == ob)]]
    groups = [(c, bounds.out) for c, bounds in fields]
    c = np.flatnonzero(obstacles < 0)
    if len(c):
        groups.append((c, self_bounds(TG, mov[c], ref[c], spheres)))
    args = (np.ascontiguousarray(sched), dQ.max(axis=1) * (1 + 1e-9), checker.W.sum(axis=0), ext, BOUND_SLACK,
            ADVANCE_SHARE)   # (the static bound dQ @ W ≤ max_j |Δq_j| · Σ_j W[j])
    out = _uncertified(kernel, groups, checker.margins, args)
    # a cell's value can only raise the bounds at its samples, so only the samples next to a step not yet certified
    # need theirs: every step certifies as with every cell known
    if any(bounds.met for _, bounds in fields):
        need = _next_to(out == np.arange(n - 1), n)
        if any([bounds.fill(need[:, c]) for c, bounds in fields]):
            out = _uncertified(kernel, groups, checker.margins, args)
    return out


def _next_to(steps: np.ndarray, n: int) -> np.ndarray:
    """(n, P) booleans: the samples at either end of the steps ``steps`` (P, n − 1 booleans) of each pair."""
    need = np.zeros((n, len(steps)), dtype=bool)
    need[:-1] |= steps.T
    need[1:] |= steps.T
    return need


def _uncertified(kernel, groups: List[Tuple[np.ndarray, np.ndarray]], margins: np.ndarray, args: tuple) -> np.ndarray:
    """:func:`open_steps`'s (P, n − 1) answer from the clearance bounds ``groups`` ((pairs, (n, len(pairs)) bounds))
    less the pairs' ``margins``; ``args``: the schedule's step bounds, the fastest joint's and the rest of the
    kernel's arguments. One group (the judge's: its self pairs, or its pairs with one obstacle) is taken in place, as
    before: it is asked again only after its field's kernel wrote it anew."""
    n, P = len(groups[0][1]), len(margins)
    if len(groups) == 1:
        F = groups[0][1]
    else:
        F = np.empty((n, P))
        for c, lb in groups:
            F[:, c] = lb
    F -= margins
    out = np.empty((P, n - 1), np.int64)
    kernel.open_steps(F, *args, out)
    return out


class DueQueue:
    """The sweep's queue of pair queries (:meth:`SweepChecker.check <robodesign.model.sweep.SweepChecker.check>`):
    per pair the sample where it is due next (``nxt``, n: never again). The batch at sample k is the pairs due at
    the earliest such sample, in ascending order, less those whose clearance bounds certify from k (``skip``:
    :func:`open_steps`), which move to the first step they do not certify, or drop when they certify it to the end.
    After the batch's queries :meth:`settle` certifies its pairs (:meth:`PosedArms.certify
    <robodesign.model.sweep_bounds.PosedArms.certify>`) and reschedules those it can; the rest go back to the
    sweep. Compiled (:func:`~robodesign.model.sweep_kernel.settle`) when the kernels run, else in Python: the same
    batches."""

    def __init__(self, checker, n: int, skip: Optional[np.ndarray], rows: np.ndarray, TG: Optional[np.ndarray],
                 sched: np.ndarray, ext: float, self_too: bool):
        P = len(checker.pairs)
        self.n, self.nxt = n, np.zeros(P, np.int64)
        self.skip = skip if skip is not None else np.zeros((0, 0), np.int64)
        self.due, self._left = np.empty(P, np.int64), np.empty((2, P), np.int64)
        self._next: Optional[Tuple[int, int]] = None  # the next batch when settle found it
        posed = getattr(checker, "_posed", None)  # (RobotPairSweep has none)
        cen, rad = (posed.box_centre, posed.box_radius) if posed is not None else (np.zeros((0, 3)), np.zeros(0))
        mov, ref = (np.array(getattr(checker, a, ()), dtype=np.int64) for a in ("_mov", "_ref"))
        self._posed = posed
        self._args = (checker.margins, checker.is_env, rows, TG if TG is not None else np.zeros((0, 1, 3, 4)), mov,
                      ref, cen, rad, sched, ext, BOUND_SLACK, self_too)
        self._kernel = _kernel(count=False)

    def push(self, c: int, k: int) -> None:
        """Pair c is due at sample k."""
        self.nxt[c] = k

    def batch(self) -> Tuple[int, List[int]]:
        """(k, the pairs to query at sample k), (−1, []) when none is left."""
        if self._next is None:
            self._next = (self._kernel.next_due(self.nxt, self.n, self.skip, self.due) if self._kernel is not None
                          else self._next_due())
        k, cnt = self._next
        self._next = None
        return k, self.due[:cnt].tolist()

    def settle(self, k: int, due: List[int], d: np.ndarray) -> List[Tuple[int, float, int]]:
        """After the queries of the batch ``due`` at sample k (distances d): (pair, distance, certificate) of the
        pairs left to the sweep (certificate: certify's value, −2 without posed bounds; the sweep reschedules
        them), the others rescheduled."""
        kernel = self._kernel
        if kernel is None:
            return self._settle(k, due, d)
        nl, k2, cnt2 = kernel.settle(self.nxt, self.n, self.skip, self.due, len(due), d, k, self._left,
                                     self._posed is not None, *self._args)
        if not nl:
            self._next = (k2, cnt2)
            return []
        i, v = self._left[0, :nl].tolist(), self._left[1, :nl].tolist()
        return [(due[a], float(d[a]), b) for a, b in zip(i, v)]

    def _next_due(self) -> Tuple[int, int]:
        """:meth:`batch` in Python (as the kernel): (k, count) with the pairs in ``due``."""
        n, nxt, skip = self.n, self.nxt, self.skip
        while True:
            k = int(nxt.min())
            if k >= n:
                return -1, 0
            cnt = 0
            for c in np.flatnonzero(nxt == k).tolist():
                j = int(skip[c, k]) if len(skip) and k < n - 1 else k
                if j == k:
                    self.due[cnt] = c
                    cnt += 1
                else:
                    nxt[c] = j if j < n - 1 else n
            if cnt:
                return k, cnt

    def _settle(self, k: int, due: List[int], d: np.ndarray) -> List[Tuple[int, float, int]]:
        """:meth:`settle` in Python (as the kernel)."""
        n, skip, (margins, is_env, rows, TG, mov, ref, _, _, sched, ext, _, self_too) = self.n, self.skip, self._args
        certified = (self._posed.certify(due, d, k, margins, is_env, rows, TG, mov, ref, sched, ext,
                                         self_too) if self._posed is not None else [-2] * len(due))
        left = []
        for c, dist, v in zip(due, d.tolist(), certified):
            self.nxt[c] = n
            if v >= n - 1:
                continue
            if v > k and not (is_env[c] and (not len(skip) or skip[c, v] == v)):
                self.nxt[c] = v
                continue
            left.append((c, dist, v))
        return left


__all__ = ["ADVANCE_SHARE", "DueQueue", "clearance_bounds", "open_steps", "robot_spheres", "self_bounds"]
