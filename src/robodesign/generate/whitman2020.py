"""whitman2020: reach goals among random box obstacles (after Whitman, Bhirangi, Travers, Choset 2020,
"Modular Robot Design Synthesis with Deep Reinforcement Learning", as packaged by CoBRA).

A cell of ``--obstacles`` axis-aligned 0.25 m cubes and ``--goals`` position goals (±5 mm in x, y, z,
orientation free) around a robot base at the world origin. ``--base fixed`` bolts the base to the origin;
``--base xyz_any_rot`` lets it move ±``--base-range`` m in x, y, z with any rotation.

Draw order (one random stream per task): obstacles first (each redrawn until it keeps clear of the base
column and of the other cubes), then goals one at a time. A goal is redrawn until it is at least
``GOAL_CLEARANCE`` from every cube, ``GOAL_SPACING`` from the other goals, and the reference arm
(robodesign_arm, default order, base at the origin) has a collision-free IK solution for it that holds
it within its torque limits. When a goal cannot be placed in ``GOAL_TRIES`` draws the cell is redrawn.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Dict, List

import numpy as np

from robodesign.core.errors import InputError, RobodesignError
from robodesign.generate.common import AABB, PI, Provenance, ReferenceArm, header, tolerated, transform, verified
from robodesign.generate.registry import VERIFY, Family, GeneratedTask, Option

VERSION = 3
CUBE = 0.25  # m, obstacle edge
POS_TOL = 0.005  # m, goal tolerance in x, y, z
GOAL_R = (0.30, 0.90)  # m, horizontal distance of a goal from the base axis
GOAL_Z = (0.05, 1.00)  # m, goal height
CUBE_R = (0.30, 1.00)  # m, horizontal distance of a cube centre from the base axis
CUBE_Z = (0.125, 1.00)  # m, cube centre height (the lowest cubes stand on the floor)
BASE_COLUMN = 0.20  # m, cubes keep this horizontal distance from the base axis (the robot's base and shoulder)
GOAL_CLEARANCE = 0.06  # m, goal point to cube surface
GOAL_SPACING = 0.15  # m, between goals
GOAL_TRIES = 150
CELL_TRIES = 50


def _polar(rng: np.random.Generator, r_range, z_range) -> np.ndarray:
    """A point uniform in area over the annulus r_range (horizontal) times z_range."""
    r = math.sqrt(rng.uniform(r_range[0] ** 2, r_range[1] ** 2))
    phi = rng.uniform(-PI, PI)
    return np.array([r * math.cos(phi), r * math.sin(phi), rng.uniform(*z_range)])


def _draw_cubes(rng: np.random.Generator, m: int) -> List[AABB]:
    cubes: List[AABB] = []
    for _ in range(1000 * (m + 1)):
        if len(cubes) == m:
            break
        c = AABB.cube(_polar(rng, CUBE_R, CUBE_Z), CUBE)
        column = AABB((-BASE_COLUMN, -BASE_COLUMN, -1.0), (BASE_COLUMN, BASE_COLUMN, 2.0))
        if c.overlaps(column) or any(c.overlaps(o) for o in cubes):
            continue
        cubes.append(c)
    if len(cubes) < m:
        raise InputError(f"whitman2020: {m} cubes of {CUBE} m do not fit into the workspace")
    return cubes


def goal_pose(p) -> dict:
    tol = (-POS_TOL, POS_TOL)
    return tolerated(transform(p), x=tol, y=tol, z=tol)


def base_constraint(base: str, base_range: float) -> dict:
    if base == "fixed":
        return {"type": "basePlacement", "pose": tolerated(transform(), x=(-0.001, 0.001), y=(-0.001, 0.001),
                                                           z=(-0.001, 0.001), Theta_R=(0.0, 0.01))}
    r = (-base_range, base_range)
    return {"type": "basePlacement", "pose": tolerated(transform(), x=r, y=r, z=r, Theta_R=(0.0, PI))}


def _cell(task_id: str, prov: Provenance, opts: Dict[str, object], cubes: List[AABB], goals: List[np.ndarray]) -> dict:
    n, m = opts["goals"], opts["obstacles"]
    return {
        "header": header(task_id, f"Whitman 2020 style: {n} reach goals, {m} box obstacles, base {opts['base']}",
                         prov, ["reach", f"base_{opts['base']}"]),
        "obstacles": [{"ID": f"box_{k}", "name": f"box {k}", "collision": [c.geometry()]} for k, c in enumerate(cubes)],
        "constraints": [
            base_constraint(str(opts["base"]), float(opts["base_range"])),
            {"type": "joint", "parts": ["q", "dq", "tau"]},
            {"type": "selfCollisionFree"},
            {"type": "collisionFree"},
            {"type": "allGoalsFulfilled"},
        ],
        "goals": [{"ID": f"goal_{k}", "type": "reach", "goalPose": goal_pose(p)} for k, p in enumerate(goals)],
    }


def task_id(prov: Provenance, opts: Dict[str, object]) -> str:
    return f"whitman2020_g{opts['goals']}o{opts['obstacles']}_{opts['base']}_s{prov.seed}_{prov.index:04d}"


def build(prov: Provenance, opts: Dict[str, object], folder: Path) -> GeneratedTask:
    rng = prov.rng()
    tid = task_id(prov, opts)
    n, m = int(opts["goals"]), int(opts["obstacles"])
    for _ in range(CELL_TRIES):
        cubes = _draw_cubes(rng, m)
        arm = ReferenceArm(_cell(tid, prov, opts, cubes, []), folder, seed=int(rng.integers(2 ** 31)))
        goals: List[np.ndarray] = []
        for _ in range(GOAL_TRIES):
            if len(goals) == n:
                break
            p = _polar(rng, GOAL_R, GOAL_Z)
            if any(c.distance(p) < GOAL_CLEARANCE for c in cubes):
                continue
            if any(np.linalg.norm(p - g) < GOAL_SPACING for g in goals):
                continue
            if arm.reaches(goal_pose(p)):
                goals.append(p)
        if len(goals) < n:
            continue
        task = _cell(tid, prov, opts, cubes, goals)
        if verified(task, opts, folder, np.eye(4)):
            return GeneratedTask(tid, task)
    raise RobodesignError(f"whitman2020: no cell with {n} reachable goals among {m} cubes in {CELL_TRIES} draws "
                          f"(seed {prov.seed}, index {prov.index})")


FAMILY = Family(
    name="whitman2020",
    version=VERSION,
    summary="N reach goals (±5 mm, orientation free) among M axis-aligned 0.25 m cubes; base fixed or free",
    options=(
        Option("goals", int, 3, "number of reach goals (published: 3 or 5)", minimum=1),
        Option("obstacles", int, 3, "number of 0.25 m cube obstacles (published: 3 or 5)", minimum=0),
        Option("base", str, "fixed", "fixed: base at the origin; xyz_any_rot: base free in x, y, z and rotation",
               choices=("fixed", "xyz_any_rot")),
        Option("base_range", float, 1.0, "with --base xyz_any_rot: the base may move ± this many metres in x, y, z",
               minimum=0.0),
        VERIFY,
    ),
    build=build,
)
