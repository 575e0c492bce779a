"""The narrow phase's scratch space of a :class:`~robodesign.model.collision_cull.CollisionCuller`: a geometry model
of just the collision pairs the culler has asked coal about (and their objects), and its ``pin.GeometryData``.

``pin.GeometryData`` of a robot's whole geometry makes three coal functors per collision pair (2–6 ms for a robot
with 500 pairs), while the culler's bounds let few of those pairs reach coal (a dozen per robot in a genetic
search). Here a pair enters the model when it is first asked; the scratch space is then made again, with every
request asked before carried over as it is (its GJK guesses too) and the new ones made as the robot's own scratch
space makes them (pinocchio's request with contacts on and the pair's security margin). A query is the one
``pin.computeCollision`` makes on the robot's geometry: the same objects (copied from it: shape, parent joint,
placement), in the same order within the pair, the same placements (``pin.updateGeometryPlacements``) and a request
with the same fields.

:func:`fresh_guesses` sets a scratch space's GJK guesses back to a new one's (the robot's own, the culler's when
taken up again, the sweep's).
"""
from __future__ import annotations

import sys
from typing import Any, Dict, List

import numpy as np
import pinocchio as pin


class PairScratch:
    """The pairs asked so far of the robot geometry ``geom`` (a ``pin.GeometryModel``), as ``model`` holds them
    (``local``: robot pair index → index in ``model``), and ``data``, the scratch space of ``model``; ``margins``: the
    security margin of every robot pair's request."""

    def __init__(self, geom: "pin.GeometryModel", margins: np.ndarray):
        self.geom = geom
        self.margins = margins
        self.model = pin.GeometryModel()
        self.data = pin.GeometryData(self.model)
        self.local: Dict[int, int] = {}
        self._objects: Dict[int, int] = {}   # robot geometry object → its index in model

    def add(self, ks: List[int]) -> None:
        """Add the robot pairs ``ks`` not asked before (``local`` then holds every one)."""
        new = [k for k in dict.fromkeys(ks) if k not in self.local]
        if new:
            self._add(new)

    def _object(self, g: int) -> int:
        """The index in ``model`` of robot geometry object ``g`` (added on first use)."""
        i = self._objects.get(g)
        if i is None:
            i = self._objects[g] = self.model.addGeometryObject(self.geom.geometryObjects[g])
        return i

    def _add(self, new: List[int]) -> None:
        """Add the robot pairs ``new`` to ``model`` and make its scratch space again: the requests of the pairs
        before carried over (C++ copies), each new one pinocchio's own with contacts on and the pair's margin."""
        pairs = self.geom.collisionPairs
        for k in new:
            cp = pairs[k]
            self.model.addCollisionPair(pin.CollisionPair(self._object(cp.first), self._object(cp.second)))
            self.local[k] = len(self.local)
        old = self.data.collisionRequests
        data = pin.GeometryData(self.model)
        out = type(old)()
        out.extend(old)
        made: Dict[float, Any] = {}   # security margin → a request made for it, alone in a vector (then copied)
        for k in new:
            m = float(self.margins[k])
            one = made.get(m)
            if one is None:
                one = made[m] = type(old)()
                one.append(data.collisionRequests[0])
                one[0].enable_contact = True
                one[0].security_margin = m
            out.append(one[0])
        data.collisionRequests = out
        self.data = data


__all__ = ["PairScratch"]


GUESS, SUPPORT_GUESS = np.array([1.0, 0.0, 0.0]), np.zeros(2, dtype=np.int32)  # a new coal request's
NO_BOUND = sys.float_info.max  # a new collision request's distance_upper_bound


def fresh_guesses(gd: "pin.GeometryData") -> None:
    """coal starts each pair's GJK from where its last query ended (the requests' cached guesses, which pinocchio
    enables): set them back to a new scratch space's, so that answers do not depend on earlier queries."""
    for r in gd.collisionRequests:   # (pinocchio sets distance_upper_bound at every query)
        r.cached_gjk_guess, r.cached_support_func_guess, r.distance_upper_bound = GUESS, SUPPORT_GUESS, NO_BOUND
    for r in gd.distanceRequests:
        r.cached_gjk_guess, r.cached_support_func_guess = GUESS, SUPPORT_GUESS
