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
import pinocchio as pin

from robodesign.core.spatial import inv
from robodesign.design.regions import position_radius
from robodesign.formats.assembly import Assembly
from robodesign.formats.geometry import GeometrySpec, coal_shapes
from robodesign.formats.module_spec import Module, ModuleSet
from robodesign.formats.task_spec import CollisionFree, Task
from robodesign.formats.tolerance import ToleratedPose
from robodesign.model.robot import Obstacle, Robot

__all__ = ["BlockedGoalProof", "ToolBlock", "blocked_goal_proof", "fixed_part_proof", "rotation_radius", "tool_block"]


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
    pose: np.ndarray  # in the frame the tolerance moves (the TCP, the base frame)
    radius: float     # largest distance of its bounding box's corners from that frame's origin


def _corner_radius(shape: coal.CollisionGeometry, M: np.ndarray, origin=np.zeros(3)) -> float:
    """The largest distance from ``origin`` of a corner of ``shape``'s bounding box placed at ``M`` (a bound of
    how far any of its points is)."""
    shape.computeLocalAABB()
    lo, hi = np.asarray(shape.aabb_local.min_), np.asarray(shape.aabb_local.max_)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    return float(np.linalg.norm(corners @ M[:3, :3].T + M[:3, 3] - origin, axis=1).max())


def _tool_pieces(module: Module) -> Optional[Tuple[_ToolPiece, ...]]:
    """The collision geometry of ``module``'s body that holds its eef connector, in the TCP frame (the
    connector's own frame, model/robot.py); None when the module has not exactly one eef connector."""
    cons = [c for c in module.connectors if c.type == "eef"]
    if len(cons) != 1:
        return None
    c = cons[0]
    body_in_tcp = inv(c.pose)
    out = []
    shape: coal.CollisionGeometry  # coal_shapes types its shapes as object
    for g in module.body(c.body_id).collision:
        for shape in coal_shapes(g):
            P = body_in_tcp @ g.pose
            out.append(_ToolPiece(shape, P, _corner_radius(shape, P)))
    return tuple(out)


@dataclass(frozen=True)
class ToolBlock:
    """End effector ``eef`` at the nominal pose of goal ``goal`` overlaps obstacle ``obstacle`` with a point
    deeper than ``slack`` [m], the most the goal's tolerance moves any point of it. For a base module
    (``goal`` None), ``eef`` names the base and the pose is the basePlacement's nominal one."""
    goal: Optional[str]
    eef: str
    obstacle: str
    slack: float

    @property
    def where(self) -> str:
        if self.goal is None:
            return (f"modules {self.eef} at the base placement inside {self.obstacle} (tolerance moves it ≤ "
                    f"{self.slack * 1e3:.1f} mm)")
        return f"{self.eef} at goal {self.goal} inside {self.obstacle} (tolerance moves it ≤ {self.slack * 1e3:.1f} mm)"

    def to_json(self) -> dict:
        if self.goal is None:
            return {"modules": self.eef.split(","), "obstacle": self.obstacle, "slack": self.slack}
        return {"goal": self.goal, "eef": self.eef, "obstacle": self.obstacle, "slack": self.slack}


def _static_obstacles(task: Task) -> List[Tuple[str, GeometrySpec]]:
    return [(ob.id, g) for ob in task.obstacles if not ob.moving for g in ob.collision]


def _pose_block(goal_id: Optional[str], tp: ToleratedPose, eef: str, pieces: Sequence[_ToolPiece],
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


def _fixed_block(task: Task, ms: ModuleSet, prefix: Sequence[str], bp: ToleratedPose) -> Optional[ToolBlock]:
    """Whether the part of ``prefix`` (an order's first modules) that no joint moves collides with a static
    obstacle at every base pose ``bp`` allows: the robot's geometry fixed to the world, at the nominal base
    pose, against the obstacles shrunk by δ = p + θ·r (r: the farthest bounding-box corner of that geometry
    from the base frame's origin)."""
    p, th = position_radius(bp), rotation_radius(bp)
    if not (math.isfinite(p) and math.isfinite(th)):
        return None
    robot = Robot(ms, Assembly.from_order(ms, list(prefix)), base_pose=bp.nominal)
    gd = pin.GeometryData(robot.geom_model)
    pin.updateGeometryPlacements(robot.model, robot.data, robot.geom_model, gd, np.zeros(robot.model.nq))
    origin = bp.nominal[:3, 3]
    r = max((_corner_radius(obj.geometry, gd.oMg[i].homogeneous, origin)
             for i, obj in enumerate(robot.geom_model.geometryObjects) if obj.parentJoint == 0), default=0.0)
    d = p + th * r
    cores = [Obstacle(f"{oid}#{k}", core, g.pose) for k, (oid, g) in enumerate(_static_obstacles(task))
             for core in [_shrunk(g, d)] if core is not None]
    if not cores:
        return None
    robot.set_obstacles(cores)
    hits = robot.base_collisions()
    return ToolBlock(None, ",".join(prefix), hits[0][1].removeprefix("obstacle:").rsplit("#", 1)[0], d) \
        if hits else None


def fixed_part_proof(task: Task, space, limit: int = 2000) -> Optional["BlockedGoalProof"]:
    """A proof that every design of ``space`` collides with a static obstacle wherever the task's basePlacement
    allows its base: every chain from an allowed base module up to and including the first joint module has a
    part that no joint moves (:func:`_fixed_block`) inside an obstacle. The chains are walked from the base
    (a blocked chain blocks every extension; the fixed part only grows); None when some chain reaches its
    first joint unblocked, beyond ``limit`` chains, or without a bounded basePlacement or ``collisionFree``."""
    bp = task.base_placement
    if bp is None or bp.is_unconstrained or task.constraint(CollisionFree) is None or not _static_obstacles(task):
        return None
    ms = space.module_set
    blocks: List[ToolBlock] = []
    stack: List[Tuple[str, ...]] = [(b,) for b in space.base_modules]
    seen = 0
    while stack:
        prefix = stack.pop()
        seen += 1
        if seen > limit:
            return None
        b = _fixed_block(task, ms, prefix, bp)
        if b is not None:
            blocks.append(b)
            continue
        kind = ms[prefix[-1]].kind
        if kind in ("joint", "eef") and len(prefix) > 1:
            return None  # the first joint (or the end) reached with nothing in the way
        nxt = space.successors(prefix)
        if not nxt:
            continue  # a dead end of the rules: no design passes here
        stack.extend(prefix + (m,) for m in nxt)
    return BlockedGoalProof(tuple(blocks), part="fixed") if blocks else None


_MEMO: "weakref.WeakKeyDictionary[Task, Dict[str, Optional[ToolBlock]]]" = weakref.WeakKeyDictionary()


@dataclass(frozen=True)
class BlockedGoalProof:
    """Why no design of the module set fulfils the task: every end effector the search space allows lies, at
    some goal's pose (``blocks``, one per end effector), inside a static obstacle deeper than that goal's
    tolerance can move it; every design ends with one of them. Or (``part == "fixed"``) every chain of
    modules the search space allows from a base to its first joint has a part fixed to the world inside an
    obstacle at every base pose the basePlacement allows (``blocks``: the shortest blocked chains)."""
    blocks: Tuple[ToolBlock, ...]
    kind: str = "blocked"
    part: str = "eef"

    @property
    def goals(self) -> Tuple[str, ...]:
        return tuple(dict.fromkeys(b.goal for b in self.blocks if b.goal is not None))

    @property
    def message(self) -> str:
        where = "; ".join(b.where for b in self.blocks)
        if self.part == "fixed":
            return (f"provably out of reach: every design of the module set has a part that no joint moves inside an "
                    f"obstacle deeper than the base placement's tolerance can move it ({len(self.blocks)} chains from "
                    f"a base to its first joint, e.g. {where})")
        return ("provably out of reach: every end effector of the module set, held at a goal's pose, lies inside an "
                f"obstacle deeper than the goal's tolerance can move it: {where}")

    def to_json(self) -> dict:
        return {"kind": self.kind, "part": self.part, "goals": list(self.goals),
                "blocks": [b.to_json() for b in self.blocks], "message": self.message}


def blocked_goal_proof(task: Task, end_effectors: Sequence[Module], space=None) -> Optional[BlockedGoalProof]:
    """A proof that every module of ``end_effectors`` (the end effectors the search space allows) provably
    collides at some goal pose of ``task`` (:func:`tool_block`), or, given the search ``space``, that every
    design's fixed part does (:func:`fixed_part_proof`); None otherwise."""
    blocks = [tool_block(task, m) for m in end_effectors]
    if blocks and all(b is not None for b in blocks):
        return BlockedGoalProof(tuple(b for b in blocks if b is not None))
    return fixed_part_proof(task, space) if space is not None else None
