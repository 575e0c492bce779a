"""Trajectory plots (matplotlib, Agg, no pyplot state): q, dq, ddq, τ per joint with limits; TCP path.

:func:`trajectory_plots` returns ``{"q", "dq", "ddq", "tau", "tcp"}`` → PNG bytes. The joint plots have
one panel per joint with the limits as dashed lines (q: [lower, upper]; dq, ddq, τ: ± limit; infinite
limits are not drawn) and the goal instants as dotted vertical lines. τ is the checker's drivetrain
torque (RNEA under the task's gravity + reflected motor inertia + friction, with follow-goal wrenches).
The TCP plot shows the path in the x-y (top) and x-z (side) planes with the goal positions.
"""
from __future__ import annotations

import io
import math
from pathlib import Path
from typing import Dict, Optional, Union

import numpy as np

PLOT_NAMES = ("q", "dq", "ddq", "tau", "tcp")
DPI = 80


def _figure(w: float, h: float):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    fig = Figure(figsize=(w, h), dpi=DPI)
    FigureCanvasAgg(fig)
    return fig


def _png(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI)
    return buf.getvalue()


def _joint_figure(t, Y, lower, upper, title, units, names, goal_times):
    from matplotlib.ticker import MaxNLocator
    n = Y.shape[1]
    cols = 2 if n > 3 else 1
    rows = int(math.ceil(n / cols))
    fig = _figure(9.0, 1.0 + 1.55 * rows)
    axes = fig.subplots(rows, cols, sharex=True, squeeze=False)
    for j in range(rows * cols):
        ax = axes[j // cols][j % cols]
        if j >= n:
            ax.set_visible(False)
            continue
        ax.plot(t, Y[:, j], color="#1f77b4", lw=1.3)
        for b in (lower[j], upper[j]):
            if math.isfinite(b):
                ax.axhline(b, color="#d62728", ls="--", lw=1.0)
        for gid, tg in goal_times.items():
            ax.axvline(tg, color="#7f7f7f", ls=":", lw=0.9)
        ax.set_ylabel(f"{j + 1}: {names[j]} [{units[j]}]", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.yaxis.set_major_locator(MaxNLocator(4))
        ax.xaxis.set_major_locator(MaxNLocator(6))
        ax.grid(alpha=0.3)
        if j // cols == rows - 1 or j + cols >= n:
            ax.set_xlabel("t [s]", fontsize=8)
    fig.suptitle(title, fontsize=10)
    # fixed margins (tight_layout costs ~0.3 s per figure)
    h = fig.get_figheight()
    fig.subplots_adjust(left=0.08, right=0.985, bottom=0.45 / h, top=1 - 0.45 / h, wspace=0.22, hspace=0.12)
    return _png(fig)


def _tcp_figure(P, goals, goal_times, t):
    fig = _figure(9.0, 4.2)
    axes = fig.subplots(1, 2)
    for ax, (a, b), lab in zip(axes, ((0, 1), (0, 2)), (("x", "y"), ("x", "z"))):
        ax.plot(P[:, a], P[:, b], color="#ff7f0e", lw=1.5, label="TCP path")
        ax.plot(P[0, a], P[0, b], "o", color="#2ca02c", ms=6, label="start")
        ax.plot(P[-1, a], P[-1, b], "s", color="#d62728", ms=6, label="end")
        for gid, pos in goals:
            ax.plot(pos[a], pos[b], "x", color="#1f1f1f", ms=8, mew=2)
            ax.annotate(gid, (pos[a], pos[b]), textcoords="offset points", xytext=(4, 4), fontsize=8)
        ax.set_xlabel(f"{lab[0]} [m]", fontsize=8)
        ax.set_ylabel(f"{lab[1]} [m]", fontsize=8)
        ax.set_aspect("equal", adjustable="datalim")
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
        ax.set_title("top view (x-y)" if b == 1 else "side view (x-z)", fontsize=9)
    axes[0].legend(fontsize=7, loc="best")
    fig.suptitle("End-effector path (goal positions ×)", fontsize=10)
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.12, top=0.86, wspace=0.25)
    return _png(fig)


def trajectory_plots(task, solution, module_set, out_dir: Optional[Union[str, Path]] = None,
                     stem: str = "trajectory") -> Dict[str, bytes]:
    """PNG plots of a solution's trajectory (see the module docstring).

    ``task`` may be None (default gravity, no goals); ``module_set`` is a ModuleSet, a name/folder, or
    None for the solution's ``moduleSet``. With ``out_dir`` the images are also written there as
    ``<stem>_<name>.png``.
    """
    from robodesign.judge.quantities import TrajectoryQuantities
    from robodesign.model.cell import resolve_module_set
    from robodesign.model.robot import Robot

    ms = resolve_module_set(solution, module_set)
    gravity = task.header.gravity if task is not None else (0.0, 0.0, -9.81)
    robot = Robot(ms, solution.assembly(ms), base_pose=solution.base_pose, gravity=gravity)
    tr = solution.trajectory
    t = np.asarray(tr.t, dtype=float)
    if tr.q.shape[1] != robot.dof:
        raise ValueError(f"trajectory has {tr.q.shape[1]} joint columns, the robot {robot.dof} joints")
    g2t = {str(k): float(v) for k, v in (tr.goal2time or {}).items()}
    # drivetrain torque as the checker computes it (follow goals add their wrench in their window)
    tq = TrajectoryQuantities.from_solution(robot, solution, task)
    tau = tq.torques

    names = [j.name for j in robot.joint_infos]
    lin = [j.type == "prismatic" for j in robot.joint_infos]
    u = lambda rot, pri: [pri if p else rot for p in lin]  # noqa: E731
    out: Dict[str, bytes] = {}
    out["q"] = _joint_figure(t, tr.q, robot.q_lower, robot.q_upper, "Joint positions q", u("rad", "m"), names, g2t)
    out["dq"] = _joint_figure(t, tr.dq, -robot.dq_max, robot.dq_max, "Joint velocities dq", u("rad/s", "m/s"),
                              names, g2t)
    out["ddq"] = _joint_figure(t, tr.ddq, -robot.ddq_max, robot.ddq_max, "Joint accelerations ddq",
                               u("rad/s²", "m/s²"), names, g2t)
    out["tau"] = _joint_figure(t, tau, -robot.tau_max, robot.tau_max, "Drivetrain torques τ", u("Nm", "N"), names, g2t)

    P = tq.tcp_poses[:, :3, 3]
    goals = []
    if task is not None:
        for g in task.goals:
            pose = g.anchor
            if pose is not None:
                goals.append((g.id, pose.nominal[:3, 3]))
    merged: list = []  # goals at the same place get one label ("1, 3")
    for gid, pos in goals:
        for m in merged:
            if np.linalg.norm(m[1] - pos) < 1e-6:
                m[0] += f", {gid}"
                break
        else:
            merged.append([gid, np.asarray(pos, float)])
    out["tcp"] = _tcp_figure(P, merged, g2t, t)

    if out_dir is not None:
        d = Path(out_dir)
        d.mkdir(parents=True, exist_ok=True)
        for name, png in out.items():
            (d / f"{stem}_{name}.png").write_bytes(png)
    return out
