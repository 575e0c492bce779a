"""A SweepChecker's collision scratch space kept for the next checker of the same robot (issue 25).

:class:`~robodesign.model.sweep.SweepChecker` queries exact distances in a ``pinocchio.GeometryData`` of the
robot's geometry model; making one makes coal's functors for every pair (~0.2-0.5 ms on a 7-module arm in its
cell) while a check asks a few dozen pairs. Its answers depend on the queries made in it before: coal starts each
pair's GJK from where the pair's last query ended (the distance request's cached guesses, which pinocchio
enables). :class:`KeptScratch` therefore records the pairs its checker asked and sets their requests back to a new
scratch space's before it lends the scratch space again; the pairs never asked still hold a new one's. Every
answer is then that of a new ``pinocchio.GeometryData`` (tests/test_sweep_scratch.py). A kept scratch space serves
one checker at a time (and the checker's subsets, which share it): its owner lends it, as the judge lends the
robot (:mod:`robodesign.judge.robots`).
"""
from __future__ import annotations

from typing import Any, Set

import pinocchio as pin

from robodesign.model.pair_scratch import GUESS, SUPPORT_GUESS


class KeptScratch:
    """A ``pinocchio.GeometryData`` of the geometry model ``gm`` and the pairs asked in it since it was last lent."""

    def __init__(self, gm: "pin.GeometryModel"):
        self.gm = gm
        self.size = (gm.ngeoms, len(gm.collisionPairs))   # what the scratch space was made for
        self.data = pin.GeometryData(gm)
        self.asked: Set[Any] = set()   # collision pair indices (SweepChecker.pairs) whose requests were used

    def fits(self, gm: "pin.GeometryModel") -> bool:
        """Whether this is a scratch space of ``gm`` as it is now (the same object, objects and pairs)."""
        return gm is self.gm and self.size == (gm.ngeoms, len(gm.collisionPairs))

    def lend(self) -> "pin.GeometryData":
        """The scratch space as a new one: the distance requests of the pairs asked before set back first."""
        requests = self.data.distanceRequests
        for k in self.asked:
            r = requests[k]
            r.cached_gjk_guess, r.cached_support_func_guess = GUESS, SUPPORT_GUESS
        self.asked.clear()
        return self.data
