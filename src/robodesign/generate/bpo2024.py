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
from typing import Callable, Dict, FrozenSet, List, Set, Tuple

import numpy as np

from robodesign.core.errors import RobodesignError
from robodesign.core.spatial import rot_z
from robodesign.generate.common import PI, Provenance, ReferenceArm, header, tolerated, transform, verified
from robodesign.generate.registry import VERIFY, Family, GeneratedTask, Option

VERSION = 2
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


def resolved(prov: Provenance, opts: Dict[str, object]) -> Dict[str, object]:
    """``mixed`` cycles with the task index: structure index mod 5, difficulty (index // 5) mod 3."""
    out = dict(opts)
    if out["structure"] == "mixed":
        out["structure"] = list(STRUCTURES)[prov.index % len(STRUCTURES)]
    if out["difficulty"] == "mixed":
        out["difficulty"] = DIFFICULTIES[(prov.index // len(STRUCTURES)) % len(DIFFICULTIES)]
    return out


def task_id(prov: Provenance, opts) -> str:
    return f"bpo2024_{opts['structure']}_{opts['difficulty']}_s{prov.seed}_{prov.index:04d}"


def build(prov: Provenance, opts: Dict[str, object], folder: Path) -> GeneratedTask:
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


FAMILY = Family(
    name="bpo2024",
    version=VERSION,
    summary="edge cases: structures of 0.25 m cubes (x, cross, house, oven, random), 3 goals in their "
            "hard-to-reach spots; base free ±1 m in x, y, z, any rotation",
    options=(
        Option("structure", str, "mixed", "the structure; mixed: by task index, x, cross, house, oven, random, x, …",
               choices=("mixed", *STRUCTURES)),
        Option("difficulty", str, "mixed", "how enclosed the goal spots are; mixed: by task index, 5 easy, 5 medium, "
                                           "5 hard, 5 easy, …", choices=("mixed", *DIFFICULTIES)),
        VERIFY,
    ),
    build=build,
)
