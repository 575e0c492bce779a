"""Search on hard tasks (issue 21, points 2 and 4): solved share, best cost and how far the best candidate got,
with the genetic optimizer, for this checkout and optionally an older one (``--before DIR``: a folder holding
that version's ``src`` and ``optimizers``, e.g. ``git archive 01eded7 src optimizers | tar -x -C DIR``).

The tasks are written by a small seeded generator here (faithful in the points that make the published
families hard, after the statistics in issue 21): 3 reach goals 1.0–1.5 m from the nominal base, a full pose
tolerance (x, y, z ±1 mm, Theta_R ≤ 0.5°) with a random orientation, half of the goals below the base plane,
three 0.25 m cubes ≥ 0.2 m from every goal and from the base, constraints joint q and tau, collisionFree,
allGoalsFulfilled; the base fixed (±1 mm, 0.5°) in half of the tasks, free in x, y, z ±1 m with any rotation in
the others. No task is filtered by a design (some may be infeasible for every design of the set). Plus a
follow task without basePlacement 5 m from the origin (tests/test_free_base.py).

    nice python experiments/bench_hard_search.py --tasks 6 --budget 30s [--before /tmp/before] [--workers 1]
        [--position-only] [--no-far]

Each run is ``robodesign optimize TASK --modules robodesign_arm --optimizer genetic --budget B --seed 0 --json``
in its own process; the wall time of the whole command is measured too (``--budget`` must hold).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


def _random_rotation(rng) -> np.ndarray:
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _T(R, p) -> list:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, p
    return np.round(T, 12).tolist()


def hard_task(seed: int, free_base: bool, orientation: bool = True) -> dict:
    """One task (``orientation=False``: position-only goals, x, y, z ±1 mm: the reach and torque part alone)."""
    rng = np.random.default_rng(seed)
    goals = []
    while len(goals) < 3:
        d = rng.uniform(1.0, 1.5)
        below = len(goals) % 2 == 0 if seed % 2 else len(goals) % 2 == 1  # half of the goals below the base
        z = -rng.uniform(0.05, 0.7) if below else rng.uniform(0.05, 0.9)
        r = math.sqrt(max(d * d - z * z, 0.09))
        a = rng.uniform(-math.pi, math.pi)
        p = np.array([r * math.cos(a), r * math.sin(a), z])
        if all(np.linalg.norm(p - g) > 0.3 for g in goals):
            goals.append(p)
    cubes = []
    while len(cubes) < 3:
        c = np.array([*rng.uniform(-1.3, 1.3, 2), rng.uniform(-0.6, 0.9)])
        if np.linalg.norm(c[:2]) > 0.4 and all(np.linalg.norm(c - g) > 0.2 + 0.25 * math.sqrt(3) / 2 for g in goals) \
                and all(np.max(np.abs(c - o)) > 0.25 for o in cubes):
            cubes.append(c)
    pose_tol = {"toleranceProjection": ["x", "y", "z", "Theta_R"],
                "tolerance": [[-0.001, 0.001], [-0.001, 0.001], [-0.001, 0.001], [0.0, math.radians(0.5)]]}
    goal_tol = pose_tol if orientation else {"toleranceProjection": ["x", "y", "z"],
                                             "tolerance": [[-0.001, 0.001], [-0.001, 0.001], [-0.001, 0.001]]}
    base = ({"toleranceProjection": ["x", "y", "z", "Theta_R"],
             "tolerance": [[-1.0, 1.0], [-1.0, 1.0], [-1.0, 1.0], [0.0, math.pi]]} if free_base else pose_tol)
    return {
        "header": {"ID": f"bench/hard_{seed}", "version": "2022", "taskName": f"hard {seed}", "tags": ["bench"],
                   "date": "2026-11-26", "timeStepSize": 0.01, "gravity": [0, 0, -9.81], "author": ["robodesign"],
                   "affiliation": ["robodesign"]},
        "obstacles": [{"ID": f"cube{i}", "name": "cube", "collision": [
            {"type": "box", "parameters": {"x": 0.25, "y": 0.25, "z": 0.25}, "pose": _T(np.eye(3), c)}]}
            for i, c in enumerate(cubes)],
        "constraints": [{"type": "joint", "parts": ["q", "tau"]}, {"type": "collisionFree"},
                        {"type": "allGoalsFulfilled"},
                        {"type": "basePlacement", "pose": {"nominal": _T(np.eye(3), np.zeros(3)), **base}}],
        "goals": [{"ID": str(i), "type": "reach", "goalPose": {"nominal": _T(_random_rotation(rng), g), **goal_tol}}
                  for i, g in enumerate(goals)],
    }


def run(task: Path, budget: str, workers: int, src: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(src / "src"), str(src / "optimizers")]))
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "robodesign.cli", "optimize", str(task), "--modules", "robodesign_arm",
                        "--optimizer", "genetic", "--budget", budget, "--seed", "0", "--workers", str(workers),
                        "--json", "--out", str(task.with_suffix(".sol.json"))],
                       capture_output=True, text=True, env=env, cwd=str(task.parent))
    wall = time.perf_counter() - t0
    try:
        out = json.loads(r.stdout.strip().splitlines()[-1])
    except (json.JSONDecodeError, IndexError):
        return {"error": r.stderr[-300:], "wall": wall}
    best = out.get("best") or {}
    return {"solved": out["feasible"], "cost": best.get("cost"), "stage": best.get("stage"),
            "message": (best.get("message") or "")[:90], "evaluations": out["evaluations"],
            "study_s": out["seconds"], "wall": wall, "overrun": out.get("budget_overrun"),
            "stage_counts": out.get("stage_counts")}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--tasks", type=int, default=6)
    ap.add_argument("--budget", default="30s")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--before", type=Path, default=None)
    ap.add_argument("--no-far", action="store_true")
    ap.add_argument("--position-only", action="store_true", help="goals without an orientation tolerance")
    a = ap.parse_args()
    from test_free_base import far_drilling
    folder = Path(tempfile.mkdtemp(prefix="bench_hard_"))
    tasks = []
    for s in range(a.tasks):
        p = folder / f"hard_{s}.json"
        p.write_text(json.dumps(hard_task(s, free_base=s % 2 == 1, orientation=not a.position_only), indent=1))
        tasks.append(p)
    if not a.no_far:
        tasks.append(far_drilling(folder / "far_drilling.json"))
    versions = [("after", ROOT)] + ([("before", a.before)] if a.before else [])
    rows = []
    for t in tasks:
        for name, src in versions:
            r = run(t, a.budget, a.workers, src)
            rows.append((t.stem, name, r))
            print(json.dumps({"task": t.stem, "version": name, **r}), flush=True)
    print(f"\nbudget {a.budget}, {a.workers} worker(s), genetic, seed 0, "
          f"{'position-only' if a.position_only else 'full-pose'} goals")
    print("| task | version | solved | best cost | best stage | evaluations | study s | command wall s |")
    print("|---|---|---|---|---|---|---|---|")
    for task, name, r in rows:
        if "error" in r:
            print(f"| {task} | {name} | error | | | | | {r['wall']:.1f} |")
            continue
        cost = f"{r['cost']:.3f}" if r["cost"] is not None else "–"
        print(f"| {task} | {name} | {'yes' if r['solved'] else 'no'} | {cost} | {r['stage']} | {r['evaluations']} | "
              f"{r['study_s']:.1f} | {r['wall']:.1f} |")
    for name, _ in versions:
        rs = [r for _, n, r in rows if n == name and "error" not in r]
        print(f"{name}: solved {sum(r['solved'] for r in rs)}/{len(rs)}; max command wall {max(r['wall'] for r in rs):.1f} s")


if __name__ == "__main__":
    main()
