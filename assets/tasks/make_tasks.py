#!/usr/bin/env python
"""Write robodesign's built-in CoBRA tasks (``assets/tasks/robodesign/<name>.json``) and solve each once.

    .venv/bin/python assets/tasks/make_tasks.py                 # write the tasks, then solve each (seed 0)
    .venv/bin/python assets/tasks/make_tasks.py --seeds 0,1,2   # ... and check that several seeds solve
    .venv/bin/python assets/tasks/make_tasks.py --no-solve      # only write
    .venv/bin/python assets/tasks/make_tasks.py --out /tmp/sol  # also write the solutions there

Every number of every task is defined here; the files are written deterministically (fixed date,
values rounded to 10 decimals, fixed formatting), so re-running gives byte-identical files. Edit this
script, never the JSON files. Solutions are never written into ``assets/`` (the tests produce them).

The package root is ``assets/tasks/`` (task ID ``robodesign/<name>`` → ``assets/tasks/robodesign/<name>.json``).
All cells are sized for the built-in ``robodesign_arm`` in its default order (``DEFAULT_ORDER``, reach
≈ 0.98 m from the shoulder at z = 0.372 m, TCP at z = 1.355 m at q = 0), mounted at the world origin
unless ``SOLVE_SETUP`` says otherwise.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path
from typing import List, Optional, Sequence

import numpy as np

# the writer (floats rounded to 10 decimals, fixed layout) is shared with `robodesign generate`
from robodesign.generate.common import NEG_PI, PI, dumps
from robodesign.generate.common import clean as _clean

HERE = Path(__file__).resolve().parent
PACKAGE = "robodesign"
DATE = "2025-06-01"
DT = 0.01
DEFAULT_ORDER = ("1", "21", "22", "4", "22", "3", "23", "24", "23", "12")
MODULE_SET = "robodesign_arm"

# ---------------------------------------------------------------------------------------------------------
# small pose helpers
# ---------------------------------------------------------------------------------------------------------



def rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]], dtype=float)


def ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]], dtype=float)


def rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], dtype=float)


def T(p=(0, 0, 0), R=None) -> np.ndarray:
    M = np.eye(4)
    if R is not None:
        M[:3, :3] = R
    M[:3, 3] = p
    return M


# Tool orientations in the arm's natural (zero-roll) wrist posture when it reaches along +x: the tool
# x axis points back at the robot (down) resp. down (forward). The wrist rolls are limited to ±170°, so a
# tool rotated by π about its own axis would need the arm to reach over its back.
TOOL_DOWN = ry(PI)  # tool z axis pointing to -z, tool x to -x
TOOL_FWD = ry(PI / 2)  # tool z axis pointing to +x, tool x to -z


def tolerated(nominal: np.ndarray, **tol) -> dict:
    """A ToleratedPose dict; keyword = projection name, value = (lo, hi). A value ``(lo, hi, frame)``
    sets the toleranceFrame of that entry."""
    out = {"nominal": nominal}
    if tol:
        out["toleranceProjection"] = list(tol)
        out["tolerance"] = [list(v[:2]) for v in tol.values()]
        frames = [v[2] if len(v) > 2 else "nominal" for v in tol.values()]
        if any(f != "nominal" for f in frames):
            out["toleranceFrame"] = frames
    return out


def box(center, size, R=None) -> dict:
    return {"type": "box", "parameters": {"x": size[0], "y": size[1], "z": size[2]}, "pose": T(center, R)}


def box_between(lo, hi) -> dict:
    """Axis-aligned box from corner ``lo`` to corner ``hi`` (world)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    return box((lo + hi) / 2, hi - lo)


def cylinder(center, r, length, R=None) -> dict:
    return {"type": "cylinder", "parameters": {"r": r, "z": length}, "pose": T(center, R)}


def obstacle(oid: str, name: str, geoms: Sequence[dict], **extra) -> dict:
    out = {"ID": oid, "name": name, "collision": list(geoms)}
    out.update(extra)
    return out


def header(name: str, title: str, tags: Sequence[str]) -> dict:
    return {"ID": f"{PACKAGE}/{name}", "version": "2023", "taskName": title, "tags": ["robodesign", *tags],
            "date": DATE, "timeStepSize": DT, "gravity": [0.0, 0.0, -9.81], "author": ["robodesign"],
            "affiliation": ["robodesign project"]}


def bin_geoms(center_xy, floor_z, outer=(0.24, 0.20, 0.12), wall=0.01) -> List[dict]:
    """An open box (bin): a bottom plate and four walls."""
    cx, cy = center_xy
    ox, oy, oz = outer
    g = [box((cx, cy, floor_z + wall / 2), (ox, oy, wall))]
    zc = floor_z + oz / 2
    for s in (-1, 1):
        g.append(box((cx + s * (ox - wall) / 2, cy, zc), (wall, oy, oz)))
        g.append(box((cx, cy + s * (oy - wall) / 2, zc), (ox - 2 * wall, wall, oz)))
    return g


# ---------------------------------------------------------------------------------------------------------
# 1. pick_and_place — the default demo
# ---------------------------------------------------------------------------------------------------------
PP_TABLE_TOP = 0.20
PP_BIN_A = (0.45, 0.30)
PP_BIN_B = (0.45, -0.30)
PP_BIN_H = 0.12


def pick_and_place() -> dict:
    top = PP_TABLE_TOP
    rim = top + PP_BIN_H
    tool = dict(x=(-0.005, 0.005), y=(-0.005, 0.005), z=(-0.005, 0.005),  # 5 mm box
                N_x=(-0.05, 0.05), N_y=(-0.05, 0.05))  # tool down, free rotation about the tool axis
    return {
        "header": header("pick_and_place", "Pick and place between two bins", ["pickAndPlace", "demo"]),
        "obstacles": [
            obstacle("table", "table", [box_between((0.30, -0.60, 0.0), (0.80, 0.60, top))]),
            obstacle("bin_A", "bin A (pick)", bin_geoms(PP_BIN_A, top)),
            obstacle("bin_B", "bin B (place)", bin_geoms(PP_BIN_B, top)),
        ],
        "constraints": [
            {"type": "validAssembly"},
            {"type": "basePlacement", "pose": tolerated(T(), x=(-0.001, 0.001), y=(-0.001, 0.001),
                                                         z=(-0.001, 0.001), Theta_R=(0.0, 0.01))},
            {"type": "joint", "parts": ["q", "dq", "ddq", "tau"]},
            {"type": "collisionFree", "safety_margin": 0.01},
            {"type": "allGoalsFulfilled"},
            {"type": "allGoalsFulfilledInOrder", "order": ["pick", "place", "back"]},
        ],
        "goals": [
            {"ID": "pick", "type": "reach", "goalPose": tolerated(T((*PP_BIN_A, rim + 0.04), TOOL_DOWN), **tool)},
            {"ID": "place", "type": "reach", "goalPose": tolerated(T((*PP_BIN_B, rim + 0.04), TOOL_DOWN), **tool)},
            {"ID": "back", "type": "returnTo"},  # back to the configuration at t = 0
        ],
    }


# ---------------------------------------------------------------------------------------------------------
# 2. machine_tending — load a part through the open door of a CNC machine
# ---------------------------------------------------------------------------------------------------------
MT_FRONT = 0.50  # x of the machine's front face
MT_BACK = 1.10
MT_HALF_W = 0.40
MT_BED = 0.40  # bed (table) height inside the machine
MT_ROOF = 1.10
MT_DOOR = (-0.30, 0.30, MT_BED, 1.00)  # opening: y_lo, y_hi, z_lo, z_hi
MT_INSIDE = (0.72, 0.0, 0.60)  # TCP inside the machine (part held in front of the vise)
MT_REGION_R = 0.30
MT_OUTSIDE = (0.32, -0.12, 0.45)


def machine_tending() -> dict:
    f, b, w, wall = MT_FRONT, MT_BACK, MT_HALF_W, 0.02
    ylo, yhi, zlo, zhi = MT_DOOR
    housing = [
        box_between((f, -w, 0.0), (b, w, MT_BED)),  # machine bed
        box_between((b - wall, -w, MT_BED), (b, w, MT_ROOF)),  # back wall
        box_between((f, -w, MT_BED), (b, -w + wall, MT_ROOF)),  # side walls
        box_between((f, w - wall, MT_BED), (b, w, MT_ROOF)),
        box_between((f, -w, MT_ROOF - wall), (b, w, MT_ROOF)),  # roof
        box_between((f, -w, MT_BED), (f + wall, ylo, MT_ROOF)),  # front: door jambs and lintel
        box_between((f, yhi, MT_BED), (f + wall, w, MT_ROOF)),
        box_between((f, ylo, zhi), (f + wall, yhi, MT_ROOF)),
    ]
    door = [box_between((f - 0.035, yhi, zlo), (f - 0.015, yhi + 0.55, zhi))]  # sliding door, open
    vise = [box((0.86, 0.0, MT_BED + 0.05), (0.12, 0.16, 0.10)), cylinder((0.96, 0.0, MT_BED + 0.08), 0.02, 0.16, rx(PI / 2))]
    inside = T(MT_INSIDE, TOOL_FWD)
    return {
        "header": header("machine_tending", "Machine tending: load a CNC machine", ["machineTending"]),
        "obstacles": [
            obstacle("cnc_housing", "CNC machine housing (door open)", housing),
            obstacle("cnc_door", "sliding door (open)", door),
            obstacle("vise", "vise on the machine bed", vise),
        ],
        "constraints": [
            {"type": "joint", "parts": ["q", "dq", "tau"]},
            {"type": "selfCollisionFree"},
            {"type": "collisionFree", "safety_margin": 0.005},
            {"type": "allGoalsFulfilled"},
            {"type": "allGoalsFulfilledInOrder", "order": ["approach", "load", "hold", "home", "clear"]},
        ],
        "goals": [
            {"ID": "approach", "type": "at",
             "goalPose": tolerated(T(MT_OUTSIDE, TOOL_DOWN), r_sph=(0.0, 0.01), Theta_R=(0.0, 0.1))},
            {"ID": "load", "type": "at", "goalPose": tolerated(inside, r_sph=(0.0, 0.005), Theta_R=(0.0, 0.05))},
            {"ID": "hold", "type": "pause", "duration": 1.0},
            {"ID": "home", "type": "returnTo"},
            {"ID": "clear", "type": "leave", "duration": 0.5,
             "region": tolerated(inside, r_sph=(0.0, MT_REGION_R))},
        ],
    }


# ---------------------------------------------------------------------------------------------------------
# 3. welding_seam — follow a straight seam on a workpiece under a contact force
# ---------------------------------------------------------------------------------------------------------
WS_TABLE_TOP = 0.30
WS_TOP = 0.40  # workpiece top face
WS_SEAM_X = 0.50
WS_SEAM_Y = (-0.07, 0.07)  # within ±8° of the +x axis: the arm cannot switch to its flipped shoulder branch
WS_N = 8  # seam poses (2 cm apart)
WS_STICKOUT = 0.015  # TCP (wire tip) above the seam
WS_FORCE = [0.0, 0.0, 20.0]  # N, world frame: the workpiece pushes back on the torch


def seam_poses() -> List[np.ndarray]:
    ys = np.linspace(*WS_SEAM_Y, WS_N)
    return [T((WS_SEAM_X, y, WS_TOP + WS_STICKOUT), TOOL_DOWN) for y in ys]


def welding_seam() -> dict:
    poses = seam_poses()
    seam_tol = dict(r_sph=(0.0, 0.003), Theta_R=(0.0, 0.05))
    mid = T((WS_SEAM_X, 0.0, WS_TOP + WS_STICKOUT), TOOL_DOWN)
    half = (WS_SEAM_Y[1] - WS_SEAM_Y[0]) / 2
    # around the seam line: ±5 mm across and in height, the seam's length ±5 mm along it (world axes)
    line = tolerated(mid, x=(-0.005, 0.005, "world"), y=(-half - 0.005, half + 0.005, "world"),
                     z=(-0.005, 0.005, "world"), Theta_R=(0.0, 0.08))
    return {
        "header": header("welding_seam", "Weld a straight seam", ["welding", "follow", "externalForce"]),
        "obstacles": [
            obstacle("table", "welding table", [box_between((0.25, -0.45, 0.0), (0.85, 0.45, WS_TABLE_TOP))]),
            obstacle("workpiece", "workpiece (seam on the top face)",
                     [box_between((WS_SEAM_X - 0.10, -0.20, WS_TABLE_TOP), (WS_SEAM_X + 0.10, 0.20, WS_TOP))]),
            obstacle("clamp", "clamp", [box_between((WS_SEAM_X + 0.02, -0.20, WS_TOP), (WS_SEAM_X + 0.10, -0.14, WS_TOP + 0.04)),
                                        box_between((WS_SEAM_X + 0.02, 0.14, WS_TOP), (WS_SEAM_X + 0.10, 0.20, WS_TOP + 0.04))]),
        ],
        "constraints": [
            {"type": "joint", "parts": "q, dq, ddq, tau"},
            {"type": "collisionFree", "safety_margin": 0.005},
            {"type": "allGoalsFulfilled"},
            {"type": "allGoalsFulfilledInOrder", "order": ["seam_start", "weld", "retreat"]},
        ],
        "goals": [
            {"ID": "seam_start", "type": "reach", "goalPose": tolerated(poses[0], **seam_tol)},
            {"ID": "weld", "type": "follow", "trajectory": {"pose": [tolerated(P, **seam_tol) for P in poses]},
             "externalForce": WS_FORCE, "externalTorque": [0.0, 0.0, 0.0], "forceTorqueReferenceFrame": "world",
             "constraints": [{"type": "endEffector", "v_max": 0.5, "pose": line}]},
            {"ID": "retreat", "type": "reach",
             "goalPose": tolerated(T((WS_SEAM_X - 0.07, WS_SEAM_Y[1], WS_TOP + 0.12), TOOL_DOWN), r_sph=(0.0, 0.01),
                                   N_x=(-0.1, 0.1), N_y=(-0.1, 0.1))},
        ],
    }


# ---------------------------------------------------------------------------------------------------------
# 4. base_placement — goals out of reach from the nominal base, reachable from a shifted one
# ---------------------------------------------------------------------------------------------------------
BP_BASE = (0.35, 0.0, 0.0)  # the base position SOLVE_SETUP uses (inside the tolerance)
BP_FIXTURE = (1.20, 0.15, 0.55)  # tool +x into a fixture on a machine face (x = 1.25)
BP_SHELF = (0.30, -0.70, 0.50)  # tool -y into a shelf
BP_TRAY = (0.75, 0.25, 0.30)  # tool down onto a tray
BP_CONVEYOR_Y = 0.65
BP_BELT_TOP = 0.30
BP_PART = 0.12  # edge of the cube sliding along the conveyor
BP_DURATION = 10.0


def conveyor_motion() -> dict:
    """The part slides along the belt (+x) from x = 0.1 to x = 1.3 in 10 s, one pose per time step
    (the transform is applied to the part's pose at t = 0)."""
    n = int(round(BP_DURATION / DT)) + 1
    xs = np.linspace(0.0, 1.2, n)
    return {"t": DT, "pose": [T((x, 0.0, 0.0)) for x in xs]}


def base_placement() -> dict:
    y0 = BP_CONVEYOR_Y
    tol = dict(r_sph=(0.0, 0.005), Theta_R=(0.0, 0.05))
    return {
        "header": header("base_placement", "Place the base so that every station is reachable",
                         ["basePlacement", "movingObstacle"]),
        "obstacles": [
            obstacle("machine", "machine (fixture face at x = 1.25)",
                     [box_between((1.25, -0.30, 0.0), (1.65, 0.60, 1.10))]),
            obstacle("shelf", "shelf", [box_between((0.05, -1.05, 0.0), (0.55, -0.75, 0.42)),  # lower cabinet
                                        box_between((0.05, -1.05, 0.42), (0.55, -1.00, 0.80)),  # back panel
                                        box_between((0.05, -1.05, 0.78), (0.55, -0.75, 0.80))]),  # top board
            obstacle("tray_table", "tray table", [box_between((0.55, 0.05, 0.0), (0.95, 0.45, 0.20))]),
            obstacle("conveyor", "conveyor belt", [box_between((-0.60, y0 - 0.15, 0.0), (1.40, y0 + 0.15, BP_BELT_TOP))]),
            obstacle("part", "part on the conveyor (moving)",
                     [box((0.10, y0, BP_BELT_TOP + BP_PART / 2 + 0.002), (BP_PART, BP_PART, BP_PART))],
                     trajectory=conveyor_motion()),
        ],
        "constraints": [
            {"type": "basePlacement", "pose": tolerated(T(), x=(-0.4, 0.4), y=(-0.4, 0.4), z=(0.0, 0.0),
                                                         N_x=(-0.001, 0.001), N_y=(-0.001, 0.001), N_z=(NEG_PI, PI))},
            {"type": "joint", "parts": ["q", "dq", "tau"]},
            {"type": "collisionFree", "safety_margin": 0.01},
            {"type": "allGoalsFulfilled"},
        ],
        "goals": [
            {"ID": "fixture", "type": "reach", "goalPose": tolerated(T(BP_FIXTURE, TOOL_FWD), **tol)},
            {"ID": "shelf", "type": "reach",
             "goalPose": tolerated(T(BP_SHELF, rz(-PI / 2) @ TOOL_FWD), **tol)},
            {"ID": "tray", "type": "at",
             "goalPose": tolerated(T(BP_TRAY, TOOL_DOWN), r_sph=(0.0, 0.005), N_x=(-0.05, 0.05), N_y=(-0.05, 0.05))},
        ],
    }


# ---------------------------------------------------------------------------------------------------------
# 5. timed_follow — dispense glue along an arc with a given timing
# ---------------------------------------------------------------------------------------------------------
TF_TABLE_TOP = 0.25
TF_CENTER = (0.50, 0.0)
TF_RADIUS = 0.07
TF_N = 9
TF_STEP = 0.40  # s between poses


def glue_poses() -> List[np.ndarray]:
    angles = np.linspace(-PI / 2, PI / 2, TF_N)
    cx, cy = TF_CENTER
    return [T((cx + TF_RADIUS * math.cos(a), cy + TF_RADIUS * math.sin(a), TF_TABLE_TOP + 0.03 + 0.01), TOOL_DOWN)
            for a in angles]


def timed_follow() -> dict:
    poses = glue_poses()
    tol = dict(r_sph=(0.0, 0.003), N_x=(-0.05, 0.05), N_y=(-0.05, 0.05))
    return {
        "header": header("timed_follow", "Dispense glue along an arc (timed)", ["follow", "timed"]),
        "obstacles": [
            obstacle("table", "table", [box_between((0.25, -0.40, 0.0), (0.75, 0.40, TF_TABLE_TOP))]),
            obstacle("plate", "workpiece plate", [cylinder((*TF_CENTER, TF_TABLE_TOP + 0.015), 0.14, 0.03)]),
        ],
        "constraints": [
            {"type": "joint", "parts": ["q", "dq", "ddq", "tau"]},
            {"type": "selfCollisionFree"},
            {"type": "collisionFree", "safety_margin": 0.005},
            {"type": "allGoalsFulfilled"},
        ],
        "goals": [
            {"ID": "dispense", "type": "follow",
             "trajectory": {"pose": [tolerated(P, **tol) for P in poses],
                            "t": [round(k * TF_STEP, 10) for k in range(TF_N)]}},
            {"ID": "home", "type": "returnTo"},
        ],
    }


# ---------------------------------------------------------------------------------------------------------
# 6. wait_for_shuttle — a moving obstacle parks over the place station: the robot must wait for it
# ---------------------------------------------------------------------------------------------------------
SH_TABLE_TOP = 0.20
SH_PICK = (0.50, 0.35, SH_TABLE_TOP + 0.10)
SH_PLACE = (0.50, -0.35, SH_TABLE_TOP + 0.10)
SH_SHUTTLE = 0.30  # cube edge
SH_PARKED_UNTIL = 2.0  # s: the shuttle covers the place station until then ...
SH_LEAVE = 1.0  # s: ... then drives off along +x in this time, and stays out of reach
SH_STEP = 0.1  # s between shuttle poses


def shuttle_motion() -> dict:
    """The shuttle sits over the place station until ``SH_PARKED_UNTIL``, then drives 1.5 m along +x in
    ``SH_LEAVE`` s (one pose every ``SH_STEP`` s, applied to its pose at t = 0) and stays there."""
    n = int(round((SH_PARKED_UNTIL + SH_LEAVE) / SH_STEP)) + 1
    ts = np.arange(n) * SH_STEP
    xs = np.clip((ts - SH_PARKED_UNTIL) / SH_LEAVE, 0.0, 1.0) * 1.5
    return {"t": SH_STEP, "pose": [T((x, 0.0, 0.0)) for x in xs]}


def wait_for_shuttle() -> dict:
    top = SH_TABLE_TOP
    tol = dict(r_sph=(0.0, 0.005), N_x=(-0.05, 0.05), N_y=(-0.05, 0.05))
    return {
        "header": header("wait_for_shuttle", "Place a part once the shuttle has left the station",
                         ["movingObstacle", "wait"]),
        "obstacles": [
            obstacle("table", "table", [box_between((0.30, -0.60, 0.0), (0.75, 0.60, top))]),
            obstacle("shuttle", "shuttle parked over the place station (moving)",
                     [box((SH_PLACE[0], SH_PLACE[1], top + SH_SHUTTLE / 2 + 0.002), (SH_SHUTTLE,) * 3)],
                     trajectory=shuttle_motion()),
        ],
        "constraints": [
            {"type": "joint", "parts": ["q", "dq", "tau"]},
            {"type": "selfCollisionFree"},
            {"type": "collisionFree", "safety_margin": 0.005},
            {"type": "allGoalsFulfilled"},
            {"type": "allGoalsFulfilledInOrder", "order": ["pick", "place"]},
        ],
        "goals": [
            {"ID": "pick", "type": "reach", "goalPose": tolerated(T(SH_PICK, TOOL_DOWN), **tol)},
            {"ID": "place", "type": "reach", "goalPose": tolerated(T(SH_PLACE, TOOL_DOWN), **tol)},
        ],
    }


TASKS = {
    "pick_and_place": pick_and_place,
    "machine_tending": machine_tending,
    "welding_seam": welding_seam,
    "base_placement": base_placement,
    "timed_follow": timed_follow,
    "wait_for_shuttle": wait_for_shuttle,
}

# ---------------------------------------------------------------------------------------------------------
# Collaborative tasks (package robodesign-collab/, docs/collaborative.md): several robots in one cell
# ---------------------------------------------------------------------------------------------------------
COLLAB_PACKAGE = "robodesign-collab"
SC_BELT_TOP = 0.20
SC_BASE_Y = 0.45  # the two arms stand on either side of the belt, facing it
SC_Z = SC_BELT_TOP + 0.10


def shared_conveyor() -> dict:
    """Two arms on either side of a conveyor belt, both working over the belt: each has its own pick and
    place goals, and one inspection goal above the middle of the belt may be done by either."""
    tol = dict(r_sph=(0.0, 0.005), N_x=(-0.05, 0.05), N_y=(-0.05, 0.05))
    base_tol = dict(r_sph=(0.0, 0.001), Theta_R=(0.0, 0.01))

    def goal(gid, p, robot):
        """Tool down, its x axis pointing back at the robot's base (the natural wrist posture)."""
        by = SC_BASE_Y if robot == "left" else -SC_BASE_Y
        R = rz(math.atan2(by - p[1], -p[0])) @ TOOL_DOWN
        return {"ID": gid, "type": "reach", "robot": robot, "goalPose": tolerated(T(p, R), **tol)}
    h = header("shared_conveyor", "Two arms share a conveyor belt", ["collaborative"])
    h["ID"] = f"{COLLAB_PACKAGE}/shared_conveyor"
    return {
        "header": h,
        "robots": [
            {"ID": "left", "name": "arm at y = +0.45 m", "basePlacement": tolerated(T((0.0, SC_BASE_Y, 0.0), rz(-PI / 2)),
                                                                                   **base_tol)},
            {"ID": "right", "name": "arm at y = -0.45 m", "basePlacement": tolerated(T((0.0, -SC_BASE_Y, 0.0), rz(PI / 2)),
                                                                                    **base_tol)},
        ],
        "obstacles": [obstacle("belt", "conveyor belt", [box_between((-0.9, -0.15, 0.0), (0.9, 0.15, SC_BELT_TOP))])],
        "constraints": [
            {"type": "joint", "parts": ["q", "dq", "tau"]},
            {"type": "selfCollisionFree"},
            {"type": "collisionFree", "safety_margin": 0.01},
            {"type": "allGoalsFulfilled"},
        ],
        "goals": [
            goal("left_pick", (-0.25, 0.0, SC_Z), "left"),
            goal("left_place", (0.25, 0.0, SC_Z), "left"),
            goal("right_pick", (0.25, 0.0, SC_Z), "right"),
            goal("right_place", (-0.25, 0.0, SC_Z), "right"),
            {"ID": "inspect", "type": "reach", "robot": None,  # any robot; the TCP within 1 cm, any orientation
             "goalPose": tolerated(T((0.0, 0.0, SC_Z + 0.15)), r_sph=(0.0, 0.01))},
            {"ID": "left_home", "type": "returnTo", "robot": "left"},  # back to the start, out of the way
            {"ID": "right_home", "type": "returnTo", "robot": "right"},
        ],
    }


COLLAB_TASKS = {"shared_conveyor": shared_conveyor}
COLLAB_SOLVE_SETUP = {"shared_conveyor": {"left": DEFAULT_ORDER, "right": DEFAULT_ORDER, "seed": 0}}


def collab_task_path(name: str) -> Path:
    return HERE / COLLAB_PACKAGE / f"{name}.json"


# How each task is solved (by make_tasks.py and tests/test_builtin_tasks.py): module order, base
# position (x, y, z), yaw [rad] and solver seed.
SOLVE_SETUP = {
    "pick_and_place": {"order": DEFAULT_ORDER, "base": (0.0, 0.0, 0.0), "yaw": 0.0, "seed": 0},
    "machine_tending": {"order": DEFAULT_ORDER, "base": (0.0, 0.0, 0.0), "yaw": 0.0, "seed": 0},
    "welding_seam": {"order": DEFAULT_ORDER, "base": (0.0, 0.0, 0.0), "yaw": 0.0, "seed": 0},
    "base_placement": {"order": DEFAULT_ORDER, "base": BP_BASE, "yaw": 0.0, "seed": 0},
    "timed_follow": {"order": DEFAULT_ORDER, "base": (0.0, 0.0, 0.0), "yaw": 0.0, "seed": 0},
    "wait_for_shuttle": {"order": DEFAULT_ORDER, "base": (0.0, 0.0, 0.0), "yaw": 0.0, "seed": 0},
}


def base_pose(name: str) -> np.ndarray:
    s = SOLVE_SETUP[name]
    return T(s["base"], rz(s["yaw"]))


# ---------------------------------------------------------------------------------------------------------
# writing
# ---------------------------------------------------------------------------------------------------------
def task_path(name: str) -> Path:
    return HERE / PACKAGE / f"{name}.json"


def write_tasks(names: Optional[Sequence[str]] = None) -> List[tuple]:
    """Write the task files (single-robot and collaborative); [(path, changed)]."""
    out = []
    for name in names or [*TASKS, *COLLAB_TASKS]:
        make, p = (TASKS[name], task_path(name)) if name in TASKS else (COLLAB_TASKS[name], collab_task_path(name))
        text = dumps(_clean(make())) + "\n"
        p.parent.mkdir(parents=True, exist_ok=True)
        changed = not p.exists() or p.read_text() != text
        if changed:
            p.write_text(text)
        out.append((p, changed))
    return out


# ---------------------------------------------------------------------------------------------------------
# solving
# ---------------------------------------------------------------------------------------------------------
def solve_builtin(name: str, seed: Optional[int] = None, base: Optional[np.ndarray] = None, cost: str = "cyc"):
    """Solve built-in task ``name`` with its SOLVE_SETUP robot: (task, SolveResult, seconds)."""
    from robodesign.formats.module_io import load_module_set
    from robodesign.design.solve import SolveSettings, solve
    from robodesign.formats.task_io import load_task
    setup = SOLVE_SETUP[name]
    task = load_task(task_path(name))
    ms = load_module_set(MODULE_SET)
    t0 = time.perf_counter()
    res = solve(task, ms, list(setup["order"]), base_pose=base_pose(name) if base is None else base, cost=cost,
                settings=SolveSettings(seed=setup["seed"] if seed is None else seed))
    return task, res, time.perf_counter() - t0


def solve_collab_builtin(name: str, seed: Optional[int] = None):
    """Solve collaborative built-in task ``name`` with its COLLAB_SOLVE_SETUP robots (prioritized planning):
    (CollabTask, CollabSolveResult, seconds)."""
    from robodesign.collab.core import RobotSetup, load_collab_task, solve_collab
    from robodesign.formats.module_io import load_module_set
    from robodesign.design.solve import SolveSettings
    setup = COLLAB_SOLVE_SETUP[name]
    ctask = load_collab_task(collab_task_path(name))
    ms = load_module_set(MODULE_SET)
    t0 = time.perf_counter()
    res = solve_collab(ctask, [RobotSetup(rid, ms, tuple(setup[rid])) for rid in ctask.robot_ids],
                       settings=SolveSettings(seed=setup["seed"] if seed is None else seed))
    return ctask, res, time.perf_counter() - t0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--no-solve", action="store_true", help="only write the task files")
    ap.add_argument("--seeds", default=None, help="comma-separated solver seeds to try (default: SOLVE_SETUP's)")
    ap.add_argument("--out", default=None, help="folder to write the solutions to (never assets/)")
    ap.add_argument("tasks", nargs="*", help="task names (default: all)")
    a = ap.parse_args(argv)
    names = a.tasks or [*TASKS, *COLLAB_TASKS]
    for n in names:
        if n not in TASKS and n not in COLLAB_TASKS:
            ap.error(f"unknown task {n!r} (one of {', '.join([*TASKS, *COLLAB_TASKS])})")
    for p, changed in write_tasks(names):
        print(f"{'wrote' if changed else 'unchanged'} {p.relative_to(HERE)}")
    if a.no_solve:
        return 0
    failed = 0
    for n in names:
        setup = COLLAB_SOLVE_SETUP[n] if n in COLLAB_TASKS else SOLVE_SETUP[n]
        seeds = [int(s) for s in a.seeds.split(",")] if a.seeds else [setup["seed"]]
        if n in COLLAB_TASKS:
            for seed in seeds:
                ctask, cres, sec = solve_collab_builtin(n, seed)
                if cres.feasible:
                    print(f"{ctask.id:28s} seed {seed}: solved in {sec:5.1f} s (priority {', '.join(cres.priority)}), "
                          f"costs {[round(c, 3) for c in cres.verdict.costs]}")
                    if a.out:
                        cres.solution.write(Path(a.out) / f"{n}.seed{seed}.json")
                else:
                    failed += 1
                    print(f"{ctask.id:28s} seed {seed}: FAILED after {sec:.1f} s: {cres.message}")
            continue
        for seed in seeds:
            task, res, sec = solve_builtin(n, seed)
            where = f"base {tuple(setup['base'])} yaw {setup['yaw']}"
            if res.feasible:
                print(f"{task.id:28s} seed {seed}: solved in {sec:5.1f} s, cyc {res.verdict.costs['cyc']:.2f} s, "
                      f"{len(res.solution.trajectory.t)} samples ({where})")
                if a.out:
                    res.solution.write(Path(a.out) / f"{n}.seed{seed}.json")
            else:
                failed += 1
                print(f"{task.id:28s} seed {seed}: FAILED at {res.stage} after {sec:.1f} s: {res.message}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
