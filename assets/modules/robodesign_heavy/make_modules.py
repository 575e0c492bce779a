#!/usr/bin/env python3
"""Generate the built-in ``robodesign_heavy`` module set (``modules.json``): joints of three sizes whose limits
follow the joint sizes of the Universal Robots UR10e (size 4: 330 Nm, size 3: 150 Nm, size 2: 56 Nm).

Run with the project's virtual environment from anywhere::

    .venv/bin/python assets/modules/robodesign_heavy/make_modules.py          # write + check
    .venv/bin/python assets/modules/robodesign_heavy/make_modules.py --check  # only check the file on disk

It is built the way ``robodesign_arm`` is (and reuses that script's primitives, mass-property and
serial-walk helpers): every body is a set of solid or hollow primitives with a mass, its inertia is
computed from them, the output is deterministic (fixed date, values rounded to 10 decimals). After
writing, the script checks its own output: schema, masses, physically valid inertias, the example
orders of README.md (serial connector rule, 6 DoF, reach) and the gravity torque of each example held
stretched out horizontally against its joint limits. README.md has the module table and the sources.
"""
from __future__ import annotations

import argparse
import importlib.util
import json
import math
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
OUT = HERE / "modules.json"


def _load_arm_helpers():
    spec = importlib.util.spec_from_file_location("_robodesign_arm_make", HERE.parent / "robodesign_arm" / "make_modules.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


A = _load_arm_helpers()
trans, rot_x, rot_y, num, pose_json = A.trans, A.rot_x, A.rot_y, A.num, A.pose_json
cyl, sphere, body, connector = A.cyl, A.sphere, A.body, A.connector
proximal, distal, tcp, PROXIMAL, CLEAR = A.proximal, A.distal, A.tcp, A.PROXIMAL, A.CLEAR

DATE = "2026-11-26"
HEADER = {"date": DATE, "author": ["robodesign contributors"], "email": [], "affiliation": ["robodesign"],
          "cost": 0.0}

# Flange diameters (m) of the three joint sizes; named after the UR joint sizes they follow.
SIZE_4 = [0.15]
SIZE_3 = [0.12]
SIZE_2 = [0.09]

# Position range of every UR10e joint: ±360° (UR10e User Manual, technical specifications).
LIMIT = 2.0 * math.pi

# Product figures (README.md, "Which product each joint size follows"). Peak torque: Universal Robots,
# "Max. joint torques" (e-Series: size 4 330 Nm, size 3 150 Nm, size 2 56 Nm); speed: UR10e User Manual /
# UR10e data sheet (base and shoulder 120°/s, all other joints 180°/s). The same figures are in UR's own
# description package (Universal_Robots_ROS2_Description, config/ur10e/joint_limits.yaml), which also
# says that UR publishes no joint acceleration limit: none is set here (CoBRA default: unbounded), so
# accelerations are bounded by the peak torque through the dynamics, including the reflected rotor inertia.
# Never tune them to win a benchmark.
SPEED_4 = math.radians(120.0)
SPEED_32 = math.radians(180.0)
# Drivetrain: gear ratio 101 (harmonic drive), rotor inertia and friction are this project's estimates.
ACT_4 = {"peakTorque": 330.0, "velocity": SPEED_4, "gearRatio": 101.0, "motorInertia": 1.3e-4,
         "frictionCoulomb": 12.0, "frictionViscous": 12.0}
ACT_3 = {"peakTorque": 150.0, "velocity": SPEED_32, "gearRatio": 101.0, "motorInertia": 6.0e-5,
         "frictionCoulomb": 6.0, "frictionViscous": 6.0}
ACT_2 = {"peakTorque": 56.0, "velocity": SPEED_32, "gearRatio": 101.0, "motorInertia": 2.5e-5,
         "frictionCoulomb": 2.5, "frictionViscous": 2.5}

# Aluminium tubes: (outer radius, inner radius); end flanges: (radius, thickness, mass).
RHO_AL = A.RHO_AL
TUBE = {4: (0.075, 0.070), 3: (0.060, 0.056), 2: (0.045, 0.042)}
FLANGE = {4: (0.075, 0.012, 0.35), 3: (0.060, 0.010, 0.22), 2: (0.045, 0.008, 0.12)}
SIZE = {4: SIZE_4, 3: SIZE_3, 2: SIZE_2}


def module(mid: str, name: str, bodies, joints=()) -> dict:
    return {"header": {"ID": mid, "name": name, **HEADER}, "bodies": list(bodies), "joints": list(joints)}


def revolute(jid: str, parent: str, child: str, pose_parent, pose_child, act: dict) -> dict:
    return {"ID": jid, "parent": parent, "child": child, "type": "revolute", "passive": False,
            "poseParent": pose_json(pose_parent), "poseChild": pose_json(pose_child),
            "limits": {"positionLower": num(-LIMIT), "positionUpper": num(LIMIT),
                       "peakTorque": act["peakTorque"], "velocity": num(act["velocity"])},
            "gearRatio": act["gearRatio"], "motorInertia": act["motorInertia"],
            "frictionCoulomb": act["frictionCoulomb"], "frictionViscous": act["frictionViscous"]}


def tube_mass(tube, length) -> float:
    r, ri = tube
    return RHO_AL * math.pi * (r * r - ri * ri) * length


# --------------------------------------------------------------------------------------------------
# modules
def base(mid: str, name: str, h: float, plate, column) -> dict:
    (pr, pt, pm), (cr, cri, cm) = plate, column
    parts = [cyl(pr, pt, trans(z=CLEAR + pt / 2), pm),
             cyl(cr, h - CLEAR - pt, trans(z=(CLEAR + pt + h) / 2), cm, r_in=cri)]
    cons = [connector(f"{mid}_base_connector", PROXIMAL, "f", "base", []), distal(mid, trans(z=h), SIZE_4)]
    return module(mid, name, [body(f"{mid}_body", parts, cons)])


def adapter(mid: str, name: str, big: int, small: int, m_big: float, m_small: float) -> dict:
    parts = [cyl(FLANGE[big][0], 0.02, trans(z=0.01), m_big), cyl(FLANGE[small][0], 0.02, trans(z=0.03), m_small)]
    cons = [proximal(mid, SIZE[big]), distal(mid, trans(z=0.04), SIZE[small])]
    return module(mid, name, [body(f"{mid}_body", parts, cons)])


def straight_link(mid: str, name: str, length: float, size_in: int, size_out: int) -> dict:
    """A tube of the distal size between a proximal flange of ``size_in`` and a distal flange of ``size_out``
    (a tapered link when they differ)."""
    tube = TUBE[size_out]
    (fr0, ft0, fm0), (fr1, ft1, fm1) = FLANGE[size_in], FLANGE[size_out]
    lt = length - ft0 - ft1
    parts = [cyl(fr0, ft0, trans(z=ft0 / 2), fm0, collision=False),
             cyl(tube[0], lt, trans(z=ft0 + lt / 2), tube_mass(tube, lt), r_in=tube[1], collision=False),
             cyl(fr1, ft1, trans(z=length - ft1 / 2), fm1, collision=False)]
    coll = [cyl(fr0, ft0, trans(z=ft0 / 2)).geometry(), cyl(tube[0], length - ft0, trans(z=(length + ft0) / 2)).geometry()]
    cons = [proximal(mid, SIZE[size_in]), distal(mid, trans(z=length), SIZE[size_out])]
    return module(mid, name, [body(f"{mid}_body", parts, cons, collision=coll)])


def elbow_link(mid: str, name: str, a: float, b: float, size: int, knuckle_mass: float) -> dict:
    """90° elbow: up by a along z, then out by b along x; the distal connector points along +x."""
    tube, (fr, ft, fm) = TUBE[size], FLANGE[size]
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
    cons = [proximal(mid, SIZE[size]), distal(mid, trans(x=b, z=a) @ horizontal, SIZE[size])]
    return module(mid, name, [body(f"{mid}_body", parts, cons, collision=coll)])


def joint_inline(mid: str, name: str, size: int, act, housing, flange) -> dict:
    """Roll joint: the rotation axis is the module's length axis (z)."""
    (hr, hh, hm), (fr, fh, fm) = housing, flange
    prox = body(f"{mid}_proximal", [cyl(hr, hh, trans(z=hh / 2), hm)], [proximal(mid, SIZE[size])],
                visual_extra=[cyl(hr + 0.003, 0.015, trans(z=hh - 0.0075))])
    dist = body(f"{mid}_distal", [cyl(fr, fh, trans(z=fh / 2), fm)], [distal(mid, trans(z=fh), SIZE[size])])
    joint = revolute(f"{mid}_joint", prox["ID"], dist["ID"], trans(z=hh), np.eye(4), act)
    return module(mid, name, [prox, dist], [joint])


def joint_pitch(mid: str, name: str, size: int, act, neck, drum, out) -> dict:
    """Pitch joint: the axis is perpendicular to the module (body y); straight at q = 0."""
    (nr, nh, nm), (dr, dl, dm), (orad, o0, o1, om) = neck, drum, out
    zj = nh + dr
    axis_y = rot_x(-math.pi / 2)
    prox = body(f"{mid}_proximal", [cyl(nr, nh, trans(z=nh / 2), nm), cyl(dr, dl, trans(z=zj) @ axis_y, dm)],
                [proximal(mid, SIZE[size])], visual_extra=[cyl(dr * 0.6, dl + 0.008, trans(z=zj) @ axis_y)])
    dist = body(f"{mid}_distal", [cyl(orad, o1 - o0, trans(z=(o0 + o1) / 2), om)],
                [distal(mid, trans(z=o1), SIZE[size])])
    joint = revolute(f"{mid}_joint", prox["ID"], dist["ID"], trans(z=zj) @ axis_y, rot_x(math.pi / 2), act)
    return module(mid, name, [prox, dist], [joint])


def tool(mid: str, name: str, size: int, flange, shaft, tip) -> dict:
    (fr, fh, fm), (tr, th, tm), (pr, ph, pm) = flange, shaft, tip
    parts = [cyl(fr, fh, trans(z=fh / 2), fm), cyl(tr, th, trans(z=fh + th / 2), tm),
             cyl(pr, ph, trans(z=fh + th + ph / 2), pm)]
    cons = [proximal(mid, SIZE[size]), tcp(mid, trans(z=fh + th + ph))]
    return module(mid, name, [body(f"{mid}_body", parts, cons)])


def build() -> dict:
    mods = [
        base("1", "base_floor", 0.12, (0.15, 0.025, 3.0), (0.08, 0.072, 1.6)),
        base("2", "base_pedestal", 0.6, (0.2, 0.025, 5.0), (0.09, 0.084, 4.2)),
        adapter("3", "adapter_4_to_3", 4, 3, 0.45, 0.28),
        adapter("4", "adapter_3_to_2", 3, 2, 0.28, 0.16),
        straight_link("5", "link_4_300", 0.30, 4, 4),
        straight_link("6", "link_4_600", 0.60, 4, 4),
        straight_link("7", "link_43_400", 0.40, 4, 3),
        straight_link("8", "link_43_600", 0.60, 4, 3),
        straight_link("9", "link_3_300", 0.30, 3, 3),
        straight_link("10", "link_3_600", 0.60, 3, 3),
        straight_link("11", "link_32_300", 0.30, 3, 2),
        straight_link("12", "link_32_500", 0.50, 3, 2),
        straight_link("13", "link_2_100", 0.10, 2, 2),
        straight_link("14", "link_2_200", 0.20, 2, 2),
        elbow_link("15", "elbow_3_90", 0.13, 0.13, 3, knuckle_mass=0.45),
        tool("16", "tool_flange_2", 2, (0.045, 0.015, 0.15), (0.03, 0.07, 0.3), (0.01, 0.05, 0.04)),
        tool("17", "tool_flange_3", 3, (0.06, 0.015, 0.25), (0.04, 0.09, 0.5), (0.012, 0.06, 0.06)),
        joint_inline("21", "joint_4_inline", 4, ACT_4, housing=(0.075, 0.16, 6.6), flange=(0.07, 0.035, 0.8)),
        joint_pitch("22", "joint_4_pitch", 4, ACT_4, neck=(0.075, 0.06, 1.2), drum=(0.08, 0.17, 5.4),
                    out=(0.075, 0.08, 0.14, 0.8)),
        joint_inline("23", "joint_3_inline", 3, ACT_3, housing=(0.06, 0.13, 3.3), flange=(0.056, 0.03, 0.5)),
        joint_pitch("24", "joint_3_pitch", 3, ACT_3, neck=(0.06, 0.05, 0.6), drum=(0.065, 0.14, 2.7),
                    out=(0.06, 0.065, 0.115, 0.5)),
        joint_inline("25", "joint_2_inline", 2, ACT_2, housing=(0.045, 0.11, 1.7), flange=(0.042, 0.025, 0.3)),
        joint_pitch("26", "joint_2_pitch", 2, ACT_2, neck=(0.045, 0.04, 0.3), drum=(0.05, 0.11, 1.4),
                    out=(0.045, 0.05, 0.09, 0.3)),
    ]
    return {"ignore_collisions": "rigid_via_joint", "modules": mods}


# --------------------------------------------------------------------------------------------------
# self-check
EXAMPLES = {
    # UR10e-like proportions: roll-pitch shoulder (size 4), tapered 0.4 m upper arm, size-3 elbow, tapered
    # 0.3 m forearm, size-2 roll-pitch-roll wrist (a spherical wrist: full orientation), tool
    "A": ["1", "21", "22", "7", "24", "11", "25", "26", "25", "16"],
    # the longest arm of the examples: 0.6 m upper arm and 0.5 m forearm (goals 1.0-1.5 m away)
    "B": ["1", "21", "22", "8", "24", "12", "25", "26", "25", "16"],
    # pedestal, size-3 roll after the elbow, adapter, size-2 pitch-roll wrist
    "C": ["2", "21", "22", "8", "24", "23", "4", "26", "25", "16"],
}
G = 9.81


def stretched_gravity_torque(db: dict, order: list) -> np.ndarray:
    """Static gravity torque [Nm] of every joint of a straight serial arm whose modules after the shoulder are
    held horizontal (e.g. q = (0, ±90°, 0, 0, 0, 0) for a roll-pitch shoulder), by hand: each body's weight
    times its lever (distance along the arm) to the joint, summed over the bodies beyond the joint. Only
    joints whose axis is perpendicular to the arm carry a moment; a roll joint carries none."""
    mods = {m["header"]["ID"]: m for m in db["modules"]}
    s, coms, axes = 0.0, [], []
    for mid in order:
        m = mods[mid]
        frames, js = A._module_frames(m, [0.0] * len(m.get("joints", [])))
        for b in m["bodies"]:
            coms.append((s + float((frames[b["ID"]] @ np.r_[b["r_com"], 1.0])[2]), b["mass"]))
        for J in js:
            axes.append((s + float(J[2, 3]), abs(J[2, 2]) < 1e-9))  # joint z axis perpendicular to the arm
        ends = [frames[b["ID"]] @ A._mat(c["pose"]) for b in m["bodies"] for c in b["connectors"] if c["gender"] == "m"]
        assert len(ends) == 1 and np.allclose(ends[0][:3, 2], [0, 0, 1]), f"module {mid} is not straight"
        s += float(ends[0][2, 3])
    return np.array([G * sum(mc * (sc - sj) for sc, mc in coms if sc > sj) if perp else 0.0 for sj, perp in axes])


def check(db: dict, verbose: bool = True, samples: int = 3000) -> None:
    ids = A.check_modules(db, 9.5, HERE)
    limits = {m["header"]["ID"]: [j["limits"]["peakTorque"] for j in m.get("joints", [])] for m in db["modules"]}
    rng = np.random.default_rng(0)
    for name, order in EXAMPLES.items():
        dof, joints, tcp_home = A.walk_serial(db, order)
        assert dof == 6, f"example {name}: {dof} DoF"
        reach = float(np.linalg.norm(tcp_home[:3, 3] - joints[1][:3, 3]))
        for _ in range(samples):
            q = rng.uniform(-math.pi, math.pi, dof)
            _, js, T = A.walk_serial(db, order, q)
            reach = max(reach, float(np.linalg.norm(T[:3, 3] - js[1][:3, 3])))
        tau = stretched_gravity_torque(db, order)
        lim = np.array([t for mid in order for t in limits[mid]])
        assert np.all(tau <= lim), f"example {name}: stretched gravity torque {tau.round(1)} over {lim}"
        mass = sum(b["mass"] for mid in order for m in db["modules"] if m["header"]["ID"] == mid for b in m["bodies"])
        if verbose:
            print(f"example {name}: {','.join(order)}  mass={mass:.2f} kg  TCP(home)={np.round(tcp_home[:3, 3], 3).tolist()}"
                  f"  reach~{reach:.2f} m  stretched gravity torque {np.round(tau, 1).tolist()} Nm")
    n = A.count_arms(db)
    assert n >= 1000, n
    if verbose:
        print(f"{len(ids)} modules; {n} distinct serial 6-DoF arms (<= 1 passive module per gap)")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="only check the file on disk")
    args = ap.parse_args(argv)
    if not args.check:
        OUT.write_text(json.dumps(build(), indent=2, allow_nan=False) + "\n", encoding="utf-8")
        print(f"wrote {OUT.relative_to(ROOT)}")
    check(json.loads(OUT.read_text(encoding="utf-8")))
    return 0


if __name__ == "__main__":
    sys.exit(main())
