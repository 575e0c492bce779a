#!/usr/bin/env python3
"""Generate the built-in ``robodesign_arm`` module set: ``modules.json`` and ``meshes/gripper_S.stl``.

Run with the project's virtual environment from anywhere::

    .venv/bin/python assets/modules/robodesign_arm/make_modules.py          # write + check
    .venv/bin/python assets/modules/robodesign_arm/make_modules.py --check  # only check the files on disk

The output is deterministic (fixed date, fixed rounding, no randomness except the seeded reach
estimate, which is only printed). After writing, the script checks its own output: schema
validation (schemas/modules.schema.json), frame conventions, and the example module orders of
README.md (serial connector rule, 6 DoF, reach). See README.md for the module table and sources.

Conventions (same as the CoBRA sample sets):
* every body frame of a chain module starts at its proximal connector; the module extends along +z;
* a connector's z axis points away from its own body: proximal connectors are Rx(pi) at the origin,
  distal connectors point along +z (or along +x after a 90 deg elbow);
* mated connectors have coinciding origins, aligned x and anti-parallel z;
* proximal connectors are female (``f``), distal connectors male (``m``); all chain connectors have
  ``type: "rdflange"`` and ``size: [flange diameter in m]`` (0.1 = size L, 0.075 = size S);
* bases have one ``type: "base", gender: "f"`` connector pointing into the floor (pose Rx(pi)) and
  one outgoing connector; end effectors have a distal ``type: "eef", gender: "m"`` connector (TCP);
* revolute joints rotate about the joint frame's z axis; inertias are about the CoM in body axes.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import List

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]  # checkout root (holds schemas/)
OUT = HERE / "modules.json"
MESH_DIR = HERE / "meshes"
GRIPPER_MESH = "meshes/gripper_S.stl"

DATE = "2026-11-22"  # fixed, so that the output does not depend on the day the script runs
HEADER = {"date": DATE, "author": ["robodesign contributors"], "email": [], "affiliation": ["robodesign"],
          "cost": 0.0}

CON_TYPE = "rdflange"
SIZE_L = [0.1]  # flange diameter (m)
SIZE_S = [0.075]

LIMIT = math.radians(170.0)

# Actuator figures (see README.md, "Which product each joint module follows" and "Sources of the figures").
# Joint limits: those of the Franka Emika Panda's joints (libfranka rate_limiting.h, Franka "Robot and
# interface specifications"): torque 87 / 12 Nm, speed 2.175 / 2.61 rad/s for joints 1-4 / 5-7, acceleration
# per joint 15, 7.5, 10, 12.5, 15, 20, 20 rad/s^2. Module 21 follows Panda joint 1, 22 joint 2, 23 joint 5,
# 24 joint 6. Never tune them to win a benchmark.
DRIVE_L = {"gearRatio": 160.0, "motorInertia": 4.5e-5, "frictionCoulomb": 5.0, "frictionViscous": 8.0}
DRIVE_S = {"gearRatio": 100.0, "motorInertia": 1.5e-5, "frictionCoulomb": 1.8, "frictionViscous": 2.5}
ACT_L_INLINE = {"peakTorque": 87.0, "velocity": 2.175, "acceleration": 15.0, **DRIVE_L}  # Panda joint 1
ACT_L_PITCH = {"peakTorque": 87.0, "velocity": 2.175, "acceleration": 7.5, **DRIVE_L}  # Panda joint 2
ACT_S_INLINE = {"peakTorque": 12.0, "velocity": 2.61, "acceleration": 15.0, **DRIVE_S}  # Panda joint 5
ACT_S_PITCH = {"peakTorque": 12.0, "velocity": 2.61, "acceleration": 20.0, **DRIVE_S}  # Panda joint 6

# Aluminium tube links: outer radius = flange radius, wall 4 mm (L) / 3 mm (S).
RHO_AL = 2700.0
TUBE_L = (0.05, 0.046)
TUBE_S = (0.0375, 0.0345)
FLANGE_L = (0.05, 0.01, 0.2)  # radius, thickness, mass of a link end flange
FLANGE_S = (0.0375, 0.008, 0.09)


# --------------------------------------------------------------------------------------------------
# transforms
def trans(x=0.0, y=0.0, z=0.0) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def rot_x(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    T = np.eye(4)
    T[1:3, 1:3] = [[c, -s], [s, c]]
    return T


def rot_y(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    T = np.eye(4)
    T[0, 0], T[0, 2], T[2, 0], T[2, 2] = c, s, -s, c
    return T


def rot_z(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    return T


def num(x: float, nd: int = 10) -> float:
    v = round(float(x), nd)
    return 0.0 if v == 0 else v  # no -0.0


def pose_json(T: np.ndarray) -> list:
    return [[num(v) for v in row] for row in np.asarray(T)]


# --------------------------------------------------------------------------------------------------
# mass parts (solid or hollow primitives) → inertia about the CoM, and geometry objects
class Part:
    """A primitive with a mass; ``pose`` places its centre (cylinders: axis = local z)."""

    def __init__(self, shape: str, dims: dict, pose: np.ndarray, mass: float, r_in: float = 0.0,
                 collision: bool = True, visual: bool = True):
        self.shape, self.dims, self.pose, self.mass, self.r_in = shape, dims, pose, mass, r_in
        self.collision, self.visual = collision, visual

    def inertia_local(self) -> np.ndarray:
        m, d = self.mass, self.dims
        if self.shape == "cylinder":
            r, h, ri = d["r"], d["z"], self.r_in
            ixx = m * (3.0 * (r * r + ri * ri) + h * h) / 12.0
            return np.diag([ixx, ixx, m * (r * r + ri * ri) / 2.0])
        if self.shape == "box":
            x, y, z = d["x"], d["y"], d["z"]
            return np.diag([m * (y * y + z * z), m * (x * x + z * z), m * (x * x + y * y)]) / 12.0
        if self.shape == "sphere":
            r, ri = d["r"], self.r_in
            i = 0.4 * m * (r ** 5 - ri ** 5) / (r ** 3 - ri ** 3)
            return np.diag([i, i, i])
        raise ValueError(self.shape)

    def geometry(self) -> dict:
        return {"type": self.shape, "parameters": {k: num(v) for k, v in self.dims.items()},
                "pose": pose_json(self.pose)}


def cyl(r, h, pose, mass=0.0, r_in=0.0, **kw) -> Part:
    return Part("cylinder", {"r": r, "z": h}, pose, mass, r_in, **kw)


def box(x, y, z, pose, mass=0.0, **kw) -> Part:
    return Part("box", {"x": x, "y": y, "z": z}, pose, mass, **kw)


def sphere(r, pose, mass=0.0, r_in=0.0, **kw) -> Part:
    return Part("sphere", {"r": r}, pose, mass, r_in, **kw)


def mass_properties(parts):
    """Total mass, CoM and inertia about the CoM (body axes) of rigidly joined parts."""
    parts = [p for p in parts if p.mass > 0]
    m = sum(p.mass for p in parts)
    com = sum(p.mass * p.pose[:3, 3] for p in parts) / m
    inertia = np.zeros((3, 3))
    for p in parts:
        R = p.pose[:3, :3]
        d = p.pose[:3, 3] - com
        inertia += R @ p.inertia_local() @ R.T + p.mass * (d @ d * np.eye(3) - np.outer(d, d))
    return m, com, inertia


def connector(cid: str, pose: np.ndarray, gender: str, ctype: str, size: list) -> dict:
    return {"ID": cid, "pose": pose_json(pose), "gender": gender, "type": ctype, "size": list(size)}


def body(bid: str, parts, connectors=(), visual_extra=(), collision=None, visual=None) -> dict:
    m, com, inertia = mass_properties(parts)
    out = {"ID": bid, "mass": num(m, 6), "r_com": [num(v) for v in com],
           "inertia": [[num(v) for v in row] for row in inertia], "connectors": list(connectors)}
    out["collision"] = collision if collision is not None else [p.geometry() for p in parts if p.collision]
    out["visual"] = visual if visual is not None else (
        [p.geometry() for p in parts if p.visual] + [p.geometry() for p in visual_extra])
    return out


def module(mid: str, name: str, bodies, joints=()) -> dict:
    return {"header": {"ID": mid, "name": name, **HEADER}, "bodies": list(bodies), "joints": list(joints)}


def revolute(jid: str, parent: str, child: str, pose_parent, pose_child, act: dict) -> dict:
    return {"ID": jid, "parent": parent, "child": child, "type": "revolute", "passive": False,
            "poseParent": pose_json(pose_parent), "poseChild": pose_json(pose_child),
            "limits": {"positionLower": num(-LIMIT), "positionUpper": num(LIMIT),
                       "peakTorque": act["peakTorque"], "velocity": act["velocity"],
                       "acceleration": act["acceleration"]},
            "gearRatio": act["gearRatio"], "motorInertia": act["motorInertia"],
            "frictionCoulomb": act["frictionCoulomb"], "frictionViscous": act["frictionViscous"]}


PROXIMAL = rot_x(math.pi)  # proximal connector: at the body origin, z pointing "down" (away from the body)


def proximal(mid: str, size) -> dict:
    return connector(f"{mid}_proximal_connector", PROXIMAL, "f", CON_TYPE, size)


def distal(mid: str, pose: np.ndarray, size) -> dict:
    return connector(f"{mid}_distal_connector", pose, "m", CON_TYPE, size)


def tcp(mid: str, pose: np.ndarray) -> dict:
    return connector(f"{mid}_tcp", pose, "m", "eef", [])


# --------------------------------------------------------------------------------------------------
# modules
CLEAR = 0.002  # bases: geometry starts 2 mm above the mounting plane (no contact with a floor obstacle)


def base_floor() -> dict:
    mid, h = "1", 0.1
    parts = [cyl(0.1, 0.02, trans(z=CLEAR + 0.01), 1.5),
             cyl(0.055, h - CLEAR - 0.02, trans(z=(CLEAR + 0.02 + h) / 2), 0.9, r_in=0.045)]
    cons = [connector(f"{mid}_base_connector", PROXIMAL, "f", "base", []),
            distal(mid, trans(z=h), SIZE_L)]
    return module(mid, "base_floor", [body(f"{mid}_body", parts, cons)])


def base_pedestal() -> dict:
    mid, h = "2", 0.5
    parts = [cyl(0.14, 0.02, trans(z=CLEAR + 0.01), 1.8),
             cyl(0.06, h - CLEAR - 0.04, trans(z=(CLEAR + 0.02 + h - 0.02) / 2), 1.4, r_in=0.057),
             cyl(0.06, 0.02, trans(z=h - 0.01), 0.35)]
    cons = [connector(f"{mid}_base_connector", PROXIMAL, "f", "base", []),
            distal(mid, trans(z=h), SIZE_L)]
    return module(mid, "base_pedestal", [body(f"{mid}_body", parts, cons)])


def adapter_l_to_s() -> dict:
    mid = "3"
    parts = [cyl(0.05, 0.02, trans(z=0.01), 0.22), cyl(0.0375, 0.02, trans(z=0.03), 0.12)]
    cons = [proximal(mid, SIZE_L), distal(mid, trans(z=0.04), SIZE_S)]
    return module(mid, "adapter_L_to_S", [body(f"{mid}_body", parts, cons)])


def tube_mass(tube, length) -> float:
    r, ri = tube
    return RHO_AL * math.pi * (r * r - ri * ri) * length


def straight_link(mid: str, name: str, length: float, size) -> dict:
    tube, (fr, ft, fm) = (TUBE_L, FLANGE_L) if size == SIZE_L else (TUBE_S, FLANGE_S)
    lt = length - 2 * ft
    parts = [cyl(fr, ft, trans(z=ft / 2), fm, collision=False),
             cyl(tube[0], lt, trans(z=length / 2), tube_mass(tube, lt), r_in=tube[1], collision=False),
             cyl(fr, ft, trans(z=length - ft / 2), fm, collision=False)]
    coll = [cyl(tube[0], length, trans(z=length / 2)).geometry()]
    cons = [proximal(mid, size), distal(mid, trans(z=length), size)]
    return module(mid, name, [body(f"{mid}_body", parts, cons, collision=coll)])


def elbow_link(mid: str, name: str, a: float, b: float, size, knuckle_mass: float) -> dict:
    """90 deg elbow: up by a along z, then out by b along x; the distal connector points along +x."""
    tube, (fr, ft, fm) = (TUBE_L, FLANGE_L) if size == SIZE_L else (TUBE_S, FLANGE_S)
    r = tube[0]
    lv, lh = a - ft, b - ft
    horizontal = rot_y(math.pi / 2)
    parts = [cyl(fr, ft, trans(z=ft / 2), fm, collision=False),
             cyl(r, lv, trans(z=ft + lv / 2), tube_mass(tube, lv), r_in=tube[1], collision=False),
             sphere(r, trans(z=a), knuckle_mass, r_in=r - 0.008, collision=False),
             cyl(r, lh, trans(x=lh / 2, z=a) @ horizontal, tube_mass(tube, lh), r_in=tube[1], collision=False),
             cyl(fr, ft, trans(x=b - ft / 2, z=a) @ horizontal, fm, collision=False)]
    coll = [cyl(r, a, trans(z=a / 2)).geometry(), sphere(r, trans(z=a)).geometry(),
            cyl(r, b, trans(x=b / 2, z=a) @ horizontal).geometry()]
    cons = [proximal(mid, size), distal(mid, trans(x=b, z=a) @ horizontal, size)]
    return module(mid, name, [body(f"{mid}_body", parts, cons, collision=coll)])


def joint_inline(mid: str, name: str, size, act, housing, flange) -> dict:
    """Roll joint: the rotation axis is the module's length axis (z)."""
    (hr, hh, hm), (fr, fh, fm) = housing, flange
    prox = body(f"{mid}_proximal",
                [cyl(hr, hh, trans(z=hh / 2), hm)],
                [proximal(mid, size)],
                visual_extra=[cyl(hr + 0.002, 0.012, trans(z=hh - 0.006))])  # bearing ring (visual only)
    dist = body(f"{mid}_distal", [cyl(fr, fh, trans(z=fh / 2), fm)], [distal(mid, trans(z=fh), size)])
    joint = revolute(f"{mid}_joint", prox["ID"], dist["ID"], trans(z=hh), np.eye(4), act)
    return module(mid, name, [prox, dist], [joint])


def joint_pitch(mid: str, name: str, size, act, neck, drum, out) -> dict:
    """Pitch joint: the rotation axis is perpendicular to the module's length (body y axis).

    The joint frame sits at the drum centre with z = body +y; at q = 0 the distal body frame is
    parallel to the proximal body frame, so the module is straight.
    """
    (nr, nh, nm), (dr, dl, dm), (orad, o0, o1, om) = neck, drum, out
    zj = nh + dr  # joint height above the proximal connector
    axis_y = rot_x(-math.pi / 2)  # maps the local z axis onto body +y
    prox = body(f"{mid}_proximal",
                [cyl(nr, nh, trans(z=nh / 2), nm), cyl(dr, dl, trans(z=zj) @ axis_y, dm)],
                [proximal(mid, size)],
                visual_extra=[cyl(dr * 0.6, dl + 0.006, trans(z=zj) @ axis_y)])  # axis cap (visual only)
    dist = body(f"{mid}_distal", [cyl(orad, o1 - o0, trans(z=(o0 + o1) / 2), om)],
                [distal(mid, trans(z=o1), size)])
    joint = revolute(f"{mid}_joint", prox["ID"], dist["ID"], trans(z=zj) @ axis_y, rot_x(math.pi / 2), act)
    return module(mid, name, [prox, dist], [joint])


def gripper_parts():
    """Mass model of the gripper (also the source of its mesh)."""
    return [cyl(0.0375, 0.015, trans(z=0.0075), 0.1),                  # flange
            box(0.09, 0.06, 0.07, trans(z=0.05), 0.7),                  # housing (motor + gear)
            box(0.014, 0.022, 0.06, trans(x=0.022, z=0.115), 0.05),     # finger +x
            box(0.014, 0.022, 0.06, trans(x=-0.022, z=0.115), 0.05)]    # finger -x


def write_gripper_mesh() -> bytes:
    import trimesh
    meshes = []
    for p in gripper_parts():
        if p.shape == "cylinder":
            m = trimesh.creation.cylinder(radius=p.dims["r"], height=p.dims["z"], sections=48)
        else:
            m = trimesh.creation.box(extents=(p.dims["x"], p.dims["y"], p.dims["z"]))
        m.apply_transform(p.pose)
        meshes.append(m)
    mesh = trimesh.util.concatenate(meshes)
    data = mesh.export(file_type="stl")  # binary STL, metres, body frame
    MESH_DIR.mkdir(exist_ok=True)
    (HERE / GRIPPER_MESH).write_bytes(data)
    return data


def gripper() -> dict:
    mid = "13"
    mesh = {"type": "mesh", "parameters": {"file": GRIPPER_MESH, "scale": 1.0}, "pose": pose_json(np.eye(4))}
    cons = [proximal(mid, SIZE_S), tcp(mid, trans(z=0.13))]  # TCP between the finger pads
    return module(mid, "gripper_S", [body(f"{mid}_body", gripper_parts(), cons, collision=[mesh], visual=[mesh])])


def tool_flange(mid: str, name: str, size, flange, tool, tip) -> dict:
    (fr, fh, fm), (tr, th, tm), (pr, ph, pm) = flange, tool, tip
    parts = [cyl(fr, fh, trans(z=fh / 2), fm), cyl(tr, th, trans(z=fh + th / 2), tm),
             cyl(pr, ph, trans(z=fh + th + ph / 2), pm)]
    cons = [proximal(mid, size), tcp(mid, trans(z=fh + th + ph))]  # TCP at the tool tip
    return module(mid, name, [body(f"{mid}_body", parts, cons)])


def build() -> dict:
    mods = [
        base_floor(),
        base_pedestal(),
        adapter_l_to_s(),
        straight_link("4", "link_L_100", 0.10, SIZE_L),
        straight_link("5", "link_L_200", 0.20, SIZE_L),
        straight_link("6", "link_L_350", 0.35, SIZE_L),
        straight_link("7", "link_L_500", 0.50, SIZE_L),
        straight_link("8", "link_S_100", 0.10, SIZE_S),
        straight_link("9", "link_S_200", 0.20, SIZE_S),
        straight_link("10", "link_S_300", 0.30, SIZE_S),
        elbow_link("11", "elbow_L_90", 0.12, 0.12, SIZE_L, knuckle_mass=0.35),
        tool_flange("12", "tool_flange_S", SIZE_S, (0.0375, 0.012, 0.12), (0.025, 0.06, 0.18), (0.008, 0.048, 0.03)),
        gripper(),
        tool_flange("14", "tool_flange_L", SIZE_L, (0.05, 0.015, 0.2), (0.035, 0.08, 0.35), (0.01, 0.055, 0.05)),
        elbow_link("15", "elbow_S_90", 0.09, 0.09, SIZE_S, knuckle_mass=0.15),
        joint_inline("21", "joint_L_inline", SIZE_L, ACT_L_INLINE, housing=(0.055, 0.13, 2.55), flange=(0.05, 0.03, 0.45)),
        joint_pitch("22", "joint_L_pitch", SIZE_L, ACT_L_PITCH, neck=(0.05, 0.05, 0.45), drum=(0.062, 0.13, 2.4),
                    out=(0.05, 0.06, 0.1, 0.35)),
        joint_inline("23", "joint_S_inline", SIZE_S, ACT_S_INLINE, housing=(0.042, 0.1, 1.0), flange=(0.0375, 0.025, 0.2)),
        joint_pitch("24", "joint_S_pitch", SIZE_S, ACT_S_PITCH, neck=(0.0375, 0.04, 0.2), drum=(0.046, 0.095, 1.05),
                    out=(0.0375, 0.04, 0.075, 0.2)),
    ]
    return {"ignore_collisions": "rigid_via_joint", "modules": mods}


# --------------------------------------------------------------------------------------------------
# self-check (independent of the robodesign package)
EXAMPLES = {
    "A": ["1", "21", "22", "4", "22", "3", "23", "24", "23", "12"],
    "B": ["2", "21", "22", "4", "22", "3", "24", "23", "24", "13"],
    "C": ["1", "21", "22", "4", "11", "21", "3", "24", "23", "24", "12"],
}


def _mat(p):
    p = np.asarray(p, float)
    if p.ndim == 3:  # list of poses: left-to-right product
        out = np.eye(4)
        for t in p:
            out = out @ t
        return out
    return p


def _mates(a: dict, b: dict) -> bool:
    return (a["type"] == b["type"] and list(a.get("size", [])) == list(b.get("size", []))
            and {a.get("gender", "h"), b.get("gender", "h")} in ({"f", "m"}, {"h"}))


def _module_frames(mod: dict, q: list):
    """Body frames of one module relative to its first body, consuming joint values from q."""
    frames = {mod["bodies"][0]["ID"]: np.eye(4)}
    joints = []
    pending = list(mod.get("joints", []))
    while pending:
        j = next(j for j in pending if j["parent"] in frames)
        pending.remove(j)
        qj = q.pop(0) if j["type"] != "fixed" else 0.0
        Tj = frames[j["parent"]] @ _mat(j["poseParent"])
        joints.append(Tj)
        frames[j["child"]] = Tj @ rot_z(qj) @ _mat(j["poseChild"])
    return frames, joints


def walk_serial(db: dict, order: list, q=None):
    """Serial shortcut: returns (dof, joint frames, TCP frame). Raises AssertionError on a bad order."""
    mods = {m["header"]["ID"]: m for m in db["modules"]}
    first = mods[order[0]]
    cons0 = [c for b in first["bodies"] for c in b["connectors"]]
    assert sum(c["type"] == "base" for c in cons0) == 1, f"{order[0]} has no unique base connector"
    dof = sum(j["type"] != "fixed" for m in order for j in mods[m].get("joints", []))
    q = list(q) if q is not None else [0.0] * dof
    # world pose of the base body: base connector world pose is Rx(pi)
    base_con = next((b, c) for b in first["bodies"] for c in b["connectors"] if c["type"] == "base")
    frames, joints = _module_frames(first, q)
    T0 = rot_x(math.pi) @ np.linalg.inv(_mat(base_con[1]["pose"])) @ np.linalg.inv(frames[base_con[0]["ID"]])
    free = [(0, c, T0 @ frames[b["ID"]] @ _mat(c["pose"])) for b in first["bodies"] for c in b["connectors"]
            if c is not base_con[1]]
    all_joints = [T0 @ J for J in joints]
    for i, mid in enumerate(order[1:], start=1):
        mod = mods[mid]
        cands = [(fa, cb, b) for fa in free for b in mod["bodies"] for cb in b["connectors"] if _mates(fa[1], cb)]
        assert len(cands) == 1, f"position {i} ({mid}): {len(cands)} candidate connections"
        (ia, ca, Ta), cb, bb = cands[0]
        assert ia == i - 1, f"position {i} ({mid}) does not attach to the previous module"
        frames, joints = _module_frames(mod, q)
        # T_body_b = T_con_a @ Rx(pi) @ inv(pose_con_b), then the module's own first-body frame
        Tb = Ta @ rot_x(math.pi) @ np.linalg.inv(_mat(cb["pose"])) @ np.linalg.inv(frames[bb["ID"]])
        free = [f for f in free if f[1] is not ca]
        free += [(i, c, Tb @ frames[b["ID"]] @ _mat(c["pose"])) for b in mod["bodies"] for c in b["connectors"]
                 if c is not cb]
        all_joints += [Tb @ J for J in joints]
    eef = [f for f in free if f[1]["type"] == "eef"]
    assert len(eef) == 1 and eef[0][0] == len(order) - 1, "the chain must end with an end effector"
    return dof, all_joints, eef[0][2]


def count_arms(db: dict, max_links_per_gap: int = 1) -> int:
    """Distinct serial 6-DoF arms: base, 6 joint modules, at most one passive module in each gap, eef."""
    mods = db["modules"]

    def kind(m):
        cons = [c for b in m["bodies"] for c in b["connectors"]]
        if any(c["type"] == "base" for c in cons):
            return "base"
        if any(c["type"] == "eef" for c in cons):
            return "eef"
        return "joint" if m.get("joints") else "link"

    def ends(m):
        cons = [c for b in m["bodies"] for c in b["connectors"] if c["type"] == CON_TYPE]
        return (next((tuple(c["size"]) for c in cons if c["gender"] == "f"), None),
                next((tuple(c["size"]) for c in cons if c["gender"] == "m"), None))

    by_kind = {}
    for m in mods:
        by_kind.setdefault(kind(m), []).append(ends(m))
    # state: (free size, joints placed, passive modules since the last joint) -> count
    states = {}
    for _, out in by_kind["base"]:
        states[(out, 0, 0)] = states.get((out, 0, 0), 0) + 1
    total = 0
    for _ in range(6 * (max_links_per_gap + 1) + max_links_per_gap + 1):
        new = {}
        for (size, n, gap), cnt in states.items():
            for kd in ("joint", "link", "eef"):
                for fin, fout in by_kind.get(kd, []):
                    if fin != size:
                        continue
                    if kd == "eef":
                        total += cnt if n == 6 else 0
                    elif kd == "joint" and n < 6:
                        key = (fout, n + 1, 0)
                        new[key] = new.get(key, 0) + cnt
                    elif kd == "link" and gap < max_links_per_gap:
                        key = (fout, n, gap + 1)
                        new[key] = new.get(key, 0) + cnt
        states = new
    return total


def check_modules(db: dict, max_mass: float, folder: Path) -> List[str]:
    """The structural checks every built-in set passes: schema, unique IDs, module masses in [0.3, ``max_mass``]
    kg, physical inertias, proper connector rotations, mesh files present in ``folder``. Returns the IDs."""
    try:
        import jsonschema
    except ImportError:  # pragma: no cover
        print("jsonschema not installed: schema validation skipped", file=sys.stderr)
    else:
        schema = json.loads((ROOT / "schemas" / "modules.schema.json").read_text())
        errs = list(jsonschema.Draft202012Validator(schema).iter_errors(db))
        assert not errs, "schema: " + "; ".join(f"{list(e.absolute_path)}: {e.message}" for e in errs[:5])
    ids = [m["header"]["ID"] for m in db["modules"]]
    assert len(set(ids)) == len(ids), "duplicate module IDs"
    for m in db["modules"]:
        mass = sum(b["mass"] for b in m["bodies"])
        assert 0.3 <= mass <= max_mass, f"module {m['header']['ID']}: mass {mass}"
        for b in m["bodies"]:
            eig = np.linalg.eigvalsh(np.asarray(b["inertia"]))
            assert eig.min() > 0 and 2 * eig.max() <= eig.sum() + 1e-12, f"body {b['ID']}: bad inertia"
            for c in b["connectors"]:
                R = _mat(c["pose"])[:3, :3]
                assert np.allclose(R @ R.T, np.eye(3)) and np.isclose(np.linalg.det(R), 1.0), c["ID"]
            for g in b["collision"] + b["visual"]:
                if g["type"] == "mesh":
                    assert (folder / g["parameters"]["file"]).is_file(), g["parameters"]["file"]
    return ids


def check(db: dict, verbose: bool = True) -> None:
    ids = check_modules(db, 4.0, HERE)
    rng = np.random.default_rng(0)
    for name, order in EXAMPLES.items():
        dof, joints, tcp_home = walk_serial(db, order)
        assert dof == 6, f"example {name}: {dof} DoF"
        # reach: largest distance from the 2nd joint (shoulder) to the TCP over random configurations
        reach = float(np.linalg.norm(tcp_home[:3, 3] - joints[1][:3, 3]))
        for _ in range(3000):
            q = rng.uniform(-LIMIT, LIMIT, dof)
            _, js, T = walk_serial(db, order, q)
            reach = max(reach, float(np.linalg.norm(T[:3, 3] - js[1][:3, 3])))
        mass = sum(b["mass"] for mid in order for m in db["modules"] if m["header"]["ID"] == mid
                   for b in m["bodies"])
        if verbose:
            print(f"example {name}: {','.join(order)}  dof={dof}  mass={mass:.2f} kg  "
                  f"TCP(home)={np.round(tcp_home[:3, 3], 3).tolist()}  reach~{reach:.2f} m")
    n = count_arms(db)
    assert n >= 1000, n
    if verbose:
        print(f"{len(ids)} modules; {n} distinct serial 6-DoF arms (<= 1 passive module per gap)")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="only check the files on disk")
    args = ap.parse_args(argv)
    if not args.check:
        db = build()
        write_gripper_mesh()
        OUT.write_text(json.dumps(db, indent=2, allow_nan=False) + "\n", encoding="utf-8")
        print(f"wrote {OUT.relative_to(ROOT)} and {(HERE / GRIPPER_MESH).relative_to(ROOT)}")
    check(json.loads(OUT.read_text(encoding="utf-8")))
    return 0


if __name__ == "__main__":
    sys.exit(main())
