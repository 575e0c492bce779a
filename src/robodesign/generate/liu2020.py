"""liu2020: machine tending, after Liu and Althoff (2020), "Optimizing performance in automation through
modular robots", case 2b: load a part into a CNC machine's work area and unload it.

The cell: a machine mesh (``--machine FILE``, copied into ``<out>/assets/``; default a box-built CNC
housing the generator writes itself) turned so that its open side faces the robot (machine.analyse), its
front face ``MACHINE_GAP`` m in front of the nominal base, shifted sideways so a randomly chosen part of the
opening is in front of the robot; an input and an output tray left and right of the robot.

Goals, in order: ``pick`` above the input tray (tool down) → ``load`` inside the machine (tool pointing
into it) → ``unload`` at another point inside the machine → ``place`` above the output tray. Positions
±5 mm; the tool axis within ±0.1 (N_x, N_y) of the nominal, the rotation about it free.
The base is free in a region in front of the machine: x, y ± ``BASE_XY``, height 0–0.6 m above the floor
(the stand is not modelled), any yaw.

Machine goals lie on probe rays into the opening (free line of sight from the front), at least
``GOAL_DEPTH[0]`` behind the machine's front face, ``GOAL_CLEARANCE`` from the mesh, and are reachable
by the reference arm (common.ReferenceArm) from the nominal base; tray goals likewise.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Dict, List

import numpy as np

from ..errors import InputError, RobodesignError
from .common import PI, AABB, Provenance, ReferenceArm, header, rot_y, solved_by_reference, tolerated, transform
from .machine import DEFAULT_NAME, MachineFrame, analyse, default_machine_stl
from .registry import VERIFY, Family, GeneratedTask, Option, copy_file

VERSION = 2
BASE_Z = 0.30  # m, nominal base height (the robot on a stand)
BASE_XY = 0.30  # m, base tolerance in x and y
BASE_Z_RANGE = (-0.30, 0.30)  # about BASE_Z: 0 … 0.6 m above the floor
MACHINE_GAP = (0.40, 0.60)  # m, nominal base axis to the machine's front face
GOAL_DEPTH = (0.15, 0.60)  # m behind the front face
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
CELL_TRIES = 40


def _pose(p, R) -> dict:
    t = (-POS_TOL, POS_TOL)
    return tolerated(transform(p, R), x=t, y=t, z=t, N_x=(-0.1, 0.1), N_y=(-0.1, 0.1))


def _machine_source(opts: Dict[str, object]):
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
    from ..geometry import load_mesh_arrays
    V = np.concatenate([v for v, _ in load_mesh_arrays(str(file), (1.0, 1.0, 1.0))])
    return 0.001 if float(np.max(V.max(axis=0) - V.min(axis=0))) > 20.0 else 1.0


def _cell(tid: str, prov: Provenance, mesh_ref: str, scale: float, machine_pose: np.ndarray, trays: List[AABB],
          goals: Dict[str, dict]) -> dict:
    rb = (-BASE_XY, BASE_XY)
    return {
        "header": header(tid, "Liu 2020 case 2b style: machine tending (load and unload a CNC machine)", prov,
                         ["machineTending", "pickAndPlace"]),
        "obstacles": [
            {"ID": "machine", "name": f"machine ({mesh_ref.split('/')[-1]})",
             "collision": [{"type": "mesh", "parameters": {"file": mesh_ref, "scale": scale}, "pose": machine_pose}]},
            {"ID": "tray_in", "name": "input tray", "collision": [trays[0].geometry()]},
            {"ID": "tray_out", "name": "output tray", "collision": [trays[1].geometry()]},
        ],
        "constraints": [
            {"type": "basePlacement", "pose": tolerated(transform((0, 0, BASE_Z)), x=rb, y=rb, z=BASE_Z_RANGE,
                                                        N_x=(-0.001, 0.001), N_y=(-0.001, 0.001), N_z=(-PI, PI))},
            {"type": "joint", "parts": ["q", "dq", "tau"]},
            {"type": "selfCollisionFree"},
            {"type": "collisionFree"},
            {"type": "allGoalsFulfilled"},
            {"type": "allGoalsFulfilledInOrder", "order": list(goals)},
        ],
        "goals": [{"ID": gid, "type": "reach", "goalPose": pose} for gid, pose in goals.items()],
    }


def _draw_trays(rng) -> List[AABB]:
    out = []
    for side in (1, -1):
        c = np.array([rng.uniform(*TRAY_X), side * rng.uniform(*TRAY_Y), 0.0])
        top = rng.uniform(*TRAY_TOP)
        out.append(AABB((c[0] - TRAY[0] / 2, c[1] - TRAY[1] / 2, 0.0), (c[0] + TRAY[0] / 2, c[1] + TRAY[1] / 2, top)))
    return out


def task_id(prov: Provenance, machine: str) -> str:
    stem = "".join(ch if ch.isalnum() else "-" for ch in Path(machine).stem)[:24]
    return f"liu2020_case2b_{stem}_s{prov.seed}_{prov.index:04d}"


def build(prov: Provenance, opts: Dict[str, object], folder: Path) -> GeneratedTask:
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
    rays = np.array(frame.rays)
    usable = rays[(rays[:, 2] >= GOAL_DEPTH[0] + 0.10) & (rays[:, 1] >= GOAL_Z[0]) & (rays[:, 1] <= GOAL_Z[1])]
    if len(usable) == 0:
        raise InputError(f"machine {name}: no opening found at working height (0.6–1.3 m) that is at least "
                         f"{GOAL_DEPTH[0] + 0.1:.2f} m deep from any side")
    rng = prov.rng()
    tid = task_id(prov, name)
    for _ in range(CELL_TRIES):
        gap = rng.uniform(*MACHINE_GAP)
        ray = usable[rng.integers(len(usable))]
        dy = -ray[0] + rng.uniform(-OPENING_SHIFT, OPENING_SHIFT)  # world y = frame y + dy
        pose = transform((gap, dy, 0.0)) @ frame.matrix()
        trays = _draw_trays(rng)
        arm = ReferenceArm(_cell(tid, prov, asset, scale, pose, trays, {}), folder,
                           base_pose=transform((0, 0, BASE_Z)), seed=int(rng.integers(2 ** 31)))
        goals: Dict[str, dict] = {}
        tray_in, tray_out = trays
        pick = _tray_goal(rng, arm, tray_in)
        if pick is None:
            continue
        goals["pick"] = pick
        for gid in ("load", "unload"):
            g = _machine_goal(rng, arm, usable, gap, dy, ray[0])
            if g is None:
                break
            goals[gid] = g
        if len(goals) < 3:
            continue
        place = _tray_goal(rng, arm, tray_out)
        if place is None:
            continue
        goals["place"] = place
        task = _cell(tid, prov, asset, scale, pose, trays, goals)
        if opts["verify"] == "ik" or solved_by_reference(task, folder):
            return GeneratedTask(tid, task)
    raise RobodesignError(f"liu2020: no reachable cell in {CELL_TRIES} draws for machine {name} "
                          f"(seed {prov.seed}, index {prov.index})")


def _tray_goal(rng, arm: ReferenceArm, tray: AABB):
    for _ in range(GOAL_TRIES // 4):
        p = np.array([rng.uniform(tray.lo[0] + 0.06, tray.hi[0] - 0.06),
                      rng.uniform(tray.lo[1] + 0.06, tray.hi[1] - 0.06), tray.hi[2] + ABOVE_TRAY])
        pose = _pose(p, TOOL_DOWN)
        if arm.reaches(pose):
            return pose
    return None


def _machine_goal(rng, arm: ReferenceArm, usable: np.ndarray, gap: float, dy: float, y_ray: float):
    near = usable[np.abs(usable[:, 0] - y_ray) <= UNLOAD_WINDOW]
    for _ in range(GOAL_TRIES):
        y, z, depth = near[rng.integers(len(near))]
        u = rng.uniform(GOAL_DEPTH[0], min(GOAL_DEPTH[1], depth - 0.10))
        p = np.array([gap + u, y + dy, z])
        if arm.clearance(p) < GOAL_CLEARANCE:
            continue
        pose = _pose(p, TOOL_INTO)
        if arm.reaches(pose):
            return pose
    return None


FAMILY = Family(
    name="liu2020",
    version=VERSION,
    summary="machine tending (case 2b): trays → load/unload inside a CNC machine mesh → tray; base free in front",
    options=(
        Option("machine", str, None, "machine mesh file (STL, …), copied into <out>/assets/ (default: a box-built "
                                     "CNC housing written by the generator)", path=True),
        Option("machine_scale", str, "auto", "uniform scale of --machine to metres; auto: 0.001 if the mesh is "
                                             "larger than 20 units (millimetres), else 1"),
        VERIFY,
    ),
    build=build,
)
