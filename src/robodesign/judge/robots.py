"""The judge's robots, kept per task for reuse (issue 25).

A search judges the same assembly again and again, at other base poses or on other motions; the solver's
stages keep their robots in a :class:`~robodesign.model.cell.RobotPool` for that reason, and so does the judge,
one pool per task (the task's full cell: every obstacle, its safety margin and gravity; a different cell from
the solver's static one). A robot taken back costs a base-pose change instead of a build of its model and
collision geometry, and it answers every query as a fresh :func:`~robodesign.model.cell.build_robot` does
(the pool's promise; tests/test_judge_robots.py compares the verdicts).

The first robot of a task is built as before, by :func:`~robodesign.model.cell.solution_robot`'s steps, so the
task's pool is made only once a check has given a robot back (a task whose obstacles cannot be built fails
exactly where it failed). A check gives its robot back only when it returns: a robot whose check raised is
dropped.

A robot lent to a check also keeps the scratch space of its sweep (:func:`scratch`,
:class:`~robodesign.model.sweep_scratch.KeptScratch`: the answers of a new one), lent with the robot.
"""
from __future__ import annotations

import weakref
from typing import Optional

from robodesign.formats.solution import Solution
from robodesign.formats.task_spec import Task
from robodesign.model.cell import RobotPool, build_robot, resolve_module_set
from robodesign.model.robot import Robot
from robodesign.model.sweep_scratch import KeptScratch

_POOLS: "weakref.WeakKeyDictionary[Task, RobotPool]" = weakref.WeakKeyDictionary()
_LENT: "weakref.WeakKeyDictionary[Robot, bool]" = weakref.WeakKeyDictionary()   # robot lent to a check → its
# scratch space not yet lent to that check's sweep
_SCRATCH: "weakref.WeakKeyDictionary[Robot, KeptScratch]" = weakref.WeakKeyDictionary()


def take(task: Task, solution: Solution, module_set=None) -> Robot:
    """The robot of ``solution`` in ``task``'s cell, as :func:`~robodesign.model.cell.solution_robot` gives it:
    taken from the task's pool, or built (AssemblyError for an invalid assembly, InputError for an unknown
    module set or a bad base pose). Hand it back with :func:`give_back` when the check is done."""
    ms = resolve_module_set(solution, module_set)
    assembly = solution.assembly(ms)
    pool: Optional[RobotPool] = _POOLS.get(task)
    robot = build_robot(task, ms, assembly, solution.base_pose) if pool is None else \
        pool.take(ms, assembly, solution.base_pose)
    _LENT[robot] = True
    return robot


def give_back(task: Task, robot: Robot) -> None:
    """Keep ``robot`` (taken by :func:`take` for ``task``, its obstacles where they were) for the next check."""
    _LENT.pop(robot, None)
    pool = _POOLS.get(task)
    if pool is None:
        pool = _POOLS.setdefault(task, RobotPool(task))
    pool.give_back(robot)


def scratch(robot: Robot) -> Optional[KeptScratch]:
    """The sweep's scratch space kept with ``robot``, for the one sweep of the check that holds the robot (None:
    a robot not lent by :func:`take`, or asked again in the same check; that checker makes its own)."""
    if not _LENT.get(robot, False):
        return None
    _LENT[robot] = False
    kept, gm = _SCRATCH.get(robot), robot.geom_model
    if kept is None or not kept.fits(gm):
        kept = _SCRATCH[robot] = KeptScratch(gm)
    return kept
