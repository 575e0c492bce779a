"""Typed, immutable description of a CoBRA task: workcell, goals and constraints.

See docs/formats.md for the JSON format and where robodesign's semantics deliberately differ
from the reference implementation (gravity is honoured, follow-goal wrenches are honoured, a task
file without a ``constraints`` key gets the default constraint set).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar, Dict, FrozenSet, Optional, Tuple

import numpy as np

from robodesign.formats.geometry import GeometrySpec, center_point, contains_point
from robodesign.formats.tolerance import ToleratedPose


@dataclass(frozen=True)
class TaskHeader:
    id: str
    version: str = "2023"
    name: str = ""
    tags: Tuple[str, ...] = ()
    date: str = ""
    time_step: float = 0.01
    gravity: Tuple[float, float, float] = (0.0, 0.0, -9.81)
    author: Tuple[str, ...] = ()
    email: Tuple[str, ...] = ()
    affiliation: Tuple[str, ...] = ()


@dataclass(frozen=True, eq=False)
class ObstacleSpec:
    id: str
    name: str
    collision: Tuple[GeometrySpec, ...]  # world poses (at t=0 for moving obstacles)
    visual: Tuple[GeometrySpec, ...] = ()
    # moving obstacle: at time motion_t[k] the transform motion_poses[k] is applied on the left of
    # the geometry's world pose: world(t) = motion_poses[k] · geometry pose (zero-order hold)
    motion_t: Optional[np.ndarray] = None  # (K,)
    motion_poses: Optional[np.ndarray] = None  # (K,4,4)

    @property
    def moving(self) -> bool:
        return self.motion_poses is not None

    def transform_at(self, t: float) -> np.ndarray:
        """World transform applied to the t=0 geometry at time t (zero-order hold between poses)."""
        if self.motion_poses is None:
            return np.eye(4)
        k = int(np.searchsorted(self.motion_t, t + 1e-12, side="right") - 1)
        k = min(max(k, 0), len(self.motion_t) - 1)
        return self.motion_poses[k]


# ---------------------------------------------------------------------------------------------
# Constraints (paper Table III)
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TaskConstraint:
    @property
    def type(self) -> str:
        return _CONSTRAINT_TYPE_NAMES[type(self)]


@dataclass(frozen=True)
class JointLimitsConstraint(TaskConstraint):
    parts: FrozenSet[str] = frozenset({"q", "dq", "tau"})


@dataclass(frozen=True)
class CollisionFree(TaskConstraint):
    safety_margin: float = 0.0


@dataclass(frozen=True)
class SelfCollisionFree(TaskConstraint):
    pass


@dataclass(frozen=True, eq=False)
class BasePlacement(TaskConstraint):
    pose: ToleratedPose = None


@dataclass(frozen=True, eq=False)
class EndEffectorConstraint(TaskConstraint):
    pose: Optional[ToleratedPose] = None
    v_min: float = 0.0
    v_max: float = float("inf")
    o_min: float = 0.0
    o_max: float = float("inf")


@dataclass(frozen=True)
class AllGoalsFulfilled(TaskConstraint):
    pass


@dataclass(frozen=True)
class GoalsInOrder(TaskConstraint):
    order: Tuple[str, ...] = ()


@dataclass(frozen=True)
class ValidAssembly(TaskConstraint):
    pass


@dataclass(frozen=True)
class AlwaysTrue(TaskConstraint):
    pass


_CONSTRAINT_TYPE_NAMES = {JointLimitsConstraint: "joint", CollisionFree: "collisionFree",
                          SelfCollisionFree: "selfCollisionFree", BasePlacement: "basePlacement",
                          EndEffectorConstraint: "endEffector", AllGoalsFulfilled: "allGoalsFulfilled",
                          GoalsInOrder: "allGoalsFulfilledInOrder", ValidAssembly: "validAssembly",
                          AlwaysTrue: "alwaysTrue"}
GLOBAL_ONLY = (BasePlacement, AllGoalsFulfilled, GoalsInOrder, ValidAssembly)


def default_constraints() -> Tuple[TaskConstraint, ...]:
    return (JointLimitsConstraint(frozenset({"q", "dq", "tau"})), CollisionFree(0.0), AllGoalsFulfilled())


# ---------------------------------------------------------------------------------------------
# Goals (paper Table IV)
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Goal:
    """A goal of a task. Each goal type is a subclass naming its CoBRA ``type_name`` and the solver handler
    it needs (``solver_kind``); its parser is registered under that name in
    :mod:`robodesign.formats.goal_types` (a plugin goal type registers there too, docs/architecture.md)."""
    id: str
    constraints: Tuple[TaskConstraint, ...] = ()

    #: the CoBRA goal type (the JSON ``type``)
    type_name: ClassVar[str] = ""
    #: the solve pipeline's handler (design/solve.py) and what it reads of the goal: "pose" (IK of
    #: ``target_poses[0]``, move there and stop), "poses" (visit the IK solutions of ``target_poses``, timed by
    #: ``t`` or untimed if None), "hold" (stay still for ``duration``), "return" (move back to the
    #: configuration of goal ``return_to``, None = the start), "leave" (retreat until not ``contains(T)``,
    #: away from ``center``, and stay out for ``duration``)
    solver_kind: ClassVar[str] = ""

    @property
    def type(self) -> str:
        return type(self).type_name

    @property
    def target_poses(self) -> Tuple[ToleratedPose, ...]:
        """The tolerated poses the TCP must reach (none for goals defined by time or by a space to leave)."""
        return ()

    @property
    def anchor(self) -> Optional[ToleratedPose]:
        """The tolerated pose where the goal is shown (plots, labels): its first target pose by default."""
        poses = self.target_poses
        return poses[0] if poses else None


@dataclass(frozen=True, eq=False)
class At(Goal):
    pose: ToleratedPose = None
    type_name: ClassVar[str] = "at"
    solver_kind: ClassVar[str] = "pose"

    @property
    def target_poses(self) -> Tuple[ToleratedPose, ...]:
        return (self.pose,) if self.pose is not None else ()


@dataclass(frozen=True, eq=False)
class Reach(Goal):
    pose: ToleratedPose = None
    velocity_tolerance: float = 1e-3  # every component of the TCP twist at t_g
    type_name: ClassVar[str] = "reach"
    solver_kind: ClassVar[str] = "pose"

    @property
    def target_poses(self) -> Tuple[ToleratedPose, ...]:
        return (self.pose,) if self.pose is not None else ()


@dataclass(frozen=True, eq=False)
class ReturnTo(Goal):
    return_to: Optional[str] = None  # goal ID; None = the start (t = 0)
    epsilon: float = 1e-4
    type_name: ClassVar[str] = "returnTo"
    solver_kind: ClassVar[str] = "return"


@dataclass(frozen=True, eq=False)
class Pause(Goal):
    duration: float = 0.0
    type_name: ClassVar[str] = "pause"
    solver_kind: ClassVar[str] = "hold"


@dataclass(frozen=True, eq=False)
class Follow(Goal):
    poses: Tuple[ToleratedPose, ...] = ()
    t: Optional[np.ndarray] = None  # timed trajectory (relative times), None = untimed
    external_force: np.ndarray = field(default_factory=lambda: np.zeros(3))  # world frame, at the TCP
    external_torque: np.ndarray = field(default_factory=lambda: np.zeros(3))
    type_name: ClassVar[str] = "follow"
    solver_kind: ClassVar[str] = "poses"

    @property
    def target_poses(self) -> Tuple[ToleratedPose, ...]:
        return tuple(self.poses)


@dataclass(frozen=True, eq=False)
class Leave(Goal):
    """At t_g the TCP is outside the space to leave and stays outside for ``duration`` seconds.

    The space is ``occupied_space`` (geometries in world coordinates, the published form
    ``occupiedSpace``: the TCP point must lie in none of them) and/or ``region`` (robodesign's
    extension: the TCP poses that satisfy this tolerated pose).
    """
    region: Optional[ToleratedPose] = None
    duration: float = 0.0
    occupied_space: Tuple[GeometrySpec, ...] = ()
    type_name: ClassVar[str] = "leave"
    solver_kind: ClassVar[str] = "leave"

    @property
    def anchor(self) -> Optional[ToleratedPose]:
        return self.region

    def contains(self, T: np.ndarray) -> bool:
        """Whether the TCP pose T (4x4, world) is inside the space to leave."""
        if self.region is not None and self.region.valid(T):
            return True
        return any(contains_point(g, T[:3, 3]) for g in self.occupied_space)

    @property
    def center(self) -> np.ndarray:
        """A world point in the middle of the space to leave (to move away from)."""
        pts = [center_point(g) for g in self.occupied_space]
        if self.region is not None:
            pts.append(self.region.nominal[:3, 3])
        return np.mean(pts, axis=0)


BUILTIN_GOAL_TYPES = (At, Reach, ReturnTo, Pause, Follow, Leave)


@dataclass(frozen=True, eq=False)
class Task:
    header: TaskHeader
    obstacles: Tuple[ObstacleSpec, ...]
    goals: Tuple[Goal, ...]
    constraints: Tuple[TaskConstraint, ...]
    frames: Dict[str, np.ndarray] = field(default_factory=dict)  # name → world pose
    root: Optional[Path] = None  # package folder (assets resolve against it)
    source: Optional[str] = None
    warnings: Tuple[str, ...] = ()

    @property
    def id(self) -> str:
        return self.header.id

    @property
    def dt(self) -> float:
        return self.header.time_step

    def goal(self, goal_id: str) -> Goal:
        for g in self.goals:
            if g.id == goal_id:
                return g
        raise KeyError(goal_id)

    def constraint(self, cls) -> Optional[TaskConstraint]:
        for c in self.constraints:
            if isinstance(c, cls):
                return c
        return None

    @property
    def base_placement(self) -> Optional[ToleratedPose]:
        c = self.constraint(BasePlacement)
        return c.pose if c is not None else None

    @property
    def nominal_base_pose(self) -> np.ndarray:
        bp = self.base_placement
        return np.array(bp.nominal, dtype=float) if bp is not None else np.eye(4)

    @property
    def goal_order(self) -> Tuple[str, ...]:
        """Goal IDs in the order they must be (or naturally are) achieved."""
        c = self.constraint(GoalsInOrder)
        ids = [g.id for g in self.goals]
        if c is None:
            return tuple(ids)
        rest = [i for i in ids if i not in c.order]
        # listed goals keep their relative order; unlisted goals keep file order around them
        out, it = [], iter(c.order)
        for i in ids:
            out.append(next(it) if i in c.order else i)
        return tuple(out) if len(out) == len(ids) else tuple(list(c.order) + rest)
