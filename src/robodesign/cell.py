"""The robot in its cell: a :class:`~robodesign.robot.Robot` placed by a solution or candidate in a task's
world (base pose, the task's gravity, its obstacles with the collision safety margin).

The checker, the solver and the viewer all build robots here, so the judged, the planned and the
plotted robot are the same object.
"""
from __future__ import annotations

from typing import List, Optional, Union

import numpy as np

from .assembly import Assembly
from .errors import InputError
from .geometry import coal_shapes
from .module_io import load_module_set
from .module_spec import ModuleSet
from .robot import Obstacle, Robot
from .solution import Solution
from .task_spec import CollisionFree, Task


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


def solution_robot(task: Optional[Task], solution: Solution, module_set=None) -> Robot:
    """The robot of ``solution`` in ``task``'s cell (``module_set``: a ModuleSet, a name/folder, or None for
    the solution's). Raises AssemblyError for an invalid assembly, InputError for an unknown module set."""
    ms = resolve_module_set(solution, module_set)
    return build_robot(task, ms, solution.assembly(ms), solution.base_pose)
