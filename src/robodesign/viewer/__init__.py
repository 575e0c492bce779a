"""See the robots move: self-contained HTML pages of tasks, robots and solutions (docs/viewer.md).

* :func:`robodesign.viewer.scene.build_scene` — task/robot/trajectory → plain scene data (dict).
* :func:`robodesign.viewer.html.render_html` — scene + PNG plots → one HTML page (three.js inlined).
* :func:`robodesign.viewer.plots.trajectory_plots` — q, dq, ddq, τ against the limits; TCP path.
* :func:`solution_page`, :func:`task_page`, :func:`robot_page` — the pages in one call.
"""
from __future__ import annotations

from typing import Mapping, Optional, Sequence, Union

from robodesign.viewer.html import render_html
from robodesign.viewer.plots import trajectory_plots
from robodesign.viewer.scene import build_scene

__all__ = ["build_scene", "render_html", "trajectory_plots", "solution_page", "collab_page", "task_page", "robot_page"]


def _verdict_json(verdict):
    if verdict is None:
        return None
    return verdict.to_json() if hasattr(verdict, "to_json") else dict(verdict)


def solution_page(task, solution, module_set=None, *, verdict=None, plots: Union[bool, Mapping] = True,
                  fps: float = 25.0, include_collision: bool = False, title: Optional[str] = None) -> str:
    """The page of a solution: workcell, goals, robot, animation and plots.

    ``task``: a Task or None. ``module_set``: a ModuleSet, a built-in name or folder, or None for the
    solution's ``moduleSet``. ``verdict``: a checker Verdict (or its ``to_json()``) to list on the page.
    ``plots``: True (compute them), False, or a ready ``{name: png bytes}``. A solution whose robot cannot
    be built (bad assembly, wrong number of joints, unknown module set) still gives a page: the task
    alone with the reason as a note.
    """
    from robodesign.core.errors import RobodesignError
    from robodesign.model.cell import resolve_module_set
    from robodesign.model.robot import Robot

    info = {"solution": solution.source or "", "cost_function": solution.cost_function}
    if solution.cost is not None:
        info["cost"] = float(solution.cost)
    v = _verdict_json(verdict)
    if v is not None:
        info["verdict"] = v
    notes = []
    robot = None
    try:
        ms = resolve_module_set(solution, module_set)
        gravity = task.header.gravity if task is not None else (0.0, 0.0, -9.81)
        robot = Robot(ms, solution.assembly(ms), base_pose=solution.base_pose, gravity=gravity)
        if solution.trajectory.q.shape[1] != robot.dof:
            notes.append(f"the trajectory has {solution.trajectory.q.shape[1]} joint columns but the robot has "
                         f"{robot.dof} joints: the robot is not shown")
            robot = None
    except RobodesignError as e:
        notes.append(f"the robot cannot be built: {e}")
        robot = None
    if task is not None and solution.task_id != task.id:
        notes.append(f"the solution is for task {solution.task_id!r}, shown in task {task.id!r}")
    scene = build_scene(task, robot, solution.trajectory if robot is not None else None, fps=fps,
                        include_collision=include_collision, info=info)
    scene["messages"].extend(notes)
    images = None
    if robot is not None:
        if isinstance(plots, Mapping):
            images = dict(plots)
        elif plots:
            try:
                images = trajectory_plots(task, solution, ms)
            except Exception as e:  # plots are an extra: never lose the page for them
                scene["messages"].append(f"plots failed: {e}")
    name = task.id if task is not None else solution.task_id
    return render_html(scene, images, title or f"{name}: {','.join(solution.module_order)}")


def collab_page(ctask, csol, module_sets=None, *, verdict=None, fps: float = 25.0, include_collision: bool = False,
                title: Optional[str] = None) -> str:
    """The page of a collaborative solution (docs/collaborative.md): every robot in the shared cell,
    animated together with the moving obstacles on the common time base. ``module_sets``: one module set
    for every robot, a dict robot ID → module set, or None (each robot's ``moduleSet``)."""
    from types import SimpleNamespace

    from robodesign.collab.core import robot_module_set
    from robodesign.model.cell import build_robot, resolve_module_set
    robots = []
    for rid, sol in csol.robots:
        ms = resolve_module_set(sol, robot_module_set(module_sets, rid))
        robots.append((rid, build_robot(ctask.robot_tasks.get(rid, ctask.task), ms, sol.assembly(ms), sol.base_pose),
                       sol.trajectory))
    g2t = {}
    for _, _, tr in robots:
        g2t.update(tr.goal2time)
    first = robots[0]
    tr0 = SimpleNamespace(t=first[2].t, q=first[2].q, goal2time=g2t)
    info = {"solution": csol.source or "", "robots": [rid for rid, _, _ in robots],
            "cost_function": ", ".join(csol.cost_functions)}
    v = _verdict_json(verdict)
    if v is not None:
        info["verdict"] = v
    scene = build_scene(ctask.task, first[1], tr0, fps=fps, include_collision=include_collision, info=info,
                        others=[(rid, r, tr) for rid, r, tr in robots[1:]])
    return render_html(scene, None, title or f"{ctask.id}: {', '.join(rid for rid, _, _ in robots)}")


def task_page(task, *, include_collision: bool = False, title: Optional[str] = None) -> str:
    """The page of a task alone: workcell, goals with their tolerances, base placement."""
    scene = build_scene(task, None, None, include_collision=include_collision)
    return render_html(scene, None, title or f"task {task.id}")


def robot_page(robot, q: Optional[Sequence[float]] = None, task=None, *, include_collision: bool = False,
               title: Optional[str] = None) -> str:
    """The page of a static robot (at ``q``, default zeros), optionally in a task's cell."""
    scene = build_scene(task, robot, None, q=q, include_collision=include_collision)
    return render_html(scene, None, title or f"robot {','.join(robot.assembly.module_ids)}")
