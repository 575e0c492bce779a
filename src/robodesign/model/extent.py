"""How far one module can span in a serial chain: bounds of the distance between two of its connectors over
every joint configuration (exact for a rigid path or one revolute joint; docs/diagnosis.md). The design
layer sums them into a module set's reach bound (:meth:`robodesign.design.search_space.SearchSpace.max_reach`)."""
from __future__ import annotations

import math
from typing import Dict, Optional, Tuple

import numpy as np

from robodesign.formats.module_spec import Joint, Module

__all__ = ["connector_distance_bound", "module_extent"]


def _body_frames(m: Module) -> Dict[str, np.ndarray]:
    """Every body's frame in the first body's frame at q = 0 (joints form a tree over the bodies)."""
    frames = {m.bodies[0].id: np.eye(4)}
    pending = list(m.joints)
    while pending:
        progressed = False
        for j in list(pending):
            if j.parent in frames:
                frames[j.child] = frames[j.parent] @ j.pose_parent @ j.pose_child
            elif j.child in frames:
                frames[j.parent] = frames[j.child] @ np.linalg.inv(j.pose_parent @ j.pose_child)
            else:
                continue
            pending.remove(j)
            progressed = True
        if not progressed:  # bodies not joined to the first one: they cannot be on a path
            break
    return frames


def _joint_path(m: Module, a: str, b: str) -> Optional[list]:
    """The joints on the path from body ``a`` to body ``b`` (breadth-first over the joint tree)."""
    prev: Dict[str, Optional[Tuple[str, Joint]]] = {a: None}  # body → (previous body, joint); a: the start
    queue = [a]
    while queue:
        u = queue.pop(0)
        if u == b:
            break
        for j in m.joints:
            for x, y in ((j.parent, j.child), (j.child, j.parent)):
                if x == u and y not in prev:
                    prev[y] = (u, j)
                    queue.append(y)
    if b not in prev:
        return None
    path, u = [], b
    while (step := prev[u]) is not None:
        u, j = step
        path.append(j)
    return path[::-1]


def _stroke(j) -> float:
    lo, hi = j.limits.lower, j.limits.upper
    return max(abs(lo), abs(hi)) if math.isfinite(lo) and math.isfinite(hi) else math.inf


def connector_distance_bound(m: Module, con_a: str, con_b: str) -> float:
    """The largest distance between connectors ``con_a`` and ``con_b`` of module ``m`` over every joint
    configuration (exact for zero or one revolute joint between them, an upper bound otherwise)."""
    frames = _body_frames(m)
    ca, cb = m.connector(con_a), m.connector(con_b)
    if ca.body_id not in frames or cb.body_id not in frames:
        return math.inf
    pa = (frames[ca.body_id] @ ca.pose)[:3, 3]
    pb = (frames[cb.body_id] @ cb.pose)[:3, 3]
    path = _joint_path(m, ca.body_id, cb.body_id)
    if path is None:
        return math.inf
    if not path:
        return float(np.linalg.norm(pb - pa))
    moving = [j for j in path if j.type != "fixed"]
    if len(moving) == 1 and moving[0].type == "revolute":
        j = moving[0]
        # the joint frame at q = 0, seen from the side of its parent body
        J = frames[j.parent] @ j.pose_parent
        Ji = np.linalg.inv(J)
        qa, qb = Ji[:3, :3] @ pa + Ji[:3, 3], Ji[:3, :3] @ pb + Ji[:3, 3]
        return float(math.hypot(qa[2] - qb[2], math.hypot(qa[0], qa[1]) + math.hypot(qb[0], qb[1])))
    # several joints: joint origins (on their axes) keep their distances along the path
    pts = [pa] + [(frames[j.parent] @ j.pose_parent)[:3, 3] for j in path] + [pb]
    d = sum(float(np.linalg.norm(pts[i + 1] - pts[i])) for i in range(len(pts) - 1))
    return d + sum(_stroke(j) for j in path if j.type == "prismatic")


def module_extent(m: Module) -> float:
    """An upper bound of the distance a module spans in a serial chain: base connector → any other connector
    (a base), any connector → the TCP (an end effector), else the largest distance between any two of its
    connectors; over every joint configuration."""
    cons = m.connectors
    if m.is_base:
        pairs = [(a.id, b.id) for a in cons if a.type == "base" for b in cons if b.type != "base"]
    elif m.is_end_effector:
        pairs = [(a.id, b.id) for a in cons if a.type != "eef" for b in cons if b.type == "eef"]
    else:
        pairs = [(a.id, b.id) for i, a in enumerate(cons) for b in cons[i + 1:]]
    return max((connector_distance_bound(m, a, b) for a, b in pairs), default=0.0)
