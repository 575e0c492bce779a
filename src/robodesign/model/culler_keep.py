"""A robot's collision culler taken up again when its geometry comes back to the state it was made for (issue 25).

A pooled robot (``model.cell``'s robot pools: the evaluator's and the judge's) is set to its base pose at every take,
and every change of a robot's geometry forgets its :class:`~robodesign.model.collision_cull.CollisionCuller`
(``RobotGeometry._geometry_changed``): an arm evaluated again at the same base pose made a new culler each time
(its bounds' arrays, the kernel's packed arguments, the scratch space's pairs: 1–2 ms). The culler forgotten is kept
aside (``_kept_culler``) and taken up again when the geometry is back in the state it was made for: the same geometry
model object and the same :func:`geometry_state`. It then starts again as a new one would
(:meth:`~robodesign.model.collision_cull.CollisionCuller.restart`): the same verdicts, query by query
(tests/test_culler_keep.py compares them with a new culler's and coal's).
"""
from __future__ import annotations

from typing import Any, Callable, Optional

import numpy as np


def geometry_state(robot, margin: np.ndarray, active: np.ndarray) -> tuple:
    """What a robot's culler is made of besides its build and its geometry model object: the base pose (which places
    the robot's objects fixed to the world), the obstacles' placements, the model's object and pair counts, and every
    pair's security margin and active flag (``margin``, ``active``: ``collision_cull.pair_settings``)."""
    gm = robot.geom_model
    objs = gm.geometryObjects
    obstacles = b"".join(objs[k].placement.homogeneous.tobytes() for k in range(robot.n_collision_geometries, len(objs)))
    return (robot.base_pose.tobytes(), obstacles, len(objs), len(gm.collisionPairs),
            np.asarray(margin, dtype=float).tobytes(), np.asarray(active, dtype=np.bool_).tobytes())


def taken_up(robot, settings: Callable[[Any], tuple]) -> Optional[Any]:
    """The culler ``robot`` had before its geometry last changed (``_kept_culler``), restarted, when the geometry is
    back in the state it was made for (its ``geom`` is the robot's model object and its ``state`` the robot's
    :func:`geometry_state`; ``settings``: the pairs' margins and active flags of a robot); else None."""
    kept = getattr(robot, "_kept_culler", None)
    if kept is None or kept.geom is not robot.geom_model or kept.state != geometry_state(robot, *settings(robot)):
        return None
    kept.restart()
    return kept


__all__ = ["geometry_state", "taken_up"]
