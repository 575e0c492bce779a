"""What ``robodesign view`` does: its options (added to :mod:`robodesign.cli.entry`'s parser) and the page."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Dict, List, Optional, Tuple, Union

import numpy as np

from robodesign.core.errors import InputError


def _note(msg: str) -> None:
    print(f"robodesign: note: {msg}", file=sys.stderr)


def add_view_arguments(vw: argparse.ArgumentParser) -> None:
    """The options of ``robodesign view``; docs/viewer.md has the same table."""
    vw.add_argument("solution", nargs="?", help="a CoBRA solution file; omit it to show --task and/or a robot")
    vw.add_argument("--task", help="task file or built-in task (default for a solution: its taskID if that names a "
                                   "built-in task; otherwise the robot is shown without a cell and a note says so)")
    vw.add_argument("--modules", help="module set folder or built-in name (default: the solution's moduleSet)")
    vw.add_argument("--order", help="without a solution: comma-separated module IDs of a static robot")
    vw.add_argument("--q", help="with --order: joint values (comma-separated); default zeros")
    vw.add_argument("--base-pose", help="with --order: x,y,z[,roll,pitch,yaw] or 16 numbers (default: the "
                                        "task's nominal base placement, else identity)")
    vw.add_argument("--out", help="HTML file to write (default: <solution stem>_view.html, or view.html); with "
                                  "--out the plots are also written next to it as <stem>_q.png, _dq, _ddq, _tau, _tcp")
    vw.add_argument("--check", action="store_true", help="also run the checker and show the verdict on the page "
                                                         "(exit 1 if the solution is invalid)")
    vw.add_argument("--no-plots", action="store_true", help="no trajectory plots (faster: matplotlib takes 1-3 s)")
    vw.add_argument("--collision", action="store_true", help="also embed the collision geometry (a check box on "
                                                             "the page shows it)")
    vw.add_argument("--fps", type=float, default=25.0, help="animation frames per second at most (default 25; "
                                                            "goal instants are always kept)")


def run_view(solution: Optional[str] = None, task: Optional[str] = None, modules: Optional[str] = None,
             order: Optional[str] = None, q: Optional[str] = None, base_pose: Optional[str] = None,
             out: Optional[str] = None, check: bool = False, plots: bool = True, collision: bool = False,
             fps: float = 25.0) -> Tuple[Path, List[str]]:
    """Write the page; returns its path and warnings that make the command exit 1: a solution shown in
    a task that is not its own, or (with ``check``) an invalid solution. See docs/viewer.md."""
    from robodesign.formats.task_io import load_task

    if fps <= 0:
        raise InputError("--fps must be positive")
    if solution is None and task is None and order is None:
        raise InputError("give a SOLUTION file, --task, or --modules with --order")
    if solution is not None and order is not None:
        raise InputError("--order is for a bare robot; a solution brings its own module order")
    task_obj = load_task(task) if task else None
    for w in (task_obj.warnings if task_obj is not None else ()):
        _note(w)

    warnings: List[str] = []
    if solution is not None:
        from robodesign.collab.core import is_collaborative
        from robodesign.core.jsonio import load_json
        data = load_json(solution, display_name=Path(solution).name)
        if is_collaborative(data):  # several robots in one cell (docs/collaborative.md)
            return _view_collab(solution, data, task, modules, out, check, fps, collision)
    if solution is not None:
        path, page = _solution_page(solution, task_obj, modules, out, check, plots, collision, fps, warnings)
    else:
        path, page = _robot_page(task_obj, modules, order, q, base_pose, out, collision)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(page, encoding="utf-8")
    return path, warnings


def _solution_page(solution: str, task_obj, modules: Optional[str], out: Optional[str], check: bool, plots: bool,
                   collision: bool, fps: float, warnings: List[str]) -> Tuple[Path, str]:
    """The page of a (single-robot) solution, in its task's cell when the task is found; appends to ``warnings``
    what makes the command exit 1. → (where to write it, the page)."""
    from robodesign.cli.args import module_set_for_solution
    from robodesign.formats.solution import load_solution
    from robodesign.formats.task_io import load_task
    from robodesign.viewer import solution_page
    from robodesign.viewer.plots import trajectory_plots
    sol = load_solution(solution)
    if task_obj is None:
        try:
            task_obj = load_task(sol.task_id)
        except InputError:
            _note(f"task {sol.task_id!r} not found; showing the robot without its cell (use --task)")
    if task_obj is not None and sol.task_id != task_obj.id:
        warnings.append(f"the solution is for task {sol.task_id!r}, not {task_obj.id!r}: the page shows it in "
                        f"a cell it was not planned for")
    ms = module_set_for_solution(sol, modules)
    path = Path(out) if out else Path(Path(solution).stem + "_view.html")
    verdict = None
    if check:
        if task_obj is None:
            _note("--check needs the task; skipped")
        else:
            from robodesign.judge.checker import check as run_check
            verdict = run_check(task_obj, sol, ms)
            if not verdict.valid:
                warnings.append(f"the checker finds the solution INVALID ({len(verdict.violations)} "
                                "violation(s), listed on the page)")
    images: Union[bool, Dict[str, bytes]] = False
    if plots:
        try:
            images = trajectory_plots(task_obj, sol, ms, out_dir=path.parent if out else None, stem=path.stem)
        except Exception as e:  # the page still shows the motion
            _note(f"plots failed: {e}")
    page = solution_page(task_obj, sol, ms, verdict=verdict, plots=images, fps=fps, include_collision=collision)
    return path, page


def _robot_page(task_obj, modules: Optional[str], order: Optional[str], q: Optional[str], base_pose: Optional[str],
                out: Optional[str], collision: bool) -> Tuple[Path, str]:
    """The page of a bare robot (``--modules`` with ``--order``, at ``--q``) or of a task's cell alone. → (where
    to write it, the page)."""
    from robodesign.viewer import render_html
    from robodesign.viewer.scene import build_scene
    robot = None
    if order is not None:
        from robodesign.cli.args import parse_base_pose, parse_order
        from robodesign.formats.module_io import load_module_set
        from robodesign.model.robot import Robot
        if not modules:
            raise InputError("--order needs --modules")
        ms = load_module_set(modules)
        bp = parse_base_pose(base_pose) if base_pose else (
            task_obj.nominal_base_pose if task_obj is not None else None)
        robot = Robot.from_order(ms, parse_order(order), base_pose=bp)
    qv = None
    if q is not None:
        if robot is None:
            raise InputError("--q needs --modules and --order")
        from robodesign.cli.args import parse_floats
        qv = np.array(parse_floats(q, "--q"), dtype=float)
        if len(qv) != robot.dof:
            raise InputError(f"--q: the robot has {robot.dof} joints, got {len(qv)} values")
    scene = build_scene(task_obj, robot, None, q=qv, include_collision=collision)
    if robot is not None:
        name = "robot " + ",".join(robot.assembly.module_ids) + (f" in {task_obj.id}" if task_obj else "")
    else:
        assert task_obj is not None  # neither a solution nor --order: --task (checked above)
        name = f"task {task_obj.id}"
    path = Path(out) if out else Path("view.html")
    page = render_html(scene, None, name)
    return path, page


def _view_collab(solution: str, data, task: Optional[str], modules: Optional[str], out: Optional[str], check: bool,
                 fps: float, collision: bool) -> Tuple[Path, List[str]]:
    """The page of a collaborative solution: every robot and the moving obstacles animate together."""
    from robodesign.cli.args import module_set_for_solution
    from robodesign.cli.collab import load_collab_task_file
    from robodesign.collab.core import check_collab, parse_collab_solution
    from robodesign.viewer import collab_page
    csol = parse_collab_solution(data, Path(solution).name, source=str(solution))
    ctask = load_collab_task_file(task or csol.task_id)
    if ctask is None:
        raise InputError("the solution is collaborative but the task is not: give the collaborative task (--task)")
    warnings: List[str] = []
    if csol.task_id != ctask.id:
        warnings.append(f"the solution is for task {csol.task_id!r}, not {ctask.id!r}: the page shows it in a cell "
                        "it was not planned for")
    sets = {rid: module_set_for_solution(s, modules) for rid, s in csol.robots}
    verdict = None
    if check:
        verdict = check_collab(ctask, csol, sets)
        if not verdict.valid:
            warnings.append(f"the checker finds the solution INVALID ({len(verdict.violations)} violation(s), "
                            "listed on the page)")
    path = Path(out) if out else Path(Path(solution).stem + "_view.html")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(collab_page(ctask, csol, sets, verdict=verdict, fps=fps, include_collision=collision),
                    encoding="utf-8")
    return path, warnings


def describe(path: Path) -> str:
    from robodesign.viewer.html import decode_page_data
    page = path.read_text(encoding="utf-8")
    data = decode_page_data(page)
    anim = data.get("animation")
    parts = [f"{len(page) / 1e6:.2f} MB", f"{len(data.get('meshes') or {})} meshes"]
    if anim:
        parts.append(f"{anim['shape'][0]} frames × {anim['shape'][1]} moving parts")
    return f"wrote {path} ({', '.join(parts)})"
