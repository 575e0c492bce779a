"""The sweep's set-up of a robot at another base pose, from that of a robot built alike (issue 25).

:func:`~robodesign.model.sweep._setup` (the pairs, their bounds W and owners, the posed arms, ~1-1.5 ms on a
7-module arm in its cell) is kept per robot built alike, base pose included; a search meets an assembly at many
base poses. A base pose moves only what is fixed to the world: the root joints' placements (joints on the base)
and the robot geometries on the base (joint 0). Of the set-up these enter only

1. the posed arms' placements of the geometries on the base (``PosedArms.t_g``, ``R_g`` and the kernel's
   ``_k_tree``), read again here from the robot's geometry;
2. which geometries on the base are bodies of revolution about a root joint's axis (``coaxial_child_joints``:
   the self pairs' W and owners), tested in world coordinates; :func:`rebased` takes the kept set-up only when
   this comes out the same (:func:`root_coaxial`), else the set-up is made anew.

The lever arms never read a root joint's placement (the walk up stops at it) nor those of the geometries on the
base (they hang from no joint); the rest is structure, local shapes and the obstacles' names. So a set-up taken
here is the one :func:`~robodesign.model.sweep._setup` makes, array for array (tests/test_sweep_rebase.py).
"""
from __future__ import annotations

import copy
import threading
from typing import Dict, FrozenSet, Optional, Set, Tuple

import numpy as np

from robodesign.model.revolution import _revolute_axis, _symmetric

_KEPT: Dict[tuple, tuple] = {}   # the set-up key without the base pose → (module set, set-up, root_coaxial)
_LOCK = threading.Lock()


def _base_free(key: tuple) -> tuple:
    """``sweep._setup_key`` without the base pose (its third item)."""
    return key[:2] + key[3:]


def root_coaxial(robot) -> FrozenSet[Tuple[int, int]]:
    """(geometry, joint) of every geometry on the base that is a body of revolution about the axis of a root joint
    (revolute, on the base), as ``sweep._Tree.coaxial_child_joints`` tests it."""
    model, gm = robot.model, robot.geom_model
    objs = [gm.geometryObjects[g] for g in range(robot.n_collision_geometries)]
    on_base = [(g, o) for g, o in enumerate(objs) if int(o.parentJoint) == 0]
    out: Set[Tuple[int, int]] = set()
    for j in range(1, model.njoints):
        axis = _revolute_axis(model.joints[j]) if int(model.parents[j]) == 0 else None
        if axis is None:
            continue
        M = model.jointPlacements[j]
        point, direction = np.asarray(M.translation, dtype=float), np.asarray(M.rotation, dtype=float) @ axis
        out.update((g, j) for g, o in on_base if _symmetric(type(o.geometry).__name__, o.placement, point, direction))
    return frozenset(out)


def keep(robot, key: Optional[tuple], setup: dict) -> dict:
    """``setup`` (``sweep._setup`` of ``robot``, whose ``sweep._setup_key`` is ``key``; None: not kept), kept for
    other base poses."""
    if key is not None:
        entry = (robot.module_set, setup, root_coaxial(robot))
        with _LOCK:
            if len(_KEPT) >= 64:
                _KEPT.clear()
            _KEPT[_base_free(key)] = entry
    return setup


def rebased(robot, key: tuple) -> Optional[dict]:
    """The set-up of ``robot`` (``sweep._setup_key`` ``key``) from the one kept of a robot built alike at another
    base pose, or None (none kept, or its geometries on the base are coaxial with a root joint otherwise)."""
    kept = _KEPT.get(_base_free(key))
    if kept is None or kept[0] is not robot.module_set or kept[2] != root_coaxial(robot):
        return None
    setup = dict(kept[1])
    if setup["_posed"] is not None:
        setup["_posed"] = _posed_at(setup["_posed"], robot)
    return setup


def _posed_at(posed, robot):
    """The template ``posed`` (PosedArms bound to no robot) with the placements of the geometries on the base read
    from ``robot``'s geometry, as ``PosedArms.__init__`` reads every placement."""
    out = copy.copy(posed)
    t_g, R_g = posed.t_g.copy(), posed.R_g.copy()
    gm = robot.geom_model
    for g in np.flatnonzero(posed.geom_joint == 0).tolist():
        P = gm.geometryObjects[g].placement
        t_g[g], R_g[g] = np.asarray(P.translation, dtype=float), np.asarray(P.rotation, dtype=float)
    out.t_g, out.R_g = t_g, R_g
    out._k_tree = posed._k_tree[:2] + (np.ascontiguousarray(t_g),) + posed._k_tree[3:]
    return out
