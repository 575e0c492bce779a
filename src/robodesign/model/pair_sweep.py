"""Certified robot–robot collision checking of two motions on a common time base.

Two robots move at once; between two samples each moves linearly in its own joint space (the same
interpolation the checker uses for one robot, docs/checker.md). For a pair of geometries (a of robot
A, b of robot B) the relative displacement over a step is bounded by ``W_a·|Δq_A| + W_b·|Δq_B|`` with
the lever arms of :func:`robodesign.model.sweep.lever_arms` (bodies of revolution about their own joint's
axis included), which is exactly the bound of a self-collision
pair whose two bodies hang from disjoint joint sets. So the stacked configuration ``[q_A, q_B]`` is
certified by the same conservative advancement as :class:`~robodesign.model.sweep.SweepChecker`; only the
distance query differs (two robots, two models).
"""
from __future__ import annotations

from typing import Callable, List, Sequence, Tuple

import coal
import numpy as np
import pinocchio as pin

from robodesign.model.robot import Robot
from robodesign.model.sweep import SweepChecker, lever_arms


class RobotPairSweep(SweepChecker):
    """Collisions between robot ``a`` and robot ``b`` along the stacked motion ``Q = [Q_a | Q_b]``.

    ``margin`` is the safety distance (a pair closer than it counts as a collision). Event names are
    ``"<name_a>:<geometry>"`` and ``"<name_b>:<geometry>"``; ``environment`` is True for every event.
    """

    def __init__(self, a: Robot, b: Robot, margin: float = 0.0, names=("A", "B"), tolerance: float = 1e-6,
                 max_substeps: int = 2000):
        self.robot = a
        self.other = b
        self.tolerance = tolerance
        self.max_substeps = max_substeps
        na, nb = a.n_collision_geometries, b.n_collision_geometries
        self.pairs: List[Tuple[int, int]] = [(i, j) for i in range(na) for j in range(nb)]  # geometry of a, of b
        Ra, Rb = lever_arms(a), lever_arms(b)
        self.W = np.vstack([Ra[:, [i for i, _ in self.pairs]], Rb[:, [j for _, j in self.pairs]]])
        self.margins = np.full(len(self.pairs), float(margin))
        self.is_env = np.ones(len(self.pairs), dtype=bool)
        ga, gb = a.geom_model.geometryObjects, b.geom_model.geometryObjects
        self.pair_names = [(f"{names[0]}:{ga[i].name}", f"{names[1]}:{gb[j].name}") for i, j in self.pairs]
        self._dof_a = a.dof
        self._data = (a.model.createData(), b.model.createData())
        self._gdata = (pin.GeometryData(a.geom_model), pin.GeometryData(b.geom_model))
        self._shapes = ([ga[i].geometry for i in range(na)], [gb[j].geometry for j in range(nb)])
        self._req = coal.DistanceRequest()
        self._res = coal.DistanceResult()
        self.queries = 0

    def distances(self, q: np.ndarray, cols: Sequence[int]) -> np.ndarray:
        qa, qb = q[: self._dof_a], q[self._dof_a:]
        tf = []
        for robot, data, gd, qq in ((self.robot, self._data[0], self._gdata[0], qa),
                                    (self.other, self._data[1], self._gdata[1], qb)):
            pin.updateGeometryPlacements(robot.model, data, robot.geom_model, gd, qq)
            tf.append(gd.oMg)
        out = np.empty(len(cols))
        sa, sb = self._shapes
        for n, c in enumerate(cols):
            i, j = self.pairs[c]
            Ma, Mb = tf[0][i], tf[1][j]
            self._res.clear()
            out[n] = coal.distance(sa[i], coal.Transform3s(Ma.rotation, Ma.translation),
                                   sb[j], coal.Transform3s(Mb.rotation, Mb.translation), self._req, self._res)
        self.queries += len(out)
        return out

    def _pair_query(self, c: int) -> Callable[[np.ndarray], float]:
        """:meth:`distances` of the one pair with index c, as a function of the configuration."""
        return lambda q: float(self.distances(q, [c])[0])
