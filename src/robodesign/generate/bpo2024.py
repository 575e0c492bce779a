"""bpo2024: "edge-case" cells after Mayer and Althoff (2024), "Decreasing Robotic Cycle Time via Base-Pose
Optimization": named structures of 0.25 m cubes with three reach goals in their hard-to-reach spots; the
base is free within ±1 m in x, y, z with any rotation.

A structure is a set of cells of a voxel grid (edge ``CUBE``) in its own frame: i along the depth (away
from the robot), j sideways (centred), k up. Its spots are the empty cells next to it, scored by how
enclosed they are (filled face neighbours + half the filled edge neighbours). ``--difficulty`` picks the
spots: easy any spot with a score ≥ 1, medium the more enclosed half, hard the most enclosed quarter; the
clearance of a goal from the cubes shrinks from 8 to 6 to 4 cm. The structure stands 0.35–0.55 m in front
of the nominal base (the origin), turned about the vertical axis by a random angle.

A goal is a random point in a spot cell (kept ``clearance`` inside it) that the reference arm reaches
from the nominal base (common.ReferenceArm); three goals in three different cells.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Callable, Dict, FrozenSet, List, Set, Tuple

import numpy as np

from robodesign.core.errors import RobodesignError
from robodesign.core.spatial import rot_z
from robodesign.generate.common import (
    AABB,
    PI,
    Provenance,
    ReferenceArm,
    full_pose,
    header,
    outside_and_in_reach,
    set_reach_bound,
    tolerated,
    transform,
    verified,
)
from robodesign.generate.family import VARIANT, VERIFY, Family, GeneratedTask, Option

VERSION = 3  # 3: the published edge cases (default); 2: what is now --variant easy
PUBLISHED_CELL_TRIES = 200
CUBE = 0.25
N_GOALS = 3
POS_TOL = 0.005
DISTANCE = (0.35, 0.55)  # m, nominal base to the structure's front face
BASE_RANGE = 1.0
CLEARANCE = {"easy": 0.08, "medium": 0.06, "hard": 0.04}
SPOT_SHARE = {"easy": 1.0, "medium": 0.5, "hard": 0.25}  # the most enclosed share of the spots
RANDOM_CUBES = {"easy": 6, "medium": 10, "hard": 14}
DIFFICULTIES = ("easy", "medium", "hard")
GOAL_TRIES = 200
CELL_TRIES = 30

Cell = Tuple[int, int, int]


def _x(rng, difficulty) -> Set[Cell]:
    """An upright X (5 × 5 cubes, one deep), facing the robot."""
    return {(0, j - 2, k) for k in range(5) for j in range(5) if j == k or j == 4 - k}


def _cross(rng, difficulty) -> Set[Cell]:
    """An upright plus sign (5 × 5 cubes, one deep) on a one-cube plinth."""
    return {(0, j - 2, k + 1) for k in range(5) for j in range(5) if j == 2 or k == 2} | {(0, 0, 0)}


def _house(rng, difficulty) -> Set[Cell]:
    """Four walls (4 deep × 5 wide × 3 high) with a door in the front wall, a flat roof and a ridge."""
    cells = set()
    for i in range(4):
        for j in range(-2, 3):
            for k in range(3):
                wall = i in (0, 3) or abs(j) == 2
                door = i == 0 and j == 0 and k < 2
                if wall and not door:
                    cells.add((i, j, k))
            cells.add((i, j, 3))  # roof
            if abs(j) < 1:
                cells.add((i, j, 4))  # ridge
    return cells


def _oven(rng, difficulty) -> Set[Cell]:
    """A box (3 deep × 4 wide × 4 high) on two pillars, with a 2 × 2 × 2 cavity open to the robot."""
    cells = set()
    for i in range(3):
        for j in range(-2, 2):
            for k in range(2, 6):
                cavity = i < 2 and j in (-1, 0) and k in (3, 4)
                if not cavity:
                    cells.add((i, j, k))
    cells |= {(1, -2, 0), (1, -2, 1), (1, 1, 0), (1, 1, 1)}
    return cells


def _random_field(rng, difficulty) -> Set[Cell]:
    """Random stacks on a 5 × 6 floor grid: each new cube on the floor or on top of another (≤ 4 high)."""
    cells: Set[Cell] = set()
    n = RANDOM_CUBES[difficulty]
    while len(cells) < n:
        i, j = int(rng.integers(0, 5)), int(rng.integers(-3, 3))
        k = 0
        while (i, j, k) in cells:
            k += 1
        if k < 4:
            cells.add((i, j, k))
    return cells


STRUCTURES: Dict[str, Callable] = {"x": _x, "cross": _cross, "house": _house, "oven": _oven, "random": _random_field}

_FACES = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
_EDGES = [(a, b, 0) for a in (-1, 1) for b in (-1, 1)] + [(a, 0, b) for a in (-1, 1) for b in (-1, 1)] + \
         [(0, a, b) for a in (-1, 1) for b in (-1, 1)]


def spots(cells: FrozenSet[Cell], difficulty: str) -> List[Tuple[float, Cell]]:
    """Empty cells next to the structure (above the floor) with their enclosure score, most enclosed first."""
    def add(c, d):
        return (c[0] + d[0], c[1] + d[1], c[2] + d[2])
    cand = {add(c, d) for c in cells for d in _FACES} - set(cells)
    scored = []
    for c in cand:
        if c[2] < 0:
            continue
        score = sum(add(c, d) in cells for d in _FACES) + 0.5 * sum(add(c, d) in cells for d in _EDGES)
        if score >= 1:
            scored.append((score, c))
    scored.sort(key=lambda sc: (-sc[0], sc[1]))
    keep = max(N_GOALS, int(math.ceil(SPOT_SHARE[difficulty] * len(scored))))
    if keep < len(scored):  # keep ties with the last kept spot
        cut = scored[keep - 1][0]
        scored = [sc for sc in scored if sc[0] >= cut]
    return scored


def _centre(c: Cell) -> np.ndarray:
    return np.array([(c[0] + 0.5) * CUBE, c[1] * CUBE, (c[2] + 0.5) * CUBE])


def _cell(tid: str, prov: Provenance, opts, cubes: List[np.ndarray], yaw: float, goals: List[np.ndarray]) -> dict:
    r = (-BASE_RANGE, BASE_RANGE)
    t = (-POS_TOL, POS_TOL)
    R = rot_z(yaw)
    return {
        "header": header(tid, f"BPO 2024 style edge case: {opts['structure']} ({opts['difficulty']})", prov,
                         ["edge_case", f"edge_case_{opts['difficulty']}", str(opts["structure"]), "3 goals"]),
        "obstacles": [{"ID": f"cube_{k}", "name": f"cube {k}",
                       "collision": [{"type": "box", "parameters": {"x": CUBE, "y": CUBE, "z": CUBE},
                                      "pose": transform(p, R)}]} for k, p in enumerate(cubes)],
        "constraints": [
            {"type": "basePlacement", "pose": tolerated(transform(), x=r, y=r, z=r, Theta_R=(0.0, PI))},
            {"type": "joint", "parts": ["q", "dq", "tau"]},
            {"type": "selfCollisionFree"},
            {"type": "collisionFree"},
            {"type": "allGoalsFulfilled"},
        ],
        "goals": [{"ID": f"goal_{k}", "type": "reach", "goalPose": tolerated(transform(p), x=t, y=t, z=t)}
                  for k, p in enumerate(goals)],
    }


def resolved(prov: Provenance, opts: Dict[str, Any]) -> Dict[str, Any]:
    """``mixed`` cycles with the task index: structure index mod 5, difficulty (index // 5) mod 3."""
    out = dict(opts)
    if out["structure"] == "mixed":
        out["structure"] = list(STRUCTURES)[prov.index % len(STRUCTURES)]
    if out["difficulty"] == "mixed":
        out["difficulty"] = DIFFICULTIES[(prov.index // len(STRUCTURES)) % len(DIFFICULTIES)]
    return out


def task_id(prov: Provenance, opts) -> str:
    return f"bpo2024easy_{opts['structure']}_{opts['difficulty']}_s{prov.seed}_{prov.index:04d}"


def build_easy(prov: Provenance, opts: Dict[str, Any], folder: Path) -> GeneratedTask:
    opts = resolved(prov, opts)
    rng = prov.rng()
    tid = task_id(prov, opts)
    difficulty = str(opts["difficulty"])
    margin = CLEARANCE[difficulty]
    for _ in range(CELL_TRIES):
        cells = frozenset(STRUCTURES[str(opts["structure"])](rng, difficulty))
        yaw = float(rng.uniform(-PI, PI))
        dist = float(rng.uniform(*DISTANCE))
        R = rot_z(yaw)

        def world(p):
            return R @ (np.asarray(p) + [dist, 0.0, 0.0])
        order = sorted(cells)
        cubes = [world(_centre(c)) for c in order]
        arm = ReferenceArm(_cell(tid, prov, opts, cubes, yaw, []), folder, seed=int(rng.integers(2 ** 31)))
        cand = [c for _, c in spots(cells, difficulty)]
        goals: List[np.ndarray] = []
        used: Set[Cell] = set()
        for _ in range(GOAL_TRIES):
            if len(goals) == N_GOALS:
                break
            free = [c for c in cand if c not in used]
            if not free:
                break
            c = free[int(rng.integers(len(free)))]
            p = world(_centre(c) + rng.uniform(-(CUBE / 2 - margin), CUBE / 2 - margin, 3))
            if arm.clearance(p) < margin - 1e-9:
                continue
            if arm.reaches(tolerated(transform(p), x=(-POS_TOL, POS_TOL), y=(-POS_TOL, POS_TOL),
                                     z=(-POS_TOL, POS_TOL))):
                goals.append(p)
                used.add(c)
        if len(goals) < N_GOALS:
            continue
        task = _cell(tid, prov, opts, cubes, yaw, goals)
        if verified(task, opts, folder):
            return GeneratedTask(tid, task)
    raise RobodesignError(f"bpo2024: no cell of structure {opts['structure']} ({difficulty}) with {N_GOALS} reachable "
                          f"goals in {CELL_TRIES} draws (seed {prov.seed}, index {prov.index})")


# ---------------------------------------------------------------------------------------------------------
# the published variant: the edge-case archetypes of Mayer and Althoff (2024)
# Each archetype is (goal voxels, obstacle voxels, goal rotation) on a grid of 0.25 m voxels whose index
# (i, j, k) has its centre at GRID · (i - 2, j - 2, k - 2) (a 5-voxel grid centred on the nominal base). The
# voxel data are those of the published generator (Dang and Mayer, base_opt "edge_case" tasks, 2024).
_R1 = ((0, 0, 1), (0, 1, 0), (-1, 0, 0))
_R2 = ((0, 0, 1), (-1, 0, 0), (0, -1, 0))
_R3 = ((-0.17470792, -0.31766705, -0.93196823), (0.05754346, 0.94161355, -0.33174188),
       (0.98293738, -0.11158661, -0.14622769))
_OVEN_GOALS = ((3, -3, 0), (-1, 3, 0), (-4, 4, 1))
_EASY_GOALS = ((1, -1, 0), (-1, 2, 0), (-4, 4, 2))
ARCHETYPES: Dict[str, Tuple[Tuple[Cell, ...], Tuple[Cell, ...], tuple]] = {
    "middle_oven": (((3, -3, 0), (-1, 2, 0), (-4, 4, 2)),
                    ((-3, 4, 2), (-4, 4, 1), (-4, 4, 3), (-3, 4, 3), (-3, 4, 1), (-4, 3, 2), (-4, 3, 3), (-4, 3, 1)),
                    _R1),
    "oven": (_OVEN_GOALS,
             ((-3, 4, 2), (-4, 4, 2), (-4, 4, 3), (-3, 4, 3), (-3, 4, 1), (-4, 3, 2), (-4, 3, 3), (-4, 3, 1)), _R2),
    "cross": (_EASY_GOALS, ((-3, 4, 2), (-4, 4, 1), (-4, 4, 3), (-4, 3, 2)), _R2),
    "mystic_cube": (((1, 4, 2), (1, 3, 1), (-4, 4, 2)),
                    ((-4, 4, 1), (-4, 4, 3), (-3, 3, 3), (-3, 3, 1), (-3, 5, 3), (-3, 5, 1), (-4, 3, 2), (-5, 5, 1),
                     (-5, 5, 3), (-5, 3, 1), (-5, 3, 3)), _R2),
    "equality_sim": (_EASY_GOALS,
                     ((-4, 4, 1), (-4, 4, 3), (-3, 4, 3), (-3, 4, 1), (-3, 3, 3), (-3, 3, 1), (-3, 5, 3), (-3, 5, 1),
                      (-4, 3, 3), (-4, 3, 1), (-4, 5, 1), (-4, 5, 3), (-5, 5, 1), (-5, 5, 3), (-5, 4, 1), (-5, 4, 3),
                      (-5, 3, 1), (-5, 3, 3)), _R2),
    "cross_cube": (_EASY_GOALS,
                   ((-3, 4, 3), (-3, 4, 1), (-3, 3, 2), (-4, 3, 3), (-4, 3, 1), (-4, 5, 1), (-4, 5, 3), (-5, 5, 2),
                    (-5, 4, 1), (-5, 4, 3), (-5, 3, 2)), _R3),
    "house": (((0, 6, 2), (-2, 5, 3), (-4, 4, 2)),
              ((-4, 4, 1), (-4, 4, 3), (-3, 4, 3), (-3, 4, 1), (-3, 3, 1), (-3, 3, 2), (-3, 5, 3), (-3, 5, 1),
               (-4, 3, 3), (-4, 3, 1), (-4, 5, 1), (-4, 5, 3), (-5, 5, 1), (-5, 5, 3), (-5, 5, 2), (-5, 4, 1),
               (-5, 4, 3), (-5, 3, 1), (-5, 3, 3), (-5, 3, 2)), _R3),
    "c_sim": (((0, 5, 1), (1, 4, 1), (-4, 4, 2)),
              ((-4, 4, 1), (-4, 4, 3), (-3, 4, 3), (-3, 4, 1), (-3, 4, 2), (-3, 3, 1), (-3, 3, 2), (-3, 5, 2),
               (-3, 5, 3), (-3, 5, 1), (-4, 3, 3), (-4, 3, 1), (-4, 5, 1), (-4, 5, 3), (-5, 5, 1), (-5, 5, 3),
               (-5, 4, 1), (-5, 4, 3), (-5, 3, 1), (-5, 3, 3)), _R2),
    "XI_cube": (((1, -1, 0), (-2, 2, 0), (-4, 4, 2)),
                ((-4, 4, 1), (-4, 4, 3), (-3, 4, 1), (-3, 3, 3), (-3, 3, 1), (-3, 5, 3), (-3, 5, 1), (-4, 3, 2),
                 (-5, 5, 1), (-5, 5, 3), (-5, 4, 1), (-5, 3, 1), (-5, 3, 3)), _R3),
    "mystic_field": (_EASY_GOALS,
                     ((-3, 4, 1), (-3, 4, 3), (-2, 3, 3), (-1, 3, 1), (-2, 5, 3), (-1, 5, 1), (-4, 2, 2), (-4, 6, 2),
                      (-5, 5, 1), (-4, 5, 3), (-5, 3, 1), (-4, 3, 3)), _R2),
}
LEVELS = ("medium", "hard")
GRID_CENTRE = 2  # voxel index of the grid centre (grid of 5)
_QUARTER_TURN = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])


def voxel_centre(c) -> np.ndarray:
    return CUBE * (np.asarray(c, float) - GRID_CENTRE)


def mutate(rng: np.random.Generator, archetype: str, level: str):
    """The published mutation of an archetype: the whole structure shifts by (dx, dy, dz) voxels, the goals
    other than the last by a further (dx_g, dy_g, dz_g); with probability 1/2 the goal rotation is turned by
    a quarter turn about its z axis. Returns (goal voxels, obstacle voxels, goal rotation)."""
    goals, obstacles, rotation = ARCHETYPES[archetype]
    R = np.array(rotation, float)
    if level == "hard":
        dx = int(rng.choice([9, 8, 1, 0, -1]))
        dy, dz = int(rng.integers(-2, 3)), int(rng.integers(-2, 4))
        gx, gy, gz = int(rng.integers(-1, 1)), int(rng.integers(-2, 2)), int(rng.integers(-1, 2))
    else:
        dx = int(rng.choice([9, 8, 7, 1, 0]))
        dy, dz = int(rng.integers(-3, 1)), int(rng.integers(-2, 3))
        gx, gy, gz = int(rng.integers(-1, 1)), int(rng.integers(0, 2)), int(rng.integers(-1, 2))
    last = goals[-1]
    g = tuple((x + dx, y + dy, z + dz) if (x, y, z) == last else (x + dx + gx, y + dy + gy, z + dz + gz)
              for x, y, z in goals)
    o = tuple((x + dx, y + dy, z + dz) for x, y, z in obstacles)
    if rng.random() < 0.5:
        R = R @ _QUARTER_TURN
    return g, o, R


def published_resolved(prov: Provenance, opts: Dict[str, Any]) -> Dict[str, Any]:
    """``mixed`` cycles with the task index: archetype index mod 10, level (index + index // 10) mod 2, so that
    any few tasks mix medium and hard and every 20 tasks hold each archetype at both levels."""
    out = dict(opts)
    if out["archetype"] == "mixed":
        out["archetype"] = list(ARCHETYPES)[prov.index % len(ARCHETYPES)]
    if out["level"] == "mixed":
        out["level"] = LEVELS[(prov.index + prov.index // len(ARCHETYPES)) % len(LEVELS)]
    return out


def _published_cell(tid: str, prov: Provenance, opts, cubes: List[np.ndarray], goals: List[np.ndarray]) -> dict:
    r = (-BASE_RANGE, BASE_RANGE)
    return {
        "header": header(tid, f"BPO 2024 edge case: {opts['archetype']} ({opts['level']})", prov,
                         ["BPO24", "base pose optimization 2024", "Any base rotation", "edge_case",
                          str(opts["archetype"]), f"edge_case_{opts['level']}", "3 goals"]),
        "obstacles": [{"ID": f"obstacle_{k}", "name": f"Obstacle {k}",
                       "collision": [{"type": "box", "parameters": {"x": CUBE, "y": CUBE, "z": CUBE},
                                      "pose": transform(p)}]} for k, p in enumerate(cubes)],
        "constraints": [
            {"type": "joint", "parts": ["q", "dq", "tau"]},
            {"type": "collisionFree"},
            {"type": "allGoalsFulfilled"},
            {"type": "basePlacement", "pose": tolerated(transform(), x=r, y=r, z=r)},
        ],
        "goals": [{"ID": f"goal_{k}", "type": "reach", "goalPose": full_pose(T)} for k, T in enumerate(goals)],
    }


def published_task_id(prov: Provenance, opts) -> str:
    return f"bpo2024_{opts['archetype']}_{opts['level']}_s{prov.seed}_{prov.index:04d}"


def build_published(prov: Provenance, opts: Dict[str, Any], folder: Path) -> GeneratedTask:
    """Draw mutations until every goal lies outside every cube and within the module set's reach bound of
    the base region (the published set also holds goals inside a cube, which no design can reach)."""
    opts = published_resolved(prov, opts)
    rng = prov.rng()
    tid = published_task_id(prov, opts)
    reach = set_reach_bound()
    lo, hi = np.full(3, -BASE_RANGE), np.full(3, BASE_RANGE)
    for _ in range(PUBLISHED_CELL_TRIES):
        g, o, R = mutate(rng, str(opts["archetype"]), str(opts["level"]))
        cubes = [voxel_centre(c) for c in o]
        boxes = [AABB.cube(c, CUBE) for c in cubes]
        goals = [transform(voxel_centre(c), R) for c in g]
        if outside_and_in_reach(goals, boxes, lo, hi, reach):
            return GeneratedTask(tid, _published_cell(tid, prov, opts, cubes, goals))
    raise RobodesignError(f"bpo2024: no {opts['archetype']} ({opts['level']}) cell with every goal outside the cubes "
                          f"in {PUBLISHED_CELL_TRIES} draws (seed {prov.seed}, index {prov.index})")


def build(prov: Provenance, opts: Dict[str, Any], folder: Path) -> GeneratedTask:
    return build_easy(prov, opts, folder) if opts["variant"] == "easy" else build_published(prov, opts, folder)


FAMILY = Family(
    name="bpo2024",
    version=VERSION,
    summary="edge cases (Mayer & Althoff 2024): 10 archetypes of 4-20 cubes of 0.25 m shifted by up to 2.25 m, 3 "
            "full-pose goals (±1 mm, 0.5°) in their pockets; base free ±1 m in x, y, z, any rotation "
            "(--variant easy: our own structures, ±5 mm goals checked by the reference design)",
    options=(
        VARIANT,
        Option("archetype", str, "mixed", "published variant: the edge-case archetype; mixed: by task index, "
                                          + ", ".join(ARCHETYPES) + " in turn", choices=("mixed", *ARCHETYPES)),
        Option("level", str, "mixed", "published variant: medium or hard shifts; mixed: by task index, "
                                      "alternating (each archetype at both levels in every 20 tasks)",
               choices=("mixed", *LEVELS)),
        Option("structure", str, "mixed", "--variant easy: the structure; mixed: by task index, x, cross, house, oven, random, x, …",
               choices=("mixed", *STRUCTURES)),
        Option("difficulty", str, "mixed", "--variant easy: how enclosed the goal spots are; mixed: by task index, 5 easy, 5 medium, "
                                           "5 hard, 5 easy, …", choices=("mixed", *DIFFICULTIES)),
        VERIFY,
    ),
    build=build,
)
