"""What every task generator shares: pose and geometry helpers, the deterministic JSON writer, the
provenance header, the geometric reachability bound of a module set (the published variants) and
the reachability test with the reference arm (the easy variants).

Determinism: a generator draws every number from one ``numpy.random.Generator`` seeded from
(family, folder seed, task index), rounds every float to 10 decimals (except exact constants marked
:class:`Exact`, such as the bound π, which are written with all their digits) and writes with a fixed
layout, so the same arguments give byte-identical files on any machine with the same numpy bit generator
(PCG64).
"""
from __future__ import annotations

import json
import math
import zlib
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple, cast

import numpy as np

from robodesign.core.errors import InputError
from robodesign.core.spatial import homogeneous
from robodesign.design.reach import module_set_reach
from robodesign.design.solve import SolveSettings, solve
from robodesign.formats.assembly import Assembly
from robodesign.formats.geometry import coal_shapes
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import parse_task
from robodesign.formats.tolerance import ToleratedPose
from robodesign.model.cell import build_robot
from robodesign.solvers.ik import solve_ik


class Exact(float):
    """A float written with all its digits (``repr``), never rounded: bounds such as π that a reader compares
    exactly (the reference rejects ``Theta_R`` ≤ 3.1415926536, which is larger than π). Arithmetic on it gives
    a plain float, so only the constant itself is exact."""


PI = Exact(math.pi)
NEG_PI = Exact(-math.pi)
HALF_DEGREE = Exact(math.pi / 360)  # rad: the reference's default orientation tolerance of a goal, 0.5°
MM = 0.001  # m: the reference's default position tolerance of a goal (x, y, z ± 1 mm)
DATE = "2026-01-01"  # fixed: the date is part of the bytes
DT = 0.01
GRAVITY = [0.0, 0.0, -9.81]
TAG_PREFIX = "robodesign-generate:"  # header tags "robodesign-generate:<key>=<value>" hold the provenance

# The reference design used to prove that goals are reachable: robodesign_arm in its default order (floor
# base, 6 DoF, reach ≈ 0.98 m from the shoulder at z = 0.372 m); assets/modules/robodesign_arm/README.md.
REFERENCE_MODULE_SET = "robodesign_arm"
REFERENCE_ORDER = ("1", "21", "22", "4", "22", "3", "23", "24", "23", "12")


# ---------------------------------------------------------------------------------------------------------
# poses and geometry (plain JSON-ready dicts)
def transform(p=(0.0, 0.0, 0.0), R: Optional[np.ndarray] = None) -> np.ndarray:
    return homogeneous(R, p)


def tolerated(nominal: np.ndarray, **tol) -> dict:
    """A ToleratedPose dict; keyword = projection name, value = (lo, hi)."""
    out: dict = {"nominal": nominal}
    if tol:
        out["toleranceProjection"] = list(tol)
        out["tolerance"] = [list(v) for v in tol.values()]
    return out


def full_pose(nominal: np.ndarray) -> dict:
    """A goal pose with the reference's default tolerance, as the published CoBRA files write it: x, y, z ± 1 mm
    and the absolute rotation ``Theta_R`` ∈ [0, 0.5°] (Timor's ``ToleratedPose(T)`` default)."""
    t = (-MM, MM)
    return tolerated(nominal, x=t, y=t, z=t, Theta_R=(0.0, HALF_DEGREE))


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    """A rotation matrix uniform on SO(3) (a unit quaternion from four normal numbers)."""
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def box(center, size) -> dict:
    """An axis-aligned box geometry (full edge lengths ``size``) centred at ``center``."""
    return {"type": "box", "parameters": {"x": size[0], "y": size[1], "z": size[2]}, "pose": transform(center)}


def box_between(lo, hi) -> dict:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return box((lo + hi) / 2, hi - lo)


@dataclass(frozen=True)
class AABB:
    """An axis-aligned box [lo, hi] in world coordinates (the generators' own geometry for placement)."""
    lo: Tuple[float, float, float]
    hi: Tuple[float, float, float]

    @classmethod
    def cube(cls, center, edge: float) -> "AABB":
        c = np.asarray(center, float)
        return cls(tuple(c - edge / 2), tuple(c + edge / 2))

    def distance(self, p) -> float:
        """Euclidean distance of point ``p`` from the box (0 inside)."""
        p = np.asarray(p, float)
        d = np.maximum(np.maximum(np.asarray(self.lo) - p, p - np.asarray(self.hi)), 0.0)
        return float(np.linalg.norm(d))

    @property
    def centre(self) -> np.ndarray:
        return (np.asarray(self.lo) + np.asarray(self.hi)) / 2

    def overlaps(self, other: "AABB", gap: float = 0.0) -> bool:
        return all(self.lo[k] < other.hi[k] + gap and other.lo[k] < self.hi[k] + gap for k in range(3))

    def geometry(self) -> dict:
        return box_between(self.lo, self.hi)


# ---------------------------------------------------------------------------------------------------------
# header and provenance
@dataclass(frozen=True)
class Provenance:
    """Everything needed to regenerate one task file: family, generator version, folder seed, index, options."""
    family: str
    version: int
    seed: int
    index: int
    options: Tuple[Tuple[str, str], ...]  # sorted (name, value) pairs, values as written on the CLI

    def tags(self) -> List[str]:
        items = [("generator", self.family), ("version", str(self.version)), ("seed", str(self.seed)),
                 ("index", str(self.index))] + list(self.options)
        return [f"{TAG_PREFIX}{k}={v}" for k, v in items]

    @classmethod
    def from_tags(cls, tags: Sequence[str], file: str = "<task>") -> "Provenance":
        kv: Dict[str, str] = {}
        for t in tags:
            if isinstance(t, str) and t.startswith(TAG_PREFIX) and "=" in t:
                k, v = t[len(TAG_PREFIX):].split("=", 1)
                kv[k] = v
        for k in ("generator", "version", "seed", "index"):
            if k not in kv:
                raise InputError(f"no '{TAG_PREFIX}{k}=...' tag: not written by robodesign generate",
                                 file=file, path=["header", "tags"])
        try:
            version, seed, index = int(kv.pop("version")), int(kv.pop("seed")), int(kv.pop("index"))
        except ValueError:
            raise InputError("version, seed and index tags must be integers", file=file,
                             path=["header", "tags"]) from None
        if seed < 0 or index < 0:
            raise InputError("seed and index tags must be non-negative", file=file, path=["header", "tags"])
        family = kv.pop("generator")
        return cls(family, version, seed, index, tuple(sorted(kv.items())))

    def rng(self) -> np.random.Generator:
        """The task's random stream: a function of (family, seed, index) only."""
        key = zlib.crc32(self.family.encode())
        return np.random.default_rng(np.random.SeedSequence([key, self.seed, self.index]))


def header(task_id: str, title: str, prov: Provenance, tags: Sequence[str] = ()) -> dict:
    return {"ID": task_id, "version": "2023", "taskName": title,
            "tags": [prov.family, *tags, *prov.tags()], "date": DATE, "timeStepSize": DT, "gravity": GRAVITY,
            "author": [f"robodesign generate {prov.family} v{prov.version} (seed {prov.seed}, index {prov.index})"],
            "affiliation": ["robodesign project"]}


# ---------------------------------------------------------------------------------------------------------
# deterministic JSON (also used by assets/tasks/make_tasks.py for the built-in tasks)
def clean(obj):
    """JSON-ready copy: arrays to lists, floats rounded to 10 decimals (integral ones to int, -0 to 0);
    an :class:`Exact` float keeps every digit."""
    if isinstance(obj, Exact):
        return float(obj)
    if isinstance(obj, np.ndarray):
        return clean(obj.tolist())
    if isinstance(obj, dict):
        return {k: clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [clean(v) for v in obj]
    if isinstance(obj, (float, np.floating)):
        v = round(float(obj), 10)
        return int(v) if v.is_integer() and abs(v) < 1e9 else v
    if isinstance(obj, np.integer):
        return int(obj)
    return obj


def _is_numbers(v) -> bool:
    return isinstance(v, list) and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)


def _inline(v) -> bool:
    """Number lists, small matrices and string lists are written on one line."""
    return (_is_numbers(v) or (isinstance(v, list) and v and all(_is_numbers(x) for x in v) and len(v) <= 4)
            or (isinstance(v, list) and all(isinstance(x, str) for x in v)))


def dumps(obj, indent: int = 0) -> str:
    pad, pad1 = "  " * indent, "  " * (indent + 1)
    if isinstance(obj, dict):
        if not obj:
            return "{}"
        if len(obj) <= 4 and all(isinstance(v, (int, float, str)) for v in obj.values()):
            return json.dumps(obj, separators=(", ", ": "))
        items = [f"{pad1}{json.dumps(k)}: {dumps(v, indent + 1)}" for k, v in obj.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    if isinstance(obj, list):
        if not obj:
            return "[]"
        if _inline(obj):
            return json.dumps(obj, separators=(", ", ": "))
        items = [f"{pad1}{dumps(v, indent + 1)}" for v in obj]
        return "[\n" + ",\n".join(items) + "\n" + pad + "]"
    return json.dumps(obj)


def task_text(task: dict) -> str:
    return dumps(clean(task)) + "\n"


# ---------------------------------------------------------------------------------------------------------
# geometric reachability: a bound on every design of a module set (no solve, no design of ours)
@lru_cache(maxsize=None)
def set_reach_bound(module_set_name: str = REFERENCE_MODULE_SET, max_dof: int = 6,
                    max_links_between: int = 1) -> float:
    """Upper bound [m] on the distance from the base frame (the base connector) to the TCP of *any* serial
    design of the set under robodesign's search rules (at most ``max_dof`` joint modules, at most
    ``max_links_between`` link modules before, between and after them): the longest arm of
    :func:`robodesign.design.reach.set_reach`. A goal farther than this from every allowed base position is out
    of reach for every design of the set."""
    return module_set_reach(load_module_set(module_set_name), max_dof=max_dof,
                            max_links_between=max_links_between).bound


def box_distance(p, lo, hi) -> float:
    """Euclidean distance of point ``p`` from the axis-aligned box [lo, hi] (0 inside)."""
    p = np.asarray(p, float)
    d = np.maximum(np.maximum(np.asarray(lo, float) - p, p - np.asarray(hi, float)), 0.0)
    return float(np.linalg.norm(d))


def outside_and_in_reach(goals: Sequence[np.ndarray], boxes: Sequence[AABB], lo, hi, reach: float) -> bool:
    """The published variants' goal test (whitman2020, bpo2024): the position of every goal pose lies outside
    every box (distance > 0) and within ``reach`` of the base region [lo, hi] (:func:`box_distance`)."""
    return all(all(b.distance(T[:3, 3]) > 0.0 for b in boxes) and box_distance(T[:3, 3], lo, hi) <= reach
               for T in goals)


class ObstacleField:
    """The obstacles of a task (as the generators write it), for distance queries with coal."""

    def __init__(self, task_dict: dict, folder: Path):
        self.task = parse_task(clean(task_dict), folder / "_probe.json")

    def clearance(self, p) -> float:
        """Distance (coal) of point ``p`` from the cell's obstacles (≤ 0 inside one)."""
        import coal
        return self.distance(coal.Sphere(1e-6), transform(p))

    def distance(self, shape, pose: np.ndarray) -> float:
        """Distance (coal) of a coal shape at ``pose`` from the cell's obstacles (≤ 0 when they touch)."""
        import coal

        if not hasattr(self, "_obstacles"):
            self._obstacles = [coal.CollisionObject(s, coal.Transform3s(g.pose[:3, :3], g.pose[:3, 3]))
                               for o in self.task.obstacles for g in o.collision for s in coal_shapes(g)]
        probe = coal.CollisionObject(shape, coal.Transform3s(pose[:3, :3], pose[:3, 3]))
        best = math.inf
        for obj in self._obstacles:
            res = coal.DistanceResult()
            coal.distance(probe, obj, coal.DistanceRequest(), res)
            best = min(best, res.min_distance)
        return best


# ---------------------------------------------------------------------------------------------------------
# reachability with the reference arm (the easy variants only)
class ReferenceArm(ObstacleField):
    """robodesign_arm in REFERENCE_ORDER at a given base pose, in a cell of obstacles: tests whether a
    tolerated goal has a collision-free IK solution that holds its pose within the torque limits."""

    def __init__(self, task_dict: dict, folder: Path, base_pose: Optional[np.ndarray] = None,
                 ik_restarts: int = 60, min_converged: int = 4, seed: int = 0):
        super().__init__(task_dict, folder)
        self.module_set = load_module_set(REFERENCE_MODULE_SET)
        asm = Assembly.from_order(self.module_set, list(REFERENCE_ORDER))
        self.robot = build_robot(self.task, self.module_set, asm,
                                 np.eye(4) if base_pose is None else np.asarray(base_pose, float))
        self.ik_restarts, self.min_converged = ik_restarts, min_converged
        self.rng = np.random.default_rng(seed)

    def reaches(self, goal_pose: dict) -> bool:
        tp = ToleratedPose.from_json(clean(goal_pose))
        o, R = self.robot.reach_bound()
        if np.linalg.norm(tp.nominal[:3, 3] - o) > R:
            return False
        # every restart runs (n_solutions = restarts): a goal that the IK finds from only a few random starts
        # is out, so that solvers with other seeds find it too
        r = solve_ik(self.robot, tp, self.rng, max_restarts=self.ik_restarts, n_solutions=self.ik_restarts)
        if int(cast(int, r.stats["converged"])) < self.min_converged:  # (stats: Dict[str, object] of counters)
            return False
        limit = self.robot.tau_max
        return any(np.all(np.abs(self.robot.gravity_torque(q)) <= limit) for q in r.solutions)

VERIFY_PLAN_TIME = 10.0  # s per planning query of the verification solve


def verified(task_dict: dict, opts: dict, folder: Path, base_pose: Optional[np.ndarray] = None) -> bool:
    """The ``--verify`` decision for a task whose goals passed the goal tests: always true for ``ik``."""
    return (opts.get("verify") or "solve") == "ik" or solved_by_reference(task_dict, folder, base_pose)


def solved_by_reference(task_dict: dict, folder: Path, base_pose: Optional[np.ndarray] = None) -> bool:
    """Whether the reference design at ``base_pose`` (default: the task's nominal base) solves the task and the
    checker accepts the solution (``robodesign.design.solve.solve``, seed 0, ``VERIFY_PLAN_TIME`` per planning query).

    OMPL is seeded, so the answer is the same on every run unless a planning query runs into the time limit:
    a query that needs seconds on an idle machine could be cut on an overloaded one. The generous limit makes
    that unlikely (a successful query returns at once; only failing cells pay the full limit)."""
    task = parse_task(clean(task_dict), folder / "_probe.json")
    res = solve(task, load_module_set(REFERENCE_MODULE_SET), list(REFERENCE_ORDER), base_pose=base_pose,
                settings=SolveSettings(seed=0, plan_time=VERIFY_PLAN_TIME))
    return res.feasible
