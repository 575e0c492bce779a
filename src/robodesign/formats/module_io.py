"""Read and write CoBRA module sets (``<set>/modules.json``) into :mod:`robodesign.formats.module_spec`.

Every problem is reported as an :class:`~robodesign.core.errors.InputError` naming the file and the
JSON path, e.g. ``modules.json: modules[3].joints[0].limits.positionLower: expected a number, got "abc"``.
See docs/formats.md for where robodesign deliberately differs from the reference implementation.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Dict, Optional, Union

import numpy as np

from robodesign.core.errors import InputError, describe_value
from robodesign.core.input_warnings import InputWarnings
from robodesign.core.jsonio import check_finite, dumps_json, load_json
from robodesign.core.paths import builtin_module_sets
from robodesign.core.schema import validate
from robodesign.core.spatial import parse_pose, pose_to_list
from robodesign.formats.geometry import canonical_geometry_json, parse_geometries
from robodesign.formats.module_spec import (
    IGNORE_COLLISIONS,
    Body,
    Connector,
    Joint,
    JointLimits,
    Module,
    ModuleHeader,
    ModuleSet,
)

_GENDER = {"f": "f", "female": "f", "m": "m", "male": "m", "h": "h", "hermaphroditic": "h"}
_JOINT_TYPE = {"revolute": "revolute", "continuous": "revolute", "revolute_active": "revolute",
               "prismatic": "prismatic", "prismatic_active": "prismatic", "fixed": "fixed"}
_JOINT_KEYS = {"id": "ID", "parent": "parent", "child": "child", "type": "type", "passive": "passive",
               "poseparent": "poseParent", "parent2joint": "poseParent", "posechild": "poseChild",
               "joint2child": "poseChild", "limits": "limits", "gearratio": "gearRatio",
               "motorinertia": "motorInertia", "frictioncoulomb": "frictionCoulomb",
               "frictionviscous": "frictionViscous"}
_LIMIT_KEYS = {"positionlower": "lower", "lower": "lower", "positionupper": "upper", "upper": "upper",
               "peaktorque": "torque", "velocity": "velocity", "acceleration": "acceleration"}


def resolve_module_set_path(name_or_path: Union[str, Path]) -> Path:
    """A folder holding ``modules.json``, a path to such a file, or the name of a built-in set."""
    p = Path(name_or_path)
    if p.is_file():
        return p
    if p.is_dir():
        f = p / "modules.json"
        if not f.is_file():
            raise InputError("folder has no modules.json", file=str(p))
        return f
    builtin = builtin_module_sets()
    if str(name_or_path) in builtin:
        return builtin[str(name_or_path)] / "modules.json"
    known = ", ".join(builtin) or "none"
    raise InputError(f"no such module set folder or built-in module set (built-in: {known})", file=str(name_or_path))


_CACHE: Dict[str, ModuleSet] = {}


def load_module_set(name_or_path: Union[str, Path], use_cache: bool = True) -> ModuleSet:
    """Load (and validate) a module set by folder, file or built-in name. Cached per process.

    A ``.urdf`` file is imported as a one-module set (a monolithic robot, :func:`robodesign.formats.urdf.import_urdf`).
    """
    if str(name_or_path).lower().endswith(".urdf"):
        p = Path(name_or_path)
        if not p.is_file():
            raise InputError("file not found", file=str(p))
        key = f"{p.resolve()}:{p.stat().st_mtime_ns}"
        if not (use_cache and key in _CACHE):
            from robodesign.formats.urdf import import_urdf
            _CACHE[key] = import_urdf(p)
        return _CACHE[key]
    f = resolve_module_set_path(name_or_path).resolve()
    key = f"{f}:{f.stat().st_mtime_ns}"
    if use_cache and key in _CACHE:
        return _CACHE[key]
    ms = parse_module_set(load_json(f, display_name=_display(f)), f)
    _CACHE[key] = ms
    return ms


def _display(f: Path) -> str:
    return f"{f.parent.name}/{f.name}"


def parse_module_set(data, file: Path, name: Optional[str] = None) -> ModuleSet:
    fname = _display(file)
    root = file.parent
    warnings = InputWarnings()
    if isinstance(data, dict) and isinstance(data.get("modules"), list):
        data = dict(data, modules=[_canonical_module(m, fname, ["modules", i], warnings)
                                   for i, m in enumerate(data["modules"])])
    validate(data, "modules", fname)
    modules: Dict[str, Module] = {}
    names: Dict[str, str] = {}  # module name → its ID
    for i, m in enumerate(data["modules"]):
        mod = _parse_module(m, root, fname, ["modules", i], warnings)
        if mod.id in modules:
            raise InputError(f"duplicate module ID {mod.id!r}", file=fname, path=["modules", i, "header", "ID"])
        if mod.name in names:
            raise InputError(f"duplicate module name {mod.name!r} (also module {names[mod.name]!r})", file=fname,
                             path=["modules", i, "header", "name"])
        names[mod.name] = mod.id
        modules[mod.id] = mod
    ic = data.get("ignore_collisions", "via_joint")
    if ic not in IGNORE_COLLISIONS:
        raise InputError(f"expected one of {IGNORE_COLLISIONS}, got {describe_value(ic)}", file=fname,
                         path=["ignore_collisions"])
    return ModuleSet(name=name or file.parent.name, modules=modules, root=root, ignore_collisions=ic,
                     source=str(file), warnings=warnings.messages)


_JOINT_SPELLING = {k.lower(): k for k in ("ID", "parent", "child", "type", "passive", "poseParent", "parent2joint",
                                           "poseChild", "joint2child", "limits", "gearRatio", "motorInertia",
                                           "frictionCoulomb", "frictionViscous")}
_LIMIT_SPELLING = {k.lower(): k for k in ("positionLower", "lower", "positionUpper", "upper", "peakTorque", "velocity",
                                          "acceleration")}


def _respell(d, spelling):
    """Keys matched case-insensitively to their canonical spelling (as the reference's alias table does)."""
    return {spelling.get(k.lower(), k) if isinstance(k, str) else k: v for k, v in d.items()}


def _canonical_module(m, file, path, warnings):
    """Variants of real files in canonical form: null optional header strings (absent), joint and limit keys
    in any letter case, geometry type case and ignored geometry parameters (geometry.py)."""
    if not isinstance(m, dict):
        return m
    m = dict(m)
    if isinstance(m.get("header"), dict):
        h = {k: v for k, v in m["header"].items() if not (v is None and k != "ID")}
        for k in ("author", "email", "affiliation"):
            if isinstance(h.get(k), list):
                h[k] = [x for x in h[k] if x is not None]
        m["header"] = h
    joints = m.get("joints")
    if isinstance(joints, (list, dict)):
        js = [_respell(j, _JOINT_SPELLING) if isinstance(j, dict) else j
              for j in (joints if isinstance(joints, list) else [joints])]
        for j in js:
            if isinstance(j, dict) and isinstance(j.get("limits"), dict):
                j["limits"] = _respell(j["limits"], _LIMIT_SPELLING)
        m["joints"] = js if isinstance(joints, list) else js[0]
    if not isinstance(m.get("bodies"), (list, dict)):
        return m
    many = isinstance(m["bodies"], list)
    out = []
    for i, b in enumerate(m["bodies"] if many else [m["bodies"]]):
        if isinstance(b, dict):
            b = dict(b)
            for key in ("collision", "visual"):
                if key in b:
                    bp = path + ["bodies", i] if many else path + ["bodies"]
                    b[key] = canonical_geometry_json(b[key], file, bp + [key], warnings)
        out.append(b)
    return dict(m, bodies=out if many else out[0])


def _vec(value, n, file, path):
    if not isinstance(value, list) or len(value) != n:
        raise InputError(f"expected {n} numbers, got {describe_value(value)}", file=file, path=path)
    return np.array([check_finite(v, file, list(path) + [k]) for k, v in enumerate(value)])


def _as_list(v):
    if v is None:
        return []
    return v if isinstance(v, list) else [v]


def _parse_module(m, root, file, path, warnings) -> Module:
    h = m["header"]
    header = ModuleHeader(id=str(h["ID"]), name=str(h.get("name", h["ID"])), date=str(h.get("date", "")),
                          author=tuple(_as_list(h.get("author"))), email=tuple(_as_list(h.get("email"))),
                          affiliation=tuple(_as_list(h.get("affiliation"))),
                          cost=check_finite(h.get("cost", 0.0), file, path + ["header", "cost"]))
    bodies = []
    seen_b, seen_c = set(), set()
    raw_bodies = m.get("bodies", [])
    body_list = raw_bodies if isinstance(raw_bodies, list) else [raw_bodies]
    for bi, b in enumerate(body_list):
        bp = path + ["bodies", bi] if isinstance(raw_bodies, list) else path + ["bodies"]
        body = _parse_body(b, root, file, bp, warnings)
        if body.id in seen_b:
            raise InputError(f"duplicate body ID {body.id!r} in module {header.id!r}", file=file, path=bp + ["ID"])
        seen_b.add(body.id)
        for ci, c in enumerate(body.connectors):
            if c.id in seen_c:
                raise InputError(f"duplicate connector ID {c.id!r} in module {header.id!r}", file=file,
                                 path=bp + ["connectors", ci, "ID"])
            seen_c.add(c.id)
        bodies.append(body)
    joints = []
    raw_joints = m.get("joints", [])
    joint_list = raw_joints if isinstance(raw_joints, list) else [raw_joints]
    if joint_list and not bodies:
        raise InputError("a module with joints needs bodies", file=file, path=path + ["joints"])
    seen_j = set()
    for ji, j in enumerate(joint_list):
        jp = path + ["joints", ji] if isinstance(raw_joints, list) else path + ["joints"]
        joint = _parse_joint(j, file, jp)
        if joint.id in seen_j:
            raise InputError(f"duplicate joint ID {joint.id!r} in module {header.id!r}", file=file, path=jp + ["ID"])
        seen_j.add(joint.id)
        for key, ref in (("parent", joint.parent), ("child", joint.child)):
            if ref not in seen_b:
                raise InputError(f"joint {joint.id!r} references unknown body {ref!r} (bodies of module "
                                 f"{header.id!r}: {sorted(seen_b)})", file=file, path=jp + [key])
        if joint.parent == joint.child:
            raise InputError("parent and child are the same body", file=file, path=jp + ["child"])
        joints.append(joint)
    _check_tree(header.id, bodies, joints, file, path)
    return Module(header=header, bodies=tuple(bodies), joints=tuple(joints))


def _check_tree(mid, bodies, joints, file, path):
    """Bodies and joints of a module must form a tree (connected, no loops)."""
    if len(bodies) <= 1:
        return
    parent = {b.id: b.id for b in bodies}

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x
    for ji, j in enumerate(joints):
        a, b = find(j.parent), find(j.child)
        if a == b:
            raise InputError(f"joint {j.id!r} closes a kinematic loop in module {mid!r}", file=file,
                             path=path + ["joints", ji])
        parent[a] = b
    roots = {find(b.id) for b in bodies}
    if len(roots) > 1:
        raise InputError(f"bodies of module {mid!r} are not all connected by joints", file=file, path=path + ["bodies"])


def _parse_body(b, root, file, path, warnings) -> Body:
    bid = str(b["ID"])
    mass = check_finite(b.get("mass", 0.0), file, path + ["mass"])
    if mass < 0:
        raise InputError(f"mass must be >= 0, got {mass}", file=file, path=path + ["mass"])
    com = _vec(b.get("r_com", [0, 0, 0]), 3, file, path + ["r_com"])
    inertia_raw = b.get("inertia", [[0, 0, 0]] * 3)
    if not isinstance(inertia_raw, list) or len(inertia_raw) != 3:
        raise InputError(f"expected a 3x3 matrix, got {describe_value(inertia_raw)}", file=file, path=path + ["inertia"])
    inertia = np.array([_vec(r, 3, file, path + ["inertia", k]) for k, r in enumerate(inertia_raw)])
    if np.abs(inertia - inertia.T).max() > 1e-9 * max(1.0, np.abs(inertia).max()):
        raise InputError("inertia matrix is not symmetric", file=file, path=path + ["inertia"])
    if np.linalg.eigvalsh(inertia).min() < -1e-12:
        raise InputError("inertia matrix is not positive semi-definite", file=file, path=path + ["inertia"])
    cons = []
    for ci, c in enumerate(_as_list(b.get("connectors"))):
        cp = path + ["connectors", ci]
        gender = _GENDER.get(str(c.get("gender", "h")).lower())
        if gender is None:
            raise InputError(f"gender must be f, m or h, got {describe_value(c.get('gender'))}", file=file,
                             path=cp + ["gender"])
        if "pose" not in c:
            raise InputError("connector needs a pose", file=file, path=cp)
        size = c.get("size", [])
        size_l = size if isinstance(size, list) else [size]
        size_t = tuple(check_finite(s, file, cp + ["size", k]) for k, s in enumerate(size_l))
        cons.append(Connector(id=str(c["ID"]), body_id=bid, pose=parse_pose(c["pose"], file, cp + ["pose"]),
                              gender=gender, type=str(c.get("type", "")), size=size_t))
    collision = parse_geometries(b.get("collision"), root, file, path + ["collision"], required_files=True)
    if "visual" in b:
        visual = parse_geometries(b.get("visual"), root, file, path + ["visual"], required_files=False,
                                  warnings=warnings)
    else:
        visual = collision
    return Body(id=bid, mass=mass, com=com, inertia=inertia, connectors=tuple(cons), collision=collision,
                visual=visual)


def _parse_joint(j, file, path) -> Joint:
    norm = {}
    for k, v in j.items():
        key = _JOINT_KEYS.get(k.lower())
        if key is None:
            raise InputError(f"unknown joint key {k!r}", file=file, path=path + [k])
        norm[key] = (k, v)

    def get(key, default=None):
        return norm[key][1] if key in norm else default

    def p(key):
        return path + [norm[key][0]] if key in norm else path + [key]
    for req in ("ID", "parent", "child", "limits"):
        if req not in norm:
            raise InputError(f"'{req}' is required but missing", file=file, path=path)
    jtype = _JOINT_TYPE.get(str(get("type", "revolute")).lower())
    if jtype is None:
        raise InputError(f"unsupported joint type {describe_value(get('type'))} "
                         f"(revolute, prismatic, fixed)", file=file, path=p("type"))
    if get("passive", False):
        raise InputError("passive joints are not supported", file=file, path=p("passive"))
    lim_raw = get("limits")
    if not isinstance(lim_raw, dict):
        raise InputError(f"expected an object, got {describe_value(lim_raw)}", file=file, path=p("limits"))
    lim = {}
    for k, v in lim_raw.items():
        key = _LIMIT_KEYS.get(k.lower())
        if key is None:
            raise InputError(f"unknown limit {k!r}", file=file, path=p("limits") + [k])
        lim[key] = check_finite(v, file, p("limits") + [k], allow_inf=True)
    if "lower" not in lim or "upper" not in lim:
        raise InputError("positionLower and positionUpper are required", file=file, path=p("limits"))
    if lim["lower"] > lim["upper"]:
        raise InputError(f"positionLower {lim['lower']} > positionUpper {lim['upper']}", file=file,
                         path=p("limits") + ["positionLower"])
    for k in ("velocity", "acceleration", "torque"):
        if lim.get(k, math.inf) < 0:
            raise InputError(f"limit must be >= 0, got {lim[k]}", file=file, path=p("limits"))
    limits = JointLimits(lower=lim["lower"], upper=lim["upper"], velocity=lim.get("velocity", math.inf),
                         acceleration=lim.get("acceleration", math.inf), torque=lim.get("torque", math.inf))

    def scalar(key, default):
        v = check_finite(get(key, default), file, p(key))
        if v < 0:
            raise InputError(f"must be >= 0, got {v}", file=file, path=p(key))
        return v
    return Joint(id=str(get("ID")), type=jtype, parent=str(get("parent")), child=str(get("child")),
                 pose_parent=parse_pose(get("poseParent", np.eye(4).tolist()), file, p("poseParent")),
                 pose_child=parse_pose(get("poseChild", np.eye(4).tolist()), file, p("poseChild")),
                 limits=limits, gear_ratio=scalar("gearRatio", 1.0), motor_inertia=scalar("motorInertia", 0.0),
                 friction_coulomb=scalar("frictionCoulomb", 0.0), friction_viscous=scalar("frictionViscous", 0.0))


# ---------------------------------------------------------------------------------------------
# Writing
# ---------------------------------------------------------------------------------------------

def module_to_json(m: Module) -> dict:
    h = m.header
    return {
        "header": {"ID": h.id, "name": h.name, "date": h.date, "author": list(h.author), "email": list(h.email),
                   "affiliation": list(h.affiliation), "cost": h.cost},
        "bodies": [{
            "ID": b.id, "mass": b.mass, "r_com": b.com.tolist(), "inertia": b.inertia.tolist(),
            "connectors": [{"ID": c.id, "pose": pose_to_list(c.pose), "gender": c.gender, "type": c.type,
                            "size": list(c.size)} for c in b.connectors],
            "collision": [g.to_json() for g in b.collision],
            "visual": [g.to_json() for g in b.visual],
        } for b in m.bodies],
        "joints": [{
            "ID": j.id, "parent": j.parent, "child": j.child, "type": j.type, "passive": False,
            "poseParent": pose_to_list(j.pose_parent), "poseChild": pose_to_list(j.pose_child),
            "limits": {"positionLower": j.limits.lower, "positionUpper": j.limits.upper,
                       "peakTorque": j.limits.torque, "velocity": j.limits.velocity,
                       "acceleration": j.limits.acceleration},
            "gearRatio": j.gear_ratio, "motorInertia": j.motor_inertia, "frictionCoulomb": j.friction_coulomb,
            "frictionViscous": j.friction_viscous,
        } for j in m.joints],
    }


def module_set_to_json(ms: ModuleSet) -> dict:
    return {"ignore_collisions": ms.ignore_collisions, "modules": [module_to_json(m) for m in ms]}


def write_module_set(ms: ModuleSet, folder: Path) -> Path:
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    f = folder / "modules.json"
    f.write_text(dumps_json(module_set_to_json(ms)))
    return f
