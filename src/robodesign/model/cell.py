"""The robot in its cell: a :class:`~robodesign.model.robot.Robot` placed by a solution or candidate in a task's
world (base pose, the task's gravity, its obstacles with the collision safety margin).

The checker, the solver and the viewer all build robots here, so the judged, the planned and the
plotted robot are the same object.
"""
from __future__ import annotations

import threading
from collections import OrderedDict
from typing import Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from robodesign.core.errors import InputError
from robodesign.formats.assembly import Assembly
from robodesign.formats.geometry import coal_shapes
from robodesign.formats.module_io import load_module_set
from robodesign.formats.module_spec import ModuleSet
from robodesign.formats.solution import Solution
from robodesign.formats.task_spec import CollisionFree, Task
from robodesign.model.robot import Obstacle, Robot
from robodesign.model.sweep import CollisionEvent, SweepChecker


def resolve_module_set(solution: Solution, module_set: Union[ModuleSet, str, None] = None) -> ModuleSet:
    """``module_set`` itself, else the set it names, else the one the solution names (InputError if none)."""
    if isinstance(module_set, ModuleSet):
        return module_set
    name = module_set or solution.module_set
    if not name:
        raise InputError("the solution names no moduleSet; pass --modules", file=solution.source or "solution")
    return load_module_set(name)


def task_obstacles(task: Task, t: float = 0.0) -> List[Obstacle]:
    """The task's collision objects at time ``t`` (moving obstacles at their pose in effect then)."""
    out = []
    for ob in task.obstacles:
        M = ob.transform_at(t)
        for gi, g in enumerate(ob.collision):
            for si, shape in enumerate(coal_shapes(g)):
                out.append(Obstacle(f"{ob.id}.{gi}.{si}", shape, M @ g.pose))  # see obstacle_spec_id
    return out


def obstacle_spec_id(obstacle: Obstacle) -> str:
    """The id of the task obstacle a collision object of :func:`task_obstacles` comes from."""
    return obstacle.name.rsplit(".", 2)[0]


def safety_margin(task: Task) -> float:
    """The collision safety margin of the task (the largest ``collisionFree`` margin, 0 without one)."""
    return max([c.safety_margin for c in task.constraints if isinstance(c, CollisionFree)], default=0.0)


def build_robot(task: Optional[Task], ms: ModuleSet, assembly: Assembly, base_pose: np.ndarray) -> Robot:
    """The robot in the task's cell: base pose, the task's gravity, obstacles with the safety margin.
    Without a task: default gravity and no obstacles."""
    if task is None:
        return Robot(ms, assembly, base_pose=base_pose)
    robot = Robot(ms, assembly, base_pose=base_pose, gravity=task.header.gravity)
    robot.set_obstacles(task_obstacles(task), safety_margin=safety_margin(task))
    return robot


class RobotPool:
    """Robots built in one cell (``task``: its obstacles with the safety margin and its gravity; None: none),
    kept for reuse: a search evaluates the same assembly at many base poses, and taking a robot back costs a
    base-pose change instead of a build (the model, the collision geometry and pairs, the collision scratch
    space). The cell's obstacles are set up once. A robot is lent to one user at a time (:meth:`take`, then
    :meth:`give_back` when done with it); it answers every query as a fresh :func:`build_robot` does. At most
    ``size`` robots are kept (the least recently given back go first)."""

    def __init__(self, task: Optional[Task], size: int = 24):
        self.task, self.size = task, int(size)
        self.obstacles = task_obstacles(task) if task is not None else []
        self.margin = safety_margin(task) if task is not None else 0.0
        self._free: "OrderedDict[Tuple[int, str], List[Robot]]" = OrderedDict()
        self._count = 0
        self._lock = threading.Lock()

    def take(self, ms: ModuleSet, assembly: Assembly, base_pose: np.ndarray) -> Robot:
        """A robot of ``assembly`` at ``base_pose`` in the cell, built or taken back from the pool."""
        key = (id(ms), assembly.key())
        with self._lock:
            robots = self._free.get(key)
            robot = robots.pop() if robots else None
            if robot is not None:
                self._count -= 1
        if robot is None or robot.module_set is not ms or robot.assembly != assembly:
            robot = _adopt(ms, assembly)  # a bare robot of the assembly built for its kinematics, or None
            if robot is None:
                robot = Robot(ms, assembly, base_pose=base_pose) if self.task is None else \
                    Robot(ms, assembly, base_pose=base_pose, gravity=self.task.header.gravity)
            else:
                robot.set_base_pose(base_pose)
                if self.task is not None:
                    robot.set_gravity(self.task.header.gravity)
            if self.task is not None:
                robot.set_obstacles(self.obstacles, safety_margin=self.margin)
            return robot
        robot.set_base_pose(base_pose)  # (its collision scratch space as a new one's)
        return robot

    def give_back(self, robot: Robot) -> None:
        """Return a robot that :meth:`take` lent (its obstacles where they were, nothing else changed)."""
        key = (id(robot.module_set), robot.assembly.key())
        with self._lock:
            self._free.setdefault(key, []).append(robot)
            self._free.move_to_end(key)
            self._count += 1
            while self._count > self.size:
                old = next(iter(self._free))
                self._count -= len(self._free.pop(old))


_SPARE: "OrderedDict[Tuple[int, str], Robot]" = OrderedDict()  # (id(module set), assembly key) → bare robot
_SPARE_SIZE = 64
_SPARE_LOCK = threading.Lock()


def kinematic_robot(ms: ModuleSet, order: Sequence[str], base_pose: np.ndarray) -> Robot:
    """``Robot.from_order(ms, order, base_pose=base_pose)`` for a look at its kinematics (reach bound, Jacobian
    rank: what a search space asks of an order before any evaluation). The robot is kept afterwards (at most
    64 of them): the first :meth:`RobotPool.take` of its assembly adopts it instead of building it again. The
    caller must not change it."""
    robot = Robot.from_order(ms, order, base_pose=base_pose)
    with _SPARE_LOCK:
        _SPARE[(id(ms), robot.assembly.key())] = robot
        while len(_SPARE) > _SPARE_SIZE:
            _SPARE.popitem(last=False)
    return robot


def _adopt(ms: ModuleSet, assembly: Assembly) -> Optional[Robot]:
    """The bare robot :func:`kinematic_robot` built of ``assembly`` (taken out of the spares), or None. Only its
    base pose, gravity and obstacles are then set: a robot equal to a fresh build (its Jacobian's generic rank,
    if computed, is kept: it does not depend on the base pose)."""
    with _SPARE_LOCK:
        robot = _SPARE.pop((id(ms), assembly.key()), None)
    return robot if robot is not None and robot.module_set is ms and robot.assembly == assembly else None


def solution_robot(task: Optional[Task], solution: Solution, module_set=None) -> Robot:
    """The robot of ``solution`` in ``task``'s cell (``module_set``: a ModuleSet, a name/folder, or None for
    the solution's). Raises AssemblyError for an invalid assembly, InputError for an unknown module set."""
    ms = resolve_module_set(solution, module_set)
    return build_robot(task, ms, solution.assembly(ms), solution.base_pose)


def moving_obstacle_indices(robot: Robot, task: Task) -> List[int]:
    """Indices into ``robot.obstacles`` of the collision objects of the task's moving obstacles."""
    moving_ids = {ob.id for ob in task.obstacles if ob.moving}
    return [i for i, ob in enumerate(robot.obstacles) if obstacle_spec_id(ob) in moving_ids]


def moving_obstacle_events(robot: Robot, task: Task, moving: Sequence[int], t: np.ndarray, Q: np.ndarray, *,
                           first_only: bool = False, between_samples: bool = True,
                           checker: Optional[SweepChecker] = None, path: Optional[np.ndarray] = None,
                           at: Optional[Callable[[int, float], np.ndarray]] = None) -> List[CollisionEvent]:
    """Collisions of the motion through the rows of ``Q`` at the times ``t`` with the moving obstacles
    ``moving`` (indices into ``robot.obstacles``, e.g. :func:`moving_obstacle_indices`); event samples index
    the rows of ``Q``.

    An obstacle's pose is the one in effect at a sample's time (zero-order hold,
    ``ObstacleSpec.transform_at``) and is kept over the motion to the next sample; runs of samples with
    unchanged obstacle poses are certified together by conservative advancement (``between_samples``; else
    only the samples are checked). One event per pair and contact episode, or only the first event with
    ``first_only``. ``checker``: a SweepChecker over exactly these robot–obstacle pairs, to reuse it.
    ``path``/``at``: the motion between the samples when it is not the chord (the judge's motion model; as
    :meth:`SweepChecker.check`, indexed by the rows of ``Q``).
    """
    specs = {ob.id: ob for ob in task.obstacles if ob.moving}
    movers = [(i, specs[obstacle_spec_id(robot.obstacles[i])], np.array(robot.obstacles[i].pose, dtype=float))
              for i in moving]  # (robot obstacle index, spec, t=0 world pose of the geometry)
    chk = checker or SweepChecker(robot, check_self=False, check_env=True, obstacles=list(moving))
    t = np.asarray(t, dtype=float)
    Q = np.asarray(Q, dtype=float)
    times = []
    for sp in specs.values():
        assert sp.motion_t is not None  # a moving obstacle has the times of its poses (parse_task)
        times.append(sp.motion_t)
    keys = [tuple(int(np.searchsorted(mt, tk + 1e-12, side="right")) for mt in times) for tk in t]
    events: List[CollisionEvent] = []
    last: Dict[tuple, int] = {}  # pair → last sample in contact (one event per pair and contact episode)
    a = 0
    try:
        while a < len(keys):
            b = a
            while b + 1 < len(keys) and keys[b + 1] == keys[a]:
                b += 1
            for i, sp, pose0 in movers:
                robot.move_obstacle(i, sp.transform_at(float(t[a])) @ pose0)
            if not between_samples:
                hits = np.nonzero(chk.sample_collisions(Q[a:b + 1]))[0]
                events += [CollisionEvent(int(k + a), 0.0, "", "", 0.0, True) for k in hits]
                if first_only and events:
                    return events[:1]
                a = b + 1
                continue
            end = min(b + 1, len(keys) - 1)  # include the motion to the next sample (obstacle still here)
            Qr = Q[a:end + 1]
            evs = chk.check(Qr, first_only=first_only, path=None if path is None else path[a:end],
                            at=None if at is None else _shifted(at, a))
            for e in evs:
                e = CollisionEvent(e.sample + a, e.s, e.first, e.second, e.distance, e.environment)
                if first_only:
                    return [e]
                pair = (e.first, e.second)
                if pair not in last or e.sample > last[pair] + 1:  # else: the episode of the previous run
                    events.append(e)
                last[pair] = e.sample
            for pair in chk.in_contact(Qr[-1], {(e.first, e.second) for e in evs}):
                last[pair] = end  # still in contact at the end of this run
            a = b + 1
    finally:
        for i, _, pose0 in movers:
            robot.move_obstacle(i, pose0)
    return events


def _shifted(at: Callable[[int, float], np.ndarray], a: int) -> Callable[[int, float], np.ndarray]:
    """``at`` for the rows of ``Q`` from ``a`` on: step k of the run is step k + a of the motion."""
    return lambda k, s: at(k + a, s)
