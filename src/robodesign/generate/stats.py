"""Statistics of a folder of task files, as issue 21 measured the published CoBRA families: goal tolerance,
goal distance from the nominal base, share of goals below the base plane, goal clearance to the nearest cube,
base freedom, constraint list and obstacles (experiments/generator_stats.py; docs/generators.md).

Everything is read from the JSON files with plain arithmetic (no robodesign parser), so the figures are an
independent check of what the generators write.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np

# The published figures (issue 21, measured over the published files: Whitman2020 204 tasks, BPO24 edge cases,
# Liu2020 case 2b).
PUBLISHED: Dict[str, Dict[str, str]] = {
    "whitman2020": {"tolerance": "x, y, z ±1 mm; Theta_R ≤ 0.50°", "distance": "0.09 / 0.97 / 1.54",
                    "below": "51–67 %", "clearance": "0.00 / 0.5–0.6",
                    "base": "fixed (±1 mm, 0.5°) or x, y, z ±1 m, any rotation",
                    "constraints": "joint[q, tau], collisionFree, allGoalsFulfilled", "obstacles": "3 or 5 boxes 0.25 m"},
    "bpo2024": {"tolerance": "x, y, z ±1 mm; Theta_R ≤ 0.50°", "distance": "0.35 / 1.30 / 2.72", "below": "52 %",
                "clearance": "−0.12 / 0.40", "base": "x, y, z ±1 m, any rotation",
                "constraints": "joint[q, dq, tau], collisionFree, allGoalsFulfilled", "obstacles": "4–20 boxes 0.25 m"},
    "liu2020": {"tolerance": "x, y, z ±1 mm; Theta_R ≤ 0.50°", "distance": "0.15 / 0.66 / 0.90", "below": "21 %",
                "clearance": "–", "base": "x, y, z ±1 m, any rotation",
                "constraints": "joint[q, tau], collisionFree, allGoalsFulfilled(InOrder)",
                "obstacles": "1 machine mesh"},
}
ROWS = ("tolerance", "distance", "below", "clearance", "base", "constraints", "obstacles")
ROW_NAMES = {"tolerance": "goal tolerance", "distance": "goal distance from nominal base, min / median / max [m]",
             "below": "goals below the base plane", "clearance": "goal clearance to nearest cube, min / median [m]",
             "base": "base", "constraints": "constraints", "obstacles": "obstacles"}


@dataclass
class FolderStats:
    tasks: int
    tolerances: List[str]  # distinct goal tolerance descriptions
    distances: np.ndarray  # per goal [m]
    below: float  # share of goals below the base plane
    clearances: np.ndarray  # per goal, signed distance to the nearest box [m] (empty without boxes)
    bases: List[str]  # distinct base descriptions
    constraints: List[str]  # distinct constraint lists
    obstacle_counts: List[int]
    obstacle_kinds: List[str]

    def row(self, key: str) -> str:
        if key == "tolerance":
            return " | ".join(self.tolerances)
        if key == "distance":
            d = self.distances
            return f"{d.min():.2f} / {np.median(d):.2f} / {d.max():.2f}"
        if key == "below":
            return f"{100 * self.below:.0f} %"
        if key == "clearance":
            c = self.clearances
            return "–" if not len(c) else f"{c.min():.2f} / {np.median(c):.2f}"
        if key == "base":
            return " | ".join(self.bases)
        if key == "constraints":
            return " | ".join(self.constraints)
        lo, hi = min(self.obstacle_counts), max(self.obstacle_counts)
        n = str(lo) if lo == hi else f"{lo}–{hi}"
        return f"{n} × {' + '.join(self.obstacle_kinds)}"


def _tol(pose: dict) -> Dict[str, tuple]:
    return {p: tuple(v) for p, v in zip(pose.get("toleranceProjection", []), pose.get("tolerance", []))}


def describe_tolerance(pose: dict) -> str:
    t = _tol(pose)
    parts = []
    xyz = [t[k] for k in "xyz" if k in t]
    if len(xyz) == 3 and len(set(xyz)) == 1 and -xyz[0][0] == xyz[0][1]:
        h = xyz[0][1]
        parts.append(f"x, y, z ±{h * 1000:g} mm" if h < 0.1 else f"x, y, z ±{h:g} m")
    else:
        parts += [f"{k} {list(t[k])}" for k in "xyz" if k in t]
    if "Theta_R" in t:
        parts.append(f"Theta_R ≤ {math.degrees(t['Theta_R'][1]):.2f}°")
    parts += [f"{k} {list(v)}" for k, v in t.items() if k not in ("x", "y", "z", "Theta_R")]
    if not any(k in t for k in ("Theta_R", "N_x", "N_y", "N_z")):
        parts.append("any rotation")
    return "; ".join(parts)


def describe_base(constraints: Sequence[dict]) -> str:
    bp = next((c for c in constraints if c.get("type") == "basePlacement"), None)
    if bp is None:
        return "no basePlacement (free)"
    t = _tol(bp["pose"])
    if all(k in t and t[k][1] <= 0.001 + 1e-12 for k in "xyz") and "Theta_R" in t:
        return f"fixed (±1 mm, {math.degrees(t['Theta_R'][1]):.1f}°)"
    return describe_tolerance(bp["pose"])


def describe_constraints(constraints: Sequence[dict]) -> str:
    out = []
    for c in constraints:
        if c.get("type") == "basePlacement":
            continue
        if c.get("type") == "joint":
            out.append(f"joint[{', '.join(c.get('parts', []))}]")
        else:
            out.append(str(c.get("type")))
    return ", ".join(out)


def box_signed_distance(p: np.ndarray, geometry: dict) -> Optional[float]:
    """Signed distance of point p from a box geometry (negative inside), None for other geometry."""
    if geometry.get("type") != "box":
        return None
    T = np.asarray(geometry.get("pose", np.eye(4)), float)
    half = np.array([geometry["parameters"][k] for k in "xyz"], float) / 2
    q = T[:3, :3].T @ (np.asarray(p, float) - T[:3, 3])
    d = np.abs(q) - half
    outside = np.linalg.norm(np.maximum(d, 0.0))
    return float(outside) if outside > 0 else float(np.max(d))


def folder_stats(files: Sequence[Path]) -> FolderStats:
    tol, bases, cons, kinds = set(), set(), set(), set()
    dist, below, clear, counts = [], [], [], []
    for f in files:
        task = json.loads(Path(f).read_text())
        constraints = task.get("constraints", [])
        bp = next((c for c in constraints if c.get("type") == "basePlacement"), None)
        base = np.asarray(bp["pose"]["nominal"], float)[:3, 3] if bp else np.zeros(3)
        bases.add(describe_base(constraints))
        cons.add(describe_constraints(constraints))
        geoms = [g for o in task.get("obstacles", []) for g in (o["collision"] if isinstance(o["collision"], list)
                                                                 else [o["collision"]])]
        counts.append(len(task.get("obstacles", [])))
        for g in geoms:
            kinds.add(f"box {g['parameters']['x']:g} m" if g["type"] == "box" else g["type"])
        for goal in task.get("goals", []):
            pose = goal["goalPose"]
            tol.add(describe_tolerance(pose))
            p = np.asarray(pose["nominal"], float)[:3, 3]
            dist.append(float(np.linalg.norm(p - base)))
            below.append(p[2] < base[2])
            ds = [d for d in (box_signed_distance(p, g) for g in geoms) if d is not None]
            if ds:
                clear.append(min(ds))
    return FolderStats(len(files), sorted(tol), np.array(dist), float(np.mean(below)), np.array(clear),
                       sorted(bases), sorted(cons), counts, sorted(kinds))


def table(columns: Dict[str, Dict[str, str]]) -> str:
    """A markdown table: one row per statistic, one column per heading."""
    heads = list(columns)
    lines = ["| | " + " | ".join(heads) + " |", "|---|" + "---|" * len(heads)]
    for r in ROWS:
        lines.append(f"| {ROW_NAMES[r]} | " + " | ".join(columns[h].get(r, "") for h in heads) + " |")
    return "\n".join(lines)


__all__ = ["PUBLISHED", "ROWS", "FolderStats", "box_signed_distance", "describe_base", "describe_constraints",
           "describe_tolerance", "folder_stats", "table"]
