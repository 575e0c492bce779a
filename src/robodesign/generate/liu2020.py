"""liu2020: machine tending, after Liu and Althoff (2020), "Optimizing performance in automation through
modular robots", case 2b: load a part into a CNC machine's work area and unload it.

The cell: a machine mesh (``--machine FILE``, copied into ``<out>/assets/``; default a box-built CNC
housing the generator writes itself) turned so that its work area faces the robot (machine.analyse), placed
so that the work area starts ``machine_gap`` m in front of the nominal base along a randomly drawn probe ray.

Goals, in order: ``pick`` beside the robot (tool down) → ``load`` inside the machine (tool pointing into
it) → ``unload`` at another point inside the machine → ``place`` on the other side (tool down).

``--variant published`` (default; :data:`PUBLISHED`): as the published case 2b files: full-pose goals
(x, y, z ± 1 mm, ``Theta_R`` ≤ 0.5°), constraints ``joint`` q, tau, collisionFree, allGoalsFulfilled and
allGoalsFulfilledInOrder, the machine the only obstacle, base free x, y, z ± 1 m about the nominal base
(0.58 m above the floor) with any rotation. A goal is kept when it keeps ``GOAL_CLEARANCE`` from the machine
and lies within the reach bound of the reference module set from the base region (common.set_reach_bound).

``--variant easy`` (:data:`EASY`, version 4): input and output trays as obstacles, positions ± 5 mm, the tool
axis within ± 0.1 (N_x, N_y), base x, y ± 0.3 m, 0–0.6 m high, upright; every goal reachable by the reference
arm (common.ReferenceArm) from the nominal base; with ``--verify solve`` the reference design solves the task.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Tuple, Union

import numpy as np

from robodesign.core.errors import InputError, RobodesignError
from robodesign.core.spatial import rot_y
from robodesign.formats.geometry import load_mesh_arrays
from robodesign.generate.common import (
    AABB,
    NEG_PI,
    PI,
    ObstacleField,
    Provenance,
    ReferenceArm,
    box_distance,
    full_pose,
    header,
    set_reach_bound,
    tolerated,
    transform,
    verified,
)
from robodesign.generate.family import VARIANT, VERIFY, Family, GeneratedTask, Option, copy_file
from robodesign.generate.machine import (
    COVER_DOWN,
    COVER_UP,
    DEFAULT_NAME,
    STEP,
    MachineFrame,
    analyse,
    default_machine_stl,
)

VERSION = 5  # 5: the published case 2b (default); 4: what is now --variant easy
BASE_Z = 0.30  # m, nominal base height (the robot on a stand)
BASE_XY = 0.30  # m, base tolerance in x and y
BASE_Z_RANGE = (-0.30, 0.30)  # about BASE_Z: 0 … 0.6 m above the floor
MACHINE_GAP = (0.40, 0.60)  # m, nominal base axis to the start of the work area
GOAL_DEPTH = (0.10, 0.60)  # m behind the start of the work area
BASE_COLUMN = 0.20  # m, radius of the space the robot and its stand need around the base axis
GOAL_Z = (0.60, 1.30)  # m above the floor
GOAL_CLEARANCE = 0.05  # m, goal point to the machine mesh
OPENING_SHIFT = 0.20  # m, sideways offset of the chosen opening ray from the robot
UNLOAD_WINDOW = 0.40  # m, unload point within this sideways distance of the chosen ray
TRAY = (0.30, 0.40)  # m, tray footprint (x, y)
TRAY_X = (-0.15, 0.05)
TRAY_Y = (0.45, 0.65)  # |y| of the tray centres
TRAY_TOP = (0.45, 0.80)
ABOVE_TRAY = 0.05
POS_TOL = 0.005
TOOL_DOWN = rot_y(PI)  # tool z axis to -z
TOOL_INTO = rot_y(PI / 2)  # tool z axis to +x (into the machine)
GOAL_TRIES = 120
CELL_TRIES = 300  # most draws end at the cheap room checks


@dataclass(frozen=True)
class Layout:
    """The numbers of one variant of the cell."""
    published: bool
    base_z: float  # m, nominal base height
    machine_gap: Tuple[float, float]  # m, nominal base axis to the start of the work area
    goal_depth: Tuple[float, float]  # m behind the start of the work area
    goal_z: Tuple[float, float]  # m, height of the goals inside the machine
    tray_x: Tuple[float, float]
    tray_y: Tuple[float, float]  # |y| of the tray centres
    tray_top: Tuple[float, float]
    column_above: float  # m: the room kept free of the machine around the base axis reaches this far above the base


EASY = Layout(False, BASE_Z, MACHINE_GAP, GOAL_DEPTH, GOAL_Z, TRAY_X, TRAY_Y, TRAY_TOP, 0.4)
# published case 2b (docs/generators.md): goals 0.15-0.90 m from the nominal base, a fifth of them below its
# plane; the robot stands close to the machine and the trays are pick and place spots beside it (the
# published cell's only obstacle is the machine)
PUBLISHED = Layout(True, 0.58, (0.45, 0.60), (0.05, 0.30), (0.60, 1.05), (-0.20, 0.10), (0.25, 0.50), (0.45, 0.80),
                   0.1)
PUBLISHED_BASE_RANGE = 1.0  # m: x, y, z ± 1 about the nominal base, any rotation


def _pose(p, R, layout: Layout = EASY) -> dict:
    if layout.published:
        return full_pose(transform(p, R))
    t = (-POS_TOL, POS_TOL)
    return tolerated(transform(p, R), x=t, y=t, z=t, N_x=(-0.1, 0.1), N_y=(-0.1, 0.1))


class _Geometric(ObstacleField):
    """The published variant's goal test: collision-free (by the callers) and within the reach bound of the
    reference module set from some allowed base position (no design, no IK)."""

    def __init__(self, task_dict: dict, folder: Path, base: np.ndarray):
        super().__init__(task_dict, folder)
        self.lo, self.hi = base - PUBLISHED_BASE_RANGE, base + PUBLISHED_BASE_RANGE
        self.reach = set_reach_bound()

    def reaches(self, pose: dict) -> bool:
        return box_distance(np.asarray(pose["nominal"])[:3, 3], self.lo, self.hi) <= self.reach


def _machine_source(opts: Dict[str, Any]):
    """(name in assets/, bytes, uniform scale) of the machine mesh."""
    if opts["machine"] is None:
        return DEFAULT_NAME, default_machine_stl(), 1.0
    src = Path(str(opts["machine"]))
    data = copy_file(src)
    scale = str(opts["machine_scale"])
    if scale == "auto":
        return src.name, data, None
    try:
        s = float(scale)
    except ValueError:
        s = math.nan
    if not (s > 0 and math.isfinite(s)):
        raise InputError(f"liu2020 --machine-scale: expected auto or a positive number, got {scale!r}")
    return src.name, data, s


def _auto_scale(file: Path) -> float:
    V = np.concatenate([v for v, _ in load_mesh_arrays(str(file), (1.0, 1.0, 1.0))])
    return 0.001 if float(np.max(V.max(axis=0) - V.min(axis=0))) > 20.0 else 1.0


def _cell(tid: str, prov: Provenance, mesh_ref: str, scale: float, machine_pose: np.ndarray, trays: List[AABB],
          goals: Dict[str, dict], layout: Layout = EASY) -> dict:
    if layout.published:
        r = (-PUBLISHED_BASE_RANGE, PUBLISHED_BASE_RANGE)
        return {
            "header": header(tid, "Liu 2020 case 2b: machine tending (load and unload a CNC machine)", prov,
                             ["Liu 2020", "case 2b", "machineTending"]),
            "obstacles": [
                {"ID": "machine", "name": f"machine ({mesh_ref.split('/')[-1]})",
                 "collision": [{"type": "mesh", "parameters": {"file": mesh_ref, "scale": scale},
                                "pose": machine_pose}]}],
            "constraints": [
                {"type": "basePlacement", "pose": tolerated(transform((0, 0, layout.base_z)), x=r, y=r, z=r)},
                {"type": "joint", "parts": ["q", "tau"]},
                {"type": "collisionFree"},
                {"type": "allGoalsFulfilled"},
                {"type": "allGoalsFulfilledInOrder", "order": list(goals)},
            ],
            "goals": [{"ID": gid, "type": "reach", "goalPose": pose} for gid, pose in goals.items()],
        }
    rb = (-BASE_XY, BASE_XY)
    return {
        "header": header(tid, "Liu 2020 case 2b style: machine tending (load and unload a CNC machine)", prov,
                         ["machineTending", "pickAndPlace"]),
        "obstacles": [
            {"ID": "machine", "name": f"machine ({mesh_ref.split('/')[-1]})",
             "collision": [{"type": "mesh", "parameters": {"file": mesh_ref, "scale": scale}, "pose": machine_pose}]},
        ] + [{"ID": oid, "name": name, "collision": [t.geometry()]}
             for (oid, name), t in zip((("tray_in", "input tray"), ("tray_out", "output tray")), trays)],
        "constraints": [
            {"type": "basePlacement", "pose": tolerated(transform((0, 0, BASE_Z)), x=rb, y=rb, z=BASE_Z_RANGE,
                                                        N_x=(-0.001, 0.001), N_y=(-0.001, 0.001), N_z=(NEG_PI, PI))},
            {"type": "joint", "parts": ["q", "dq", "tau"]},
            {"type": "selfCollisionFree"},
            {"type": "collisionFree"},
            {"type": "allGoalsFulfilled"},
            {"type": "allGoalsFulfilledInOrder", "order": list(goals)},
        ],
        "goals": [{"ID": gid, "type": "reach", "goalPose": pose} for gid, pose in goals.items()],
    }


def _draw_trays(rng, layout: Layout = EASY) -> List[AABB]:
    out = []
    for side in (1, -1):
        c = np.array([rng.uniform(*layout.tray_x), side * rng.uniform(*layout.tray_y), 0.0])
        top = rng.uniform(*layout.tray_top)
        out.append(AABB((c[0] - TRAY[0] / 2, c[1] - TRAY[1] / 2, 0.0), (c[0] + TRAY[0] / 2, c[1] + TRAY[1] / 2, top)))
    return out


def task_id(prov: Provenance, machine: str, layout: Layout = EASY) -> str:
    stem = "".join(ch if ch.isalnum() else "-" for ch in Path(machine).stem)[:24]
    return f"liu2020{'' if layout.published else 'easy'}_case2b_{stem}_s{prov.seed}_{prov.index:04d}"


def build(prov: Provenance, opts: Dict[str, Any], folder: Path) -> GeneratedTask:
    lay = EASY if opts["variant"] == "easy" else PUBLISHED
    name, data, scale = _machine_source(opts)
    asset = f"assets/{name}"
    target = Path(folder) / asset
    if target.exists() and target.read_bytes() != data:
        raise InputError(f"{target} exists with other content: use another --out folder or rename the machine file")
    target.parent.mkdir(parents=True, exist_ok=True)
    if not target.exists():
        target.write_bytes(data)
    if scale is None:
        scale = _auto_scale(target)
    frame = analyse(str(target.resolve()), scale)
    pts = np.array(frame.points).reshape(-1, 3)
    pts = pts[(pts[:, 2] >= lay.goal_z[0]) & (pts[:, 2] <= lay.goal_z[1])]
    if len(pts) == 0:
        raise InputError(f"machine {name}: no work area found at 0.6–1.3 m height (free space with the machine "
                         f"above and below it, in line of sight from one side of its bounding box)")
    # each probe ray (y, z) of the work area: where it enters the work area; anchors are entries with room behind
    rows: Dict[tuple, List[float]] = {}
    for x, y, z in pts:
        rows.setdefault((y, z), []).append(x)
    anchors = np.array([(min(xs), y, z) for (y, z), xs in sorted(rows.items())
                        if max(xs) - min(xs) >= lay.goal_depth[0]]).reshape(-1, 3)
    if len(anchors) == 0:
        raise InputError(f"machine {name}: its work area is nowhere {lay.goal_depth[0]:.2f} m deep")
    rng = prov.rng()
    tid = task_id(prov, name, lay)
    # the machine alone in its analysed frame: the room for the robot and the trays is checked against it
    placed = ObstacleField(_cell(tid, prov, asset, scale, frame.matrix(), [], {}), folder)
    column = coal_cylinder(BASE_COLUMN, lay.base_z + lay.column_above)
    base = np.array([0.0, 0.0, lay.base_z])
    for _ in range(CELL_TRIES):
        anchor = anchors[rng.integers(len(anchors))]
        entry = float(anchor[0])  # where the work area starts along the anchor's probe ray
        gap = rng.uniform(*lay.machine_gap)
        shift = np.array([gap - entry, -anchor[1] + rng.uniform(-OPENING_SHIFT, OPENING_SHIFT), 0.0])
        pose = transform(shift) @ frame.matrix()
        if placed.distance(column, transform(np.array([0.0, 0.0, (lay.base_z + lay.column_above) / 2]) - shift)) <= 0:
            continue  # the robot (and its stand) would stand inside the machine
        trays = _draw_trays(rng, lay)
        if any(placed.distance(coal_box(t), transform(t.centre - shift)) <= 0.02 for t in trays):
            continue
        arm: Union[_Geometric, ReferenceArm]
        if lay.published:
            arm = _Geometric(_cell(tid, prov, asset, scale, pose, [], {}, lay), folder, base)
        else:
            arm = ReferenceArm(_cell(tid, prov, asset, scale, pose, trays, {}), folder,
                               base_pose=transform(base), seed=int(rng.integers(2 ** 31)))
        goals: Dict[str, dict] = {}
        pick = _tray_goal(rng, arm, trays[0], lay)
        if pick is None:
            continue
        goals["pick"] = pick
        near = pts[(np.abs(pts[:, 1] - anchor[1]) <= UNLOAD_WINDOW) & (pts[:, 0] >= entry + lay.goal_depth[0])
                   & (pts[:, 0] <= entry + lay.goal_depth[1])]
        for gid in ("load", "unload"):
            g = _machine_goal(rng, arm, near, shift, frame, lay) if len(near) else None
            if g is None:
                break
            goals[gid] = g
        if len(goals) < 3:
            continue
        place = _tray_goal(rng, arm, trays[1], lay)
        if place is None:
            continue
        goals["place"] = place
        task = _cell(tid, prov, asset, scale, pose, trays, goals, lay)
        if lay.published or verified(task, opts, folder):
            return GeneratedTask(tid, task)
    raise RobodesignError(f"liu2020: no reachable cell in {CELL_TRIES} draws for machine {name} "
                          f"(seed {prov.seed}, index {prov.index})")


def coal_cylinder(r: float, h: float):
    import coal
    return coal.Cylinder(r, h)


def coal_box(b: AABB):
    return coal_box_size(*(np.asarray(b.hi) - np.asarray(b.lo)))


def coal_box_size(x: float, y: float, z: float):
    import coal
    return coal.Box(float(x), float(y), float(z))


def _tray_goal(rng, arm: Union[_Geometric, ReferenceArm], tray: AABB, layout: Layout = EASY):
    for _ in range(GOAL_TRIES // 4):
        p = np.array([rng.uniform(tray.lo[0] + 0.06, tray.hi[0] - 0.06),
                      rng.uniform(tray.lo[1] + 0.06, tray.hi[1] - 0.06), tray.hi[2] + ABOVE_TRAY])
        if layout.published and arm.clearance(p) < GOAL_CLEARANCE:
            continue
        pose = _pose(p, TOOL_DOWN, layout)
        if arm.reaches(pose):
            return pose
    return None


def _machine_goal(rng, arm: Union[_Geometric, ReferenceArm], near: np.ndarray, shift: np.ndarray, frame: MachineFrame,
                  layout: Layout = EASY):
    """A work-area grid point near the anchor, jittered within its grid cell, in world coordinates."""
    for _ in range(GOAL_TRIES):
        p = near[rng.integers(len(near))] + shift + rng.uniform(-STEP / 2, STEP / 2, 3)
        if arm.clearance(p) < GOAL_CLEARANCE:
            continue
        # still inside after the jitter: machine above and below (thin vertical prisms, as in machine.analyse)
        if arm.distance(coal_box_size(0.002, 0.002, COVER_UP), transform(p + [0, 0, COVER_UP / 2])) > 0 or \
                arm.distance(coal_box_size(0.002, 0.002, COVER_DOWN), transform(p - [0, 0, COVER_DOWN / 2])) > 0:
            continue
        pose = _pose(p, TOOL_INTO, layout)
        if arm.reaches(pose):
            return pose
    return None


FAMILY = Family(
    name="liu2020",
    version=VERSION,
    summary="machine tending (case 2b): pick → load/unload inside a CNC machine mesh → place, full-pose goals "
            "(±1 mm, 0.5°) in order; base free ±1 m, any rotation (--variant easy: trays, ±5 mm, tool axis ±0.1)",
    options=(
        VARIANT,
        Option("machine", str, None, "machine mesh file (STL, …), copied into <out>/assets/ (default: a box-built "
                                     "CNC housing written by the generator)", path=True),
        Option("machine_scale", str, "auto", "uniform scale of --machine to metres; auto: 0.001 if the mesh is "
                                             "larger than 20 units (millimetres), else 1"),
        VERIFY,
    ),
    build=build,
)
