"""whitman2020: full-pose reach goals among random 0.25 m cubes (after Whitman, Bhirangi, Travers, Choset 2020,
"Modular Robot Design Synthesis with Deep Reinforcement Learning", as packaged by CoBRA:
``Whitman2020/with_torque/...``, 3 goals / 3 cubes and 5 goals / 5 cubes, base fixed or free).

``--variant published`` (default) follows the published task files (docs/generators.md, table): goal
positions uniform in [-1, 1] × [-1, 1] × [-1, 0.8] m around the nominal base (56 % below the base plane), goal
orientations uniform on SO(3), tolerance x, y, z ± 1 mm and ``Theta_R`` ≤ 0.5° (the reference's default,
written as the published files write it); cube centres uniform in [-0.8, 0.8]³ m; constraints ``joint``
q, tau, collisionFree, allGoalsFulfilled (no selfCollisionFree, no dq); base ``fixed`` (± 1 mm, 0.5°) or
``xyz_any_rot`` (x, y, z ± ``--base-range``, rotation free). A task is kept when every goal lies outside
every cube and within the reach bound of the reference module set from some allowed base position
(common.set_reach_bound: a geometric bound on every design of the set, never a solve); a cell that fails
is redrawn. Draw order: cubes (each redrawn until it keeps clear of the nominal base and the other cubes),
then every goal (position, then rotation).

``--variant easy`` is the earlier variant (version 3): ± 5 mm, orientation free, goals in an annulus above
the floor, each checked by IK of the robodesign_arm reference design, the whole task by a solve of it
(``--verify``).
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Dict, List

import numpy as np

from robodesign.core.errors import InputError, RobodesignError
from robodesign.generate.common import (
    AABB,
    HALF_DEGREE,
    MM,
    PI,
    Provenance,
    ReferenceArm,
    full_pose,
    header,
    outside_and_in_reach,
    random_rotation,
    set_reach_bound,
    tolerated,
    transform,
    verified,
)
from robodesign.generate.family import VARIANT, VERIFY, Family, GeneratedTask, Option

VERSION = 4  # 4: the published variant (default); 3: what is now --variant easy
WORKSPACE = 1.0  # m: goals are uniform in x, y ∈ [-WORKSPACE, WORKSPACE] about the nominal base ...
GOAL_TOP = 0.8  # m: ... and z ∈ [-WORKSPACE, GOAL_TOP] (56 % below the base plane, published 51-67 %)
CUBE_REGION = 0.8  # m: cube centres uniform in [-CUBE_REGION, CUBE_REGION]³ (matches the published goal clearance)
BASE_KEEPOUT = 0.10  # m: a cube keeps this distance from the nominal base position (the base module stands there)
PUBLISHED_CELL_TRIES = 200
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


def _cell(task_id: str, prov: Provenance, opts: Dict[str, Any], cubes: List[AABB], goals: List[np.ndarray]) -> dict:
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


def task_id(prov: Provenance, opts: Dict[str, Any]) -> str:
    name = "whitman2020easy" if opts.get("variant") == "easy" else "whitman2020"
    return f"{name}_g{opts['goals']}o{opts['obstacles']}_{opts['base']}_s{prov.seed}_{prov.index:04d}"


def build_easy(prov: Provenance, opts: Dict[str, Any], folder: Path) -> GeneratedTask:
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


# ---------------------------------------------------------------------------------------------------------
# the published variant
def published_base_constraint(base: str, base_range: float) -> dict:
    """Fixed: ± 1 mm and 0.5° about the origin; xyz_any_rot: x, y, z ± base_range, no rotation projection
    (any rotation, as in the published files)."""
    if base == "fixed":
        t = (-MM, MM)
        return {"type": "basePlacement", "pose": tolerated(transform(), x=t, y=t, z=t, Theta_R=(0.0, HALF_DEGREE))}
    r = (-base_range, base_range)
    return {"type": "basePlacement", "pose": tolerated(transform(), x=r, y=r, z=r)}


def _published_cell(task_id: str, prov: Provenance, opts: Dict[str, Any], cubes: List[AABB],
                    goals: List[np.ndarray]) -> dict:
    n, m = opts["goals"], opts["obstacles"]
    return {
        "header": header(task_id, f"Whitman 2020: {n} full-pose reach goals, {m} cubes of 0.25 m, base {opts['base']}",
                         prov, ["Whitman 2020", f"{n} goals", f"{m} obstacles", "static torque",
                                f"base_{opts['base']}"]),
        "obstacles": [{"ID": f"box_{k}", "name": f"box {k}", "collision": [c.geometry()]} for k, c in enumerate(cubes)],
        "constraints": [
            published_base_constraint(str(opts["base"]), float(opts["base_range"])),
            {"type": "joint", "parts": ["q", "tau"]},
            {"type": "collisionFree"},
            {"type": "allGoalsFulfilled"},
        ],
        "goals": [{"ID": f"goal_{k}", "type": "reach", "goalPose": full_pose(T)} for k, T in enumerate(goals)],
    }


def _published_cubes(rng: np.random.Generator, m: int) -> List[AABB]:
    cubes: List[AABB] = []
    for _ in range(1000 * (m + 1)):
        if len(cubes) == m:
            break
        c = AABB.cube(rng.uniform(-CUBE_REGION, CUBE_REGION, 3), CUBE)
        if c.distance(np.zeros(3)) < BASE_KEEPOUT or any(c.overlaps(o) for o in cubes):
            continue
        cubes.append(c)
    if len(cubes) < m:
        raise InputError(f"whitman2020: {m} cubes of {CUBE} m do not fit into the workspace")
    return cubes


def base_region(opts: Dict[str, Any]):
    """(lo, hi) of the allowed base positions."""
    r = MM if opts["base"] == "fixed" else float(opts["base_range"])
    return np.full(3, -r), np.full(3, r)


def build_published(prov: Provenance, opts: Dict[str, Any], folder: Path) -> GeneratedTask:
    rng = prov.rng()
    tid = task_id(prov, opts)
    n, m = int(opts["goals"]), int(opts["obstacles"])
    reach = set_reach_bound()
    lo, hi = base_region(opts)
    for _ in range(PUBLISHED_CELL_TRIES):
        cubes = _published_cubes(rng, m)
        goals = []
        for _ in range(n):
            T = transform(rng.uniform([-WORKSPACE, -WORKSPACE, -WORKSPACE], [WORKSPACE, WORKSPACE, GOAL_TOP]))
            T[:3, :3] = random_rotation(rng)
            goals.append(T)
        if outside_and_in_reach(goals, cubes, lo, hi, reach):
            return GeneratedTask(tid, _published_cell(tid, prov, opts, cubes, goals))
    raise RobodesignError(f"whitman2020: no cell with {n} goals outside {m} cubes in {PUBLISHED_CELL_TRIES} draws "
                          f"(seed {prov.seed}, index {prov.index})")


def build(prov: Provenance, opts: Dict[str, Any], folder: Path) -> GeneratedTask:
    return build_easy(prov, opts, folder) if opts["variant"] == "easy" else build_published(prov, opts, folder)


FAMILY = Family(
    name="whitman2020",
    version=VERSION,
    summary="N full-pose reach goals (±1 mm, 0.5°) among M axis-aligned 0.25 m cubes within 1 m of the base; base fixed "
            "or free (--variant easy: ±5 mm, orientation free, goals checked by the reference design)",
    options=(
        VARIANT,
        Option("goals", int, 3, "number of reach goals (published: 3 or 5)", minimum=1),
        Option("obstacles", int, 3, "number of 0.25 m cube obstacles (published: 3 or 5)", minimum=0),
        Option("base", str, "fixed", "fixed: base at the origin; xyz_any_rot: base free in x, y, z and rotation",
               choices=("fixed", "xyz_any_rot")),
        Option("base_range", float, 1.0, "with --base xyz_any_rot: the base may move ± this many metres in x, y, z "
                                         "(published: 1)",
               minimum=0.0),
        VERIFY,
    ),
    build=build,
)
