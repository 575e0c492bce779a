"""Distance certificates of a robot's collision pairs for the planner's batched validity test (issue 25).

The planner's straight segments are checked state by state (:meth:`robodesign.solvers.planning._Memoized.first_invalid`),
and near a modular arm's joints the bounding spheres of neighbouring bodies always overlap: every state asked coal
about the same dozen self pairs (about 1,900 collision queries on each segment of the PTP_3 good arm).

A distance d of pair k at a configuration a proves the pair free at every configuration q with
``d − margin_k − |q − a| · W[:, k] > SLACK``: along the straight segment from a to q no point of one body moves by
more than ``|q − a| · W[:, k]`` relative to the other (the static lever-arm bounds of the judge's sweep,
:func:`robodesign.model.sweep.pair_arms`), so at q their distance is more than ``margin_k + SLACK``, and coal's
collision test (contact within the pair's security margin) finds them free there. Such pairs are not asked; the
others are asked their distance at q first (a new certificate), and only those closer than ``margin + SLACK`` are
left for the collision test. The verdicts are the collision tests' (tests/test_pair_certificates.py).

Certified: the pairs of a robot with a convex mesh (coal's ``Convex``: the IMPROV modules) without a triangle mesh
(``BVHModel…``, whose distance costs more than its collision test) among their two geometries
(:func:`certified_pairs`): a convex mesh's collision test costs some 2 µs, and with every such pair certified most
states ask coal nothing. A robot of primitives only (the built-in arms' cylinders and spheres, each test about a
microsecond) gets none: the genetic search on the whitman2020 tasks planned 1.0–1.8× slower with them.
"""
from __future__ import annotations

import sys
import weakref
from typing import Any, List, Optional

import numpy as np
import pinocchio as pin

from robodesign.model.collision_cull import pair_ends, pair_margins
from robodesign.model.sweep import pair_arms

#: clearance (m) beyond the pair's margin that a certificate must prove: 100× coal's distance error (GJK tolerance)
SLACK = 1e-4
#: certificates kept (the latest; an older one is overwritten)
ANCHORS = 32


def certified_pairs(gm, n_robot: int) -> np.ndarray:
    """Per collision pair of the geometry model ``gm`` (robot objects below ``n_robot``): whether it gets
    certificates (module docstring)."""
    kind = [type(o.geometry).__name__ for o in gm.geometryObjects]
    first, second = pair_ends(gm, n_robot)
    if not any(k.startswith("Convex") for k in kind):
        return np.zeros(len(first), dtype=bool)
    mesh = np.array([k.startswith("BVH") for k in kind], dtype=bool)
    return ~(mesh[first] | mesh[second])


#: per geometry model, :func:`certified_pairs` with what it was made of: (objects, pairs, robot objects). A model's
#: objects and pairs are only ever appended (model.robot_geometry: the obstacles added once, a new model when they
#: change), so the same counts are the same geometry
_CERTIFIED: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()
#: per culler (kept while the robot's geometry and margins are: model.collision_cull.culler_of), the set-up of its
#: robot's certificates: (the pairs certified, W, the margins), or None when no pair is certified
_SETUPS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def _certified_of(gm, n_robot: int) -> np.ndarray:
    """:func:`certified_pairs` of ``gm``, remembered per geometry model (a robot keeps its model while its culler
    is made again at each change of its geometry's state: PTP_3's good arm once per evaluation)."""
    key = (len(gm.geometryObjects), len(gm.collisionPairs), n_robot)
    hit = _CERTIFIED.get(gm)
    if hit is None or hit[0] != key:
        hit = _CERTIFIED[gm] = (key, certified_pairs(gm, n_robot))
    return hit[1]


class PairCertificates:
    """The latest :data:`ANCHORS` configurations at which pairs' distances were computed (``anchors``), and per
    configuration and pair the clearance found beyond the margin (``free``; NaN: not computed); ``certified``: the
    pairs that get certificates (:func:`certified_pairs`)."""

    def __init__(self, robot, certified: np.ndarray, W: np.ndarray, margins: np.ndarray):
        self.robot = robot
        self.certified = certified
        self.W = W                  # (dof, pairs): model.sweep.pair_arms
        self.margin = margins
        self.anchors = np.zeros((ANCHORS, robot.dof))
        self.free = np.full((ANCHORS, len(self.certified)), np.nan)
        self.count = 0         # certificates made
        self.kernel = _kernel()   # the compiled loops (solvers.certificate_kernel), or None: numpy

    def pending(self, R: np.ndarray, S: np.ndarray) -> np.ndarray:
        """(N, pairs) booleans: ``S`` (the pairs the culler's bounds do not clear at the rows of ``R``) without the
        pairs the kept certificates prove free. Only the rows with one of these pairs in ``S`` are bounded (each
        row's bounds are its own (m, dof) @ (dof, pairs) product, the same numbers with or without the other rows)."""
        P = S.copy()
        m = min(self.count, ANCHORS)
        cols = np.flatnonzero(S.any(axis=0) & self.certified)
        if m and len(cols) and self.kernel is not None:
            self.kernel.clear_pending(P, R, self.anchors, self.free, m, self.W, cols, SLACK)
        elif m and len(cols):
            rows = np.flatnonzero(S[:, cols].any(axis=1))
            bound = np.abs(R[rows, None, :] - self.anchors[None, :m]) @ self.W[:, cols]   # (rows, m, pairs)
            P[np.ix_(rows, cols)] &= ~(self.free[:m, cols] - bound > SLACK).any(axis=1)
        return P

    @classmethod
    def of(cls, robot, culler) -> "Optional[PairCertificates]":
        """New certificates for a planning call of ``robot`` (whose collision culler is ``culler``), or None when
        none of its pairs gets them. Their set-up is made once per culler."""
        if culler not in _SETUPS:
            certified = _certified_of(robot.geom_model, robot.n_collision_geometries)
            _SETUPS[culler] = (certified, np.ascontiguousarray(pair_arms(robot), dtype=float),
                               np.asarray(pair_margins(robot, robot.geom_data), dtype=float)) if certified.any() else None
        setup = _SETUPS[culler]
        return None if setup is None else cls(robot, *setup)

    def ask(self, P: np.ndarray, R: np.ndarray, j: int) -> List[int]:
        """The pairs of row ``j`` of :meth:`pending`'s ``P`` the collision test must be asked about at ``R[j]``:
        the certified pairs' distances are computed first (a new certificate, which also clears them in the later
        rows of ``P`` it proves free), and those farther than their margin + :data:`SLACK` are dropped."""
        own = (P[j] & self.certified).nonzero()[0]
        if not len(own):
            return P[j].nonzero()[0].tolist()
        q = R[j]
        free = self._distances(q, own)
        if self.kernel is not None:
            self.kernel.keep_and_clear(P, R, j, own, free, self.W, SLACK, self.anchors, self.free,
                                       self.count % ANCHORS)
            self.count += 1
            return P[j].nonzero()[0].tolist()
        self._keep(q, own, free)
        if j + 1 < len(R):
            P[j + 1:, own] &= ~(free - np.abs(R[j + 1:] - q) @ self.W[:, own] > SLACK)
        P[j, own[free > SLACK]] = False
        return P[j].nonzero()[0].tolist()

    def _distances(self, q: np.ndarray, own: np.ndarray) -> np.ndarray:
        """The clearances beyond the margin of pairs ``own`` at ``q`` (coal's distances)."""
        r = self.robot
        gm, gd = r.geom_model, r.geom_data
        pin.updateGeometryPlacements(r.model, r.data, gm, gd, q)
        distance = pin.computeDistance
        d = np.array([distance(gm, gd, k).min_distance for k in own.tolist()], dtype=float)
        return d - self.margin[own]

    def _keep(self, q: np.ndarray, own: np.ndarray, free: np.ndarray) -> None:
        """The clearances ``free`` of pairs ``own`` at ``q`` kept as a new certificate (the oldest overwritten)."""
        row = self.count % ANCHORS
        self.anchors[row] = q
        self.free[row] = np.nan
        self.free[row, own] = free
        self.count += 1


def _kernel() -> Any:
    """:mod:`robodesign.solvers.certificate_kernel` when its compiled loops run in this process, else None (also
    in a process that has not imported numba: importing it takes 0.3–1 s). Both paths give the same verdicts."""
    if "numba" not in sys.modules:
        return None
    from robodesign.solvers import certificate_kernel
    return certificate_kernel if certificate_kernel.ready() else None
