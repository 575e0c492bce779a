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

Certified: the self pairs and the pairs with a primitive obstacle (:data:`PRIMITIVES`); a mesh obstacle's distance
costs more than its collision test, and its pairs are asked as before.
"""
from __future__ import annotations

from typing import List

import numpy as np
import pinocchio as pin

from robodesign.model.sweep import pair_arms

#: clearance (m) beyond the pair's margin that a certificate must prove: 100× coal's distance error (GJK tolerance)
SLACK = 1e-4
#: certificates kept (the latest; an older one is overwritten)
ANCHORS = 32
#: the obstacle shapes whose pairs are certified (coal's class names)
PRIMITIVES = ("Box", "Sphere", "Cylinder", "Capsule", "Cone", "Ellipsoid")


class PairCertificates:
    """The latest :data:`ANCHORS` configurations at which pairs' distances were computed (``anchors``), and per
    configuration and pair the clearance found beyond the margin (``free``; NaN: not computed); ``certified``: the
    pairs that get certificates."""

    def __init__(self, robot, margins: np.ndarray):
        self.robot = robot
        gm = robot.geom_model
        objs = gm.geometryObjects
        n_robot = robot.n_collision_geometries
        self.certified = np.array([cp.second < n_robot or type(objs[cp.second].geometry).__name__ in PRIMITIVES
                                   for cp in gm.collisionPairs], dtype=bool)
        self.W = np.ascontiguousarray(pair_arms(robot), dtype=float)   # (dof, pairs)
        self.margin = np.asarray(margins, dtype=float)
        self.anchors = np.zeros((ANCHORS, robot.dof))
        self.free = np.full((ANCHORS, len(self.certified)), np.nan)
        self.count = 0         # certificates made
        self.distances = 0     # distance queries asked (statistics)

    def pending(self, R: np.ndarray, S: np.ndarray) -> np.ndarray:
        """(N, pairs) booleans: ``S`` (the pairs the culler's bounds do not clear at the rows of ``R``) without the
        pairs the kept certificates prove free."""
        P = S.copy()
        m = min(self.count, ANCHORS)
        cols = np.flatnonzero(S.any(axis=0) & self.certified)
        if m and len(cols):
            bound = np.abs(R[:, None, :] - self.anchors[None, :m]) @ self.W[:, cols]   # (N, m, pairs)
            P[:, cols] &= ~(self.free[:m, cols] - bound > SLACK).any(axis=1)
        return P

    def ask(self, P: np.ndarray, R: np.ndarray, j: int) -> List[int]:
        """The pairs of row ``j`` of :meth:`pending`'s ``P`` the collision test must be asked about at ``R[j]``:
        the certified pairs' distances are computed first (a new certificate, which also clears them in the later
        rows of ``P`` it proves free), and those farther than their margin + :data:`SLACK` are dropped."""
        ks = P[j].nonzero()[0]
        own = ks[self.certified[ks]]
        if not len(own):
            return ks.tolist()
        q = R[j]
        free = self._certify(q, own)
        if j + 1 < len(R):
            P[j + 1:, own] &= ~(free - np.abs(R[j + 1:] - q) @ self.W[:, own] > SLACK)
        P[j, own[free > SLACK]] = False
        return P[j].nonzero()[0].tolist()

    def _certify(self, q: np.ndarray, own: np.ndarray) -> np.ndarray:
        """The clearances beyond the margin of pairs ``own`` at ``q`` (coal's distances), kept as a new
        certificate."""
        r = self.robot
        gm, gd = r.geom_model, r.geom_data
        pin.updateGeometryPlacements(r.model, r.data, gm, gd, q)
        distance = pin.computeDistance
        d = np.array([distance(gm, gd, k).min_distance for k in own.tolist()], dtype=float)
        free = d - self.margin[own]
        row = self.count % ANCHORS
        self.anchors[row] = q
        self.free[row] = np.nan
        self.free[row, own] = free
        self.count += 1
        self.distances += len(own)
        return free
