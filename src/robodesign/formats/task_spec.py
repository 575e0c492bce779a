"""Typed, immutable description of a CoBRA task: workcell, goals and constraints.

See docs/formats.md for the JSON format and where robodesign's semantics deliberately differ
from the reference implementation (gravity is honoured, follow-goal wrenches are honoured, a task
file without a ``constraints`` key gets the default constraint set).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, ClassVar, Dict, FrozenSet, List, Optional, Sequence, Tuple, Type, TypeVar

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
        assert self.motion_t is not None  # a moving obstacle has the times of its poses (parse_task)
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
    pose: Optional[ToleratedPose] = None


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
WINDOW_TIME_TOL = 1e-9  # slack when a window's start or end time is compared with the samples [s]

#: what :meth:`Goal.check` gets to report a miss: ``violation(message, sample=…, time=…, value=…, bound=…)``
#: returns the judge's violation of this goal (time defaults to the goal time's sample)
ViolationFactory = Callable[..., Any]


def describe_pose_violations(violations: Sequence[Tuple[str, float, float, float]]) -> str:
    """``[(projection, value, lo, hi)]`` of :meth:`ToleratedPose.violations` → readable text."""
    return "; ".join(f"{p} = {val:.6g} not in [{lo:.6g}, {hi:.6g}]" for p, val, lo, hi in violations)


def _window_from(t: np.ndarray, t_start: float, k: int) -> Optional[Tuple[int, int]]:
    """The samples from time ``t_start`` to sample ``k``; None if ``t_start`` is before the trajectory."""
    if t_start < t[0] - WINDOW_TIME_TOL:
        return None
    return int(np.searchsorted(t, t_start - WINDOW_TIME_TOL, side="left")), k


def _check_pose(goal: "Goal", pose: Optional[ToleratedPose], tq: Any, k: int, violation: ViolationFactory) \
        -> List[Any]:
    """The TCP at sample ``k`` within ``pose`` (at and reach goals)."""
    assert pose is not None  # an at or reach goal read from a task has its pose (its field defaults to None)
    T = tq.tcp_poses[k]
    if pose.valid(T):
        return []
    return [violation(f"{goal.type}: TCP pose outside the goal tolerance: "
                      + describe_pose_violations(pose.violations(T)), sample=k)]


@dataclass(frozen=True, eq=False)
class Goal:
    """A goal of a task. Each goal type is a class naming its CoBRA ``type_name`` and the solver handler
    it needs (``solver_kind``); its parser is registered under that name in
    :mod:`robodesign.formats.goal_types` (a plugin goal type registers there too, docs/architecture.md).

    The task reader asks the class for :meth:`canonical_json` (the variants of its JSON it reads).
    The judge asks the goal itself (no dispatch on goal classes elsewhere): :meth:`time_window` (the samples
    its goal-level constraints hold over), :meth:`check` (why a trajectory misses it), :attr:`external_wrench`
    (a wrench it applies at the TCP during its window) and :attr:`referenced_goals` (goal IDs it names, which
    the task reader checks). ``tq`` in these methods is the trajectory's
    :class:`~robodesign.judge.quantities.TrajectoryQuantities` (``t``, ``q``, ``dq``, ``ddq``, ``tcp_poses``,
    ``tcp_twists``, ``tcp_at(time)``, ``goal2time``, ``goal_windows``, ``sample_at(time)``)."""
    id: str
    constraints: Tuple[TaskConstraint, ...] = ()

    #: the CoBRA goal type (the JSON ``type``)
    type_name: ClassVar[str] = ""
    #: a plugin goal type's own JSON keys and JSON Schema, read by ``register_goal_type`` (with the class's
    #: ``from_json(data, ctx)`` classmethod as its parser) when it is given the class alone
    json_keys: ClassVar[Tuple[str, ...]] = ()
    json_schema: ClassVar[Optional[dict]] = None
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

    @classmethod
    def canonical_json(cls, data: Dict[str, Any], file: str, path: List[Any], warnings: Any) -> Dict[str, Any]:
        """The goal's JSON object (keys already matched to the type's own, case-insensitively) with the
        variants the type reads brought into the one form its schema and ``from_json`` accept; ``warnings``
        (:class:`~robodesign.core.input_warnings.InputWarnings`) takes what is read with a warning. Default:
        unchanged (the built-in types' variants are read by the task reader, docs/formats.md)."""
        return data

    @property
    def referenced_goals(self) -> Tuple[Tuple[str, str], ...]:
        """(JSON key, goal ID) of every other goal this goal names; the task reader rejects unknown IDs."""
        return ()

    @property
    def external_wrench(self) -> Optional[np.ndarray]:
        """(6,) world wrench ``[f; τ]`` the goal applies at the TCP during its window, or None."""
        return None

    def time_window(self, tq: Any, k: int) -> Optional[Tuple[int, int]]:
        """Samples (k0, k1), inclusive, the goal spans when its goal time is sample ``k``; None if the window
        leaves the trajectory. Default: the instant t_g."""
        return k, k

    def check(self, tq: Any, k: int, violation: ViolationFactory) -> List[Any]:
        """Why the trajectory misses the goal, its goal time being sample ``k`` (empty: achieved); each
        reason made by ``violation``. Goal-level constraints are checked by the judge over
        :meth:`time_window`."""
        return [violation(f"unsupported goal type {type(self).__name__}")]


@dataclass(frozen=True, eq=False)
class At(Goal):
    pose: Optional[ToleratedPose] = None
    type_name: ClassVar[str] = "at"
    solver_kind: ClassVar[str] = "pose"

    @property
    def target_poses(self) -> Tuple[ToleratedPose, ...]:
        return (self.pose,) if self.pose is not None else ()

    def check(self, tq: Any, k: int, violation: ViolationFactory) -> List[Any]:
        return _check_pose(self, self.pose, tq, k, violation)


@dataclass(frozen=True, eq=False)
class Reach(Goal):
    pose: Optional[ToleratedPose] = None
    velocity_tolerance: float = 1e-3  # every component of the TCP twist at t_g
    type_name: ClassVar[str] = "reach"
    solver_kind: ClassVar[str] = "pose"

    @property
    def target_poses(self) -> Tuple[ToleratedPose, ...]:
        return (self.pose,) if self.pose is not None else ()

    def check(self, tq: Any, k: int, violation: ViolationFactory) -> List[Any]:
        out = _check_pose(self, self.pose, tq, k, violation)
        m = float(np.abs(tq.tcp_twists[k]).max())
        if m > self.velocity_tolerance:
            out.append(violation(f"reach: the TCP is still moving (max twist component {m:.4g} > "
                                 f"{self.velocity_tolerance})", sample=k, value=m, bound=self.velocity_tolerance))
        return out


@dataclass(frozen=True, eq=False)
class ReturnTo(Goal):
    return_to: Optional[str] = None  # goal ID; None = the start (t = 0)
    epsilon: float = 1e-4
    type_name: ClassVar[str] = "returnTo"
    solver_kind: ClassVar[str] = "return"

    @property
    def referenced_goals(self) -> Tuple[Tuple[str, str], ...]:
        return (("returnToGoal", self.return_to),) if self.return_to is not None else ()

    def check(self, tq: Any, k: int, violation: ViolationFactory) -> List[Any]:
        kr = 0
        if self.return_to is not None:
            if self.return_to not in tq.goal2time:
                return [violation(f"returnTo: goal {self.return_to!r} has no goal2time entry", sample=k)]
            kr = tq.sample_at(tq.goal2time[self.return_to])
            if kr is None:
                return [violation(f"returnTo: no unique sample at goal {self.return_to!r}'s time", sample=k)]
        out = []
        for name, arr in (("q", tq.q), ("dq", tq.dq), ("ddq", tq.ddq)):
            d = float(np.linalg.norm(arr[k] - arr[kr]))
            if d > self.epsilon:
                out.append(violation(f"returnTo: ‖Δ{name}‖ = {d:.4g} to sample {kr} exceeds {self.epsilon}",
                                     sample=k, value=d, bound=self.epsilon))
        return out


@dataclass(frozen=True, eq=False)
class Pause(Goal):
    duration: float = 0.0
    type_name: ClassVar[str] = "pause"
    solver_kind: ClassVar[str] = "hold"

    def time_window(self, tq: Any, k: int) -> Optional[Tuple[int, int]]:
        return _window_from(tq.t, tq.goal2time[self.id] - self.duration, k)

    def check(self, tq: Any, k: int, violation: ViolationFactory) -> List[Any]:
        tg = tq.goal2time[self.id]
        window = tq.goal_windows.get(self.id)
        if window is None:
            return [violation(f"pause: the window starts at {tg - self.duration:.4f} s, before the trajectory",
                              sample=k)]
        k0 = window[0]
        out = []
        dq_max = float(np.abs(tq.q[k0:k + 1] - tq.q[k0]).max())
        v_max = float(np.abs(tq.dq[k0:k + 1]).max())
        a_max = float(np.abs(tq.ddq[k0:k + 1]).max())
        if dq_max > 1e-9:
            out.append(violation(f"pause: q moves by {dq_max:.3g} during the pause [{tq.t[k0]:.4f}, {tg:.4f}] s",
                                 sample=k))
        if v_max > 1e-9 or a_max > 1e-9:
            out.append(violation(f"pause: dq/ddq not zero during the pause (max |dq| {v_max:.3g}, |ddq| "
                                 f"{a_max:.3g})", sample=k))
        return out


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

    @property
    def external_wrench(self) -> Optional[np.ndarray]:
        return np.concatenate([self.external_force, self.external_torque]).astype(float)

    def untimed_match(self, tcp_poses: np.ndarray, k: int) -> Tuple[int, Optional[int]]:
        """Walking back from sample ``k`` (the goal time), each pose of the untimed goal (last to first) is
        met at an earlier or equal sample. Returns (first sample of the window, index of the first pose never
        met or None)."""
        kk = k
        for i in range(len(self.poses) - 1, -1, -1):
            while kk >= 0 and not self.poses[i].valid(tcp_poses[kk]):
                kk -= 1
            if kk < 0:
                return 0, i
        return kk, None

    def time_window(self, tq: Any, k: int) -> Optional[Tuple[int, int]]:
        if self.t is None:
            return self.untimed_match(tq.tcp_poses, k)[0], k
        return _window_from(tq.t, tq.goal2time[self.id] + self.t[0] - self.t[-1], k)

    def check(self, tq: Any, k: int, violation: ViolationFactory) -> List[Any]:
        if self.t is None:
            _, unmet = self.untimed_match(tq.tcp_poses, k)
            return [] if unmet is None else [violation(f"follow: pose {unmet} (of {len(self.poses)}) is never met "
                                                       "before t_g", sample=k)]
        tg = tq.goal2time[self.id]
        rel = self.t - self.t[-1]
        if tq.goal_windows.get(self.id) is None:
            return [violation(f"follow: the timed trajectory would start at {tg + rel[0]:.4f} s, before t=0",
                              sample=k)]
        out = []
        for i, (pose, dt_) in enumerate(zip(self.poses, rel)):
            ti = tg + dt_
            Ti = tq.tcp_at(ti)
            if not pose.valid(Ti):
                out.append(violation(f"follow: pose {i} not met at t={ti:.4f}: "
                                     + describe_pose_violations(pose.violations(Ti)), time=ti))
        return out


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

    def time_window(self, tq: Any, k: int) -> Optional[Tuple[int, int]]:
        t_end = tq.goal2time[self.id] + self.duration
        if t_end > tq.t[-1] + WINDOW_TIME_TOL:
            return None
        return k, int(np.searchsorted(tq.t, t_end + WINDOW_TIME_TOL, side="right") - 1)

    def check(self, tq: Any, k: int, violation: ViolationFactory) -> List[Any]:
        tg = tq.goal2time[self.id]
        t_end = tg + self.duration
        window = tq.goal_windows.get(self.id)
        if window is None:
            return [violation(f"leave: the trajectory ends before t_g + duration = {t_end:.4f} s", sample=k)]
        T = tq.tcp_poses
        inside = [kk for kk in range(window[0], window[1] + 1) if self.contains(T[kk])]
        if inside:
            return [violation(f"leave: the TCP is inside the region to leave at {len(inside)} samples of "
                              f"[{tg:.4f}, {t_end:.4f}] s (first at t={tq.t[inside[0]]:.4f})", sample=inside[0])]
        return []

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


_C = TypeVar("_C", bound=TaskConstraint)


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

    def constraint(self, cls: Type[_C]) -> Optional[_C]:
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
