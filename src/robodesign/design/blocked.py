"""Goals the tool cannot be at: a proof that no design of a module set fulfils a goal collision-free, because
every end effector the set allows, put at the goal's pose, lies inside a static obstacle deeper than the
goal's tolerance can move it.

**The argument.** The TCP of every design the search space allows is the eef connector of its last module
(an end effector), so the body holding that connector is rigid with the TCP. A pose the goal's tolerance
accepts differs from the nominal pose by at most ``p`` in position (:func:`position_radius`) and ``θ`` in
rotation angle (its ``Theta_R`` bound; rotations bounded only otherwise give no proof), so a point of that
body at distance ``r`` from the TCP moves by at most ``δ = p + θ·r`` (a rotation by θ moves it by
``2r·sin(θ/2) ≤ θr``). If some point of the body at the nominal pose lies inside an obstacle at depth more
than δ from its surface, it lies inside the obstacle at every accepted pose: the body collides whatever pose
the goal is met at. The test: the body's collision geometry (the geometry the judge uses, or inside it) at
the nominal pose against the obstacle shrunk by δ on every side (boxes, spheres and cylinders; meshes and
moving obstacles give no proof), with ``r`` the largest distance of the geometry's bounding box corners from
the TCP. It needs a ``collisionFree`` constraint; its safety margin only adds to the proof.
"""
from __future__ import annotations

import math
import weakref
from dataclasses import dataclass
from typing import Dict, List, Optional, Sequence, Tuple

import coal
import numpy as np

from robodesign.core.spatial import inv
from robodesign.design.regions import position_radius
from robodesign.formats.geometry import GeometrySpec, coal_shapes
from robodesign.formats.module_spec import Module
from robodesign.formats.task_spec import CollisionFree, Task
from robodesign.formats.tolerance import ToleratedPose

__all__ = ["BlockedGoalProof", "ToolBlock", "blocked_goal_proof", "rotation_radius", "tool_block"]


def rotation_radius(tp: ToleratedPose) -> float:
    """An upper bound [rad] of the rotation angle between the nominal orientation and any orientation ``tp``
    accepts: its tightest ``Theta_R`` bound (frame-independent), inf without one."""
    his = [max(abs(lo), abs(hi)) for name, (lo, hi), _ in tp.entries if name == "Theta_R"]
    return min(his) if his else math.inf


def _shrunk(g: GeometrySpec, d: float) -> Optional[coal.CollisionGeometry]:
    """``g`` shrunk by ``d`` on every side (its points at depth > d), None when nothing is left or the kind
    cannot be shrunk exactly (meshes)."""
    if g.kind == "box":
        s = [v - 2 * d for v in g.size]
        return coal.Box(*s) if min(s) > 0 else None
    if g.kind == "sphere":
        return coal.Sphere(g.size[0] - d) if g.size[0] > d else None
    if g.kind == "cylinder":
        r, z = g.size[0] - d, g.size[1] - 2 * d
        return coal.Cylinder(r, z) if r > 0 and z > 0 else None
    return None


def _tf(M: np.ndarray) -> coal.Transform3s:
    return coal.Transform3s(np.ascontiguousarray(M[:3, :3]), np.ascontiguousarray(M[:3, 3]))


@dataclass(frozen=True)
class _ToolPiece:
    shape: coal.CollisionGeometry
    pose: np.ndarray  # in the TCP frame
    radius: float     # largest distance of its bounding box's corners from the TCP


def _tool_pieces(module: Module) -> Optional[Tuple[_ToolPiece, ...]]:
    """The collision geometry of ``module``'s body that holds its eef connector, in the TCP frame; None when
    the module has not exactly one eef connector."""
    eefs = [c for c in module.connectors if c.type == "eef"]
    if len(eefs) != 1:
        return None
    c = eefs[0]
    body_in_tcp = inv(c.pose)
    out = []
    shape: coal.CollisionGeometry  # coal_shapes types its shapes as object
    for g in module.body(c.body_id).collision:
        for shape in coal_shapes(g):
            shape.computeLocalAABB()
            lo, hi = np.asarray(shape.aabb_local.min_), np.asarray(shape.aabb_local.max_)
            corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
            P = body_in_tcp @ g.pose
            pts = corners @ P[:3, :3].T + P[:3, 3]
            out.append(_ToolPiece(shape, P, float(np.linalg.norm(pts, axis=1).max())))
    return tuple(out)


@dataclass(frozen=True)
class ToolBlock:
    """End effector ``eef`` at the nominal pose of goal ``goal`` overlaps obstacle ``obstacle`` with a point
    deeper than ``slack`` [m], the most the goal's tolerance moves any point of it."""
    goal: str
    eef: str
    obstacle: str
    slack: float

    def to_json(self) -> dict:
        return {"goal": self.goal, "eef": self.eef, "obstacle": self.obstacle, "slack": self.slack}


def _static_obstacles(task: Task) -> List[Tuple[str, GeometrySpec]]:
    return [(ob.id, g) for ob in task.obstacles if not ob.moving for g in ob.collision]


def _pose_block(goal_id: str, tp: ToleratedPose, eef: str, pieces: Sequence[_ToolPiece],
                obstacles: Sequence[Tuple[str, GeometrySpec]]) -> Optional[ToolBlock]:
    p, th = position_radius(tp), rotation_radius(tp)
    if not (math.isfinite(p) and math.isfinite(th)):
        return None
    G = tp.nominal
    req, res = coal.CollisionRequest(), coal.CollisionResult()
    for piece in pieces:
        d = p + th * piece.radius
        T = _tf(G @ piece.pose)
        for oid, g in obstacles:
            core = _shrunk(g, d)
            if core is None:
                continue
            res.clear()
            if coal.collide(piece.shape, T, core, _tf(g.pose), req, res):
                return ToolBlock(goal_id, eef, oid, d)
    return None


def tool_block(task: Task, eef: Module) -> Optional[ToolBlock]:
    """The first goal pose of ``task`` at which end effector ``eef`` provably collides with a static obstacle
    (module docstring), or None. Memoized per task and end effector."""
    memo = _MEMO.setdefault(task, {})
    if eef.id in memo:
        return memo[eef.id]
    out = None
    if task.constraint(CollisionFree) is not None:
        pieces = _tool_pieces(eef)
        obstacles = _static_obstacles(task)
        if pieces and obstacles:
            out = next((b for g in task.goals for tp in g.target_poses
                        for b in [_pose_block(g.id, tp, eef.id, pieces, obstacles)] if b is not None), None)
    memo[eef.id] = out
    return out


_MEMO: "weakref.WeakKeyDictionary[Task, Dict[str, Optional[ToolBlock]]]" = weakref.WeakKeyDictionary()


@dataclass(frozen=True)
class BlockedGoalProof:
    """Why no design of the module set fulfils the task: every end effector the search space allows lies, at
    some goal's pose (``blocks``, one per end effector), inside a static obstacle deeper than that goal's
    tolerance can move it; every design ends with one of them."""
    blocks: Tuple[ToolBlock, ...]
    kind: str = "blocked"

    @property
    def goals(self) -> Tuple[str, ...]:
        return tuple(dict.fromkeys(b.goal for b in self.blocks))

    @property
    def message(self) -> str:
        where = "; ".join(f"{b.eef} at goal {b.goal} inside {b.obstacle} (tolerance moves it ≤ {b.slack * 1e3:.1f} mm)"
                          for b in self.blocks)
        return ("provably out of reach: every end effector of the module set, held at a goal's pose, lies inside an "
                f"obstacle deeper than the goal's tolerance can move it: {where}")

    def to_json(self) -> dict:
        return {"kind": self.kind, "goals": list(self.goals), "blocks": [b.to_json() for b in self.blocks],
                "message": self.message}


def blocked_goal_proof(task: Task, end_effectors: Sequence[Module]) -> Optional[BlockedGoalProof]:
    """A proof that every module of ``end_effectors`` (the end effectors the search space allows) provably
    collides at some goal pose of ``task`` (:func:`tool_block`), or None (also when there are none)."""
    blocks = []
    for eef in end_effectors:
        b = tool_block(task, eef)
        if b is None:
            return None
        blocks.append(b)
    return BlockedGoalProof(tuple(blocks)) if blocks else None
