"""Read and write CoBRA task files (``<package>/<task ID>.json``) into :mod:`robodesign.formats.task_spec`.

Reading is two steps: every variant of the format that the reference implementation reads is first
brought into canonical form (``_canonical_task``; the list is in docs/formats.md), then schema-validated
and parsed. Errors name the file and the JSON path. Unknown keys the reference ignores, and a missing or
empty *visual* mesh, are warnings (``Task.warnings``, each once; printed by the CLI); a missing or broken
*collision* mesh is an error. Asset paths are resolved relative to the task *package* folder (the folder
the task ID's namespace starts in: ``simple/PTP_2`` at ``tasks/simple/PTP_2.json`` → package ``tasks/``)
and may not escape it.
"""
from __future__ import annotations

import difflib
import json
import math
from pathlib import Path
from typing import Dict, List, Optional, Tuple, Union

import numpy as np

from robodesign.core.errors import InputError, PathPart, describe_value
from robodesign.core.input_warnings import InputWarnings
from robodesign.core.jsonio import check_finite, load_json
from robodesign.core.paths import builtin_tasks_dir
from robodesign.core.schema import load_schema, validate
from robodesign.core.spatial import parse_pose
from robodesign.formats.geometry import GeometrySpec, canonical_geometry_json, parse_geometries
from robodesign.formats.goal_types import GoalContext, find_goal_type, goal_type, plugin_goal_types, register_goal_type
from robodesign.formats.task_spec import (
    GLOBAL_ONLY,
    AllGoalsFulfilled,
    AlwaysTrue,
    At,
    BasePlacement,
    CollisionFree,
    EndEffectorConstraint,
    Follow,
    Goal,
    GoalsInOrder,
    JointLimitsConstraint,
    Leave,
    ObstacleSpec,
    Pause,
    Reach,
    ReturnTo,
    SelfCollisionFree,
    Task,
    TaskConstraint,
    TaskHeader,
    ValidAssembly,
    default_constraints,
)
from robodesign.formats.tolerance import ToleratedPose

RESERVED_FRAMES = ("world", "nominal")


def resolve_task_path(name_or_path: Union[str, Path]) -> Path:
    p = Path(name_or_path)
    if p.is_file():
        return p
    if p.suffix != ".json" and Path(str(p) + ".json").is_file():
        return Path(str(p) + ".json")
    cand = builtin_tasks_dir() / (str(name_or_path) + ("" if str(name_or_path).endswith(".json") else ".json"))
    if cand.is_file():
        return cand
    builtin = sorted(f.relative_to(builtin_tasks_dir()).with_suffix("").as_posix()
                     for f in builtin_tasks_dir().glob("*/*.json")) if builtin_tasks_dir().is_dir() else []
    close = difflib.get_close_matches(str(name_or_path), builtin, n=1)
    raise InputError("no such task file or built-in task" + (f" (did you mean {close[0]!r}?)" if close else "")
                     + (f"; built-in tasks: {', '.join(builtin)}" if builtin else ""), file=str(name_or_path))


def _package_root(file: Path, task_id: str) -> Path:
    """``<package>/<ID>.json``: strip one folder per ``/`` in the task ID."""
    root = file.resolve().parent
    for _ in range(task_id.count("/")):
        root = root.parent
    return root


def load_task(name_or_path: Union[str, Path]) -> Task:
    f = resolve_task_path(name_or_path)
    data = load_json(f, display_name=f.name)
    return parse_task(data, f)


def validate_task_json(data, fname: str, warnings: Optional[InputWarnings] = None) -> dict:
    """Bring task JSON into canonical form (every variant the reference reads, docs/formats.md) and
    schema-validate it. Unknown keys the reference ignores are dropped and reported in ``warnings``."""
    if not isinstance(data, dict):
        raise InputError("a task file must hold a JSON object", file=fname)
    data = _canonical_task(data, fname, InputWarnings() if warnings is None else warnings)
    validate(data, "task", fname, schema=_task_schema())
    return data


def _task_schema() -> Optional[dict]:
    """task.schema.json extended by the registered plugin goal types (None without any: the file's)."""
    plugins = plugin_goal_types()
    if not plugins:
        return None
    schema = load_schema("task")
    goal = schema["$defs"]["goal"]
    goal["properties"]["type"]["enum"] += [gt.name for gt in plugins]
    for gt in plugins:
        goal["allOf"].append({"if": {"properties": {"type": {"enum": [gt.name]}}, "required": ["type"]},
                              "then": gt.schema or {}})
    return schema


# ---------------------------------------------------------------------------------------------
# Variants → canonical form (one place; see docs/formats.md, "Variants read as the reference reads them")
# ---------------------------------------------------------------------------------------------
_HEADER_OPTIONAL = ("version", "taskName", "date", "tags", "author", "email", "affiliation")
_HEADER_LISTS = ("tags", "author", "email", "affiliation")
_OBSTACLE_KEYS = ("ID", "name", "collision", "visual", "pose", "acknowledgement", "trajectory")
_GOAL_KEYS = ("ID", "type", "constraints", "goalPose", "returnToGoal", "epsilon", "duration", "trajectory",
              "externalForce", "externalTorque", "forceTorqueReferenceFrame", "occupiedSpace", "region")
_LENIENT_CONSTRAINT_KEYS = {"basePlacement": ("type", "pose"),
                            "endEffector": ("type", "pose", "v_min", "v_max", "o_min", "o_max")}


def _canonical_task(data: dict, f: str, w: InputWarnings) -> dict:
    out = dict(data)
    if "Constraints" in out and "constraints" not in out:
        w.add(f, ["Constraints"], "read as 'constraints' (the key is lower case)")
        out["constraints"] = out.pop("Constraints")
    if isinstance(out.get("header"), dict):
        h = dict(out["header"])
        for k in ("ID", "version", "taskName"):  # the reference casts these to str
            if isinstance(h.get(k), (int, float)) and not isinstance(h.get(k), bool):
                h[k] = _number_text(h[k])
        for k in _HEADER_OPTIONAL:
            if k in h and h[k] is None:
                del h[k]  # null = absent
            elif k in _HEADER_LISTS and isinstance(h.get(k), str):
                h[k] = [h[k]]
            elif k in _HEADER_LISTS and isinstance(h.get(k), list):
                h[k] = [x for x in h[k] if x is not None]
        out["header"] = h
    if isinstance(out.get("obstacles"), list):
        out["obstacles"] = [_canonical_obstacle(o, f, ["obstacles", i], w) for i, o in enumerate(out["obstacles"])]
    if isinstance(out.get("goals"), list):
        out["goals"] = [_canonical_goal(g, f, ["goals", i], w) for i, g in enumerate(out["goals"])]
    if isinstance(out.get("constraints"), list):
        out["constraints"] = [_canonical_constraint(c, f, ["constraints", i], w)
                              for i, c in enumerate(out["constraints"])]
    return out


def _number_text(v) -> str:
    return str(int(v)) if isinstance(v, float) and v.is_integer() and abs(v) < 1e15 else str(v)


def _canonical_obstacle(o, f, path, w):
    if not isinstance(o, dict):
        return o
    out = {}
    for k, v in o.items():
        if k not in _OBSTACLE_KEYS:
            w.ignored_key(f, path, k, _OBSTACLE_KEYS)
        elif v is not None or k not in ("name", "acknowledgement", "visual"):  # null = absent
            out[k] = v
    for k in ("collision", "visual"):
        if k in out:
            out[k] = canonical_geometry_json(out[k], f, path + [k], w)
    pose = out.get("pose")
    if isinstance(pose, dict):  # informative pose written as a tolerated pose: its nominal
        pose = ToleratedPose.canonical_json(pose, f, path + ["pose"], w)
        if "nominal" not in pose:
            raise InputError("an obstacle pose given as an object needs 'nominal'", file=f, path=path + ["pose"])
        out["pose"] = pose["nominal"]
    return out


def _canonical_goal(g, f, path, w):
    if not isinstance(g, dict):
        return g
    gt = find_goal_type(g["type"]) if isinstance(g.get("type"), str) else None
    names = {k.lower(): k for k in _GOAL_KEYS + (gt.keys if gt is not None else ())}
    out = {}
    for k, v in g.items():
        canon = names.get(str(k).lower())  # the reference matches goal keys case-insensitively
        if canon is None:
            w.ignored_key(f, path, k, tuple(names.values()))
            continue
        if canon in out:
            raise InputError(f"{k!r} is given twice (keys are matched case-insensitively)", file=f, path=path + [k])
        if v is None and canon in ("returnToGoal", "constraints", "epsilon"):
            continue  # null = absent
        out[canon] = v
    if gt is not None:
        out["type"] = gt.name
        out = gt.cls.canonical_json(out, f, path, w)
    if "goalPose" in out:
        out["goalPose"] = ToleratedPose.canonical_json(out["goalPose"], f, path + ["goalPose"], w)
    if isinstance(out.get("trajectory"), dict):
        traj = {k: v for k, v in out["trajectory"].items() if not (k == "t" and v is None)}
        g2t = traj.pop("goal2time", None)  # the reference's Trajectory writes it (empty); goals ignore it
        if g2t:
            w.add(f, path + ["trajectory", "goal2time"], "ignored (a follow goal's trajectory has no goal times)")
        if isinstance(traj.get("t"), list) and len(traj["t"]) == 1 and len(traj.get("pose") or ()) > 1:
            traj["t"] = traj["t"][0]  # one time for several poses is the time step (reference: t.size == 1)
        if isinstance(traj.get("pose"), list):
            traj["pose"] = [ToleratedPose.canonical_json(p, f, path + ["trajectory", "pose", i], w)
                            for i, p in enumerate(traj["pose"])]
        out["trajectory"] = traj
    if "occupiedSpace" in out:
        out["occupiedSpace"] = canonical_geometry_json(out["occupiedSpace"], f, path + ["occupiedSpace"], w)
    region = out.get("region")
    if isinstance(region, dict) and "nominal" in region:
        out["region"] = ToleratedPose.canonical_json(region, f, path + ["region"], w)
    elif region is not None:
        out["region"] = canonical_geometry_json(region, f, path + ["region"], w)
    if isinstance(out.get("constraints"), list):
        out["constraints"] = [_canonical_constraint(c, f, path + ["constraints", i], w)
                              for i, c in enumerate(out["constraints"])]
    return out


def _canonical_constraint(c, f, path, w):
    if not isinstance(c, dict):
        return c
    if not c:
        return {"type": "alwaysTrue"}  # the reference reads {} as "always true" (and writes it so)
    out = dict(c)
    kind = out.get("type")
    known = _LENIENT_CONSTRAINT_KEYS.get(kind) if isinstance(kind, str) else None  # schema reports a bad type
    if known:  # these two constraints ignore other keys in the reference; the others reject them
        for k in c:
            if k not in known:
                w.ignored_key(f, path, k, known)
                del out[k]
        if "pose" in out:
            out["pose"] = ToleratedPose.canonical_json(out["pose"], f, path + ["pose"], w)
    return out


def parse_task(data, file: Path) -> Task:
    fname = file.name
    warnings = InputWarnings()
    data = validate_task_json(data, fname, warnings)
    h = data["header"]
    tid = str(h["ID"])
    root = _package_root(file, tid)
    stem = file.resolve().with_suffix("").as_posix()
    if not (stem == tid or stem.endswith("/" + tid)) and '"file"' in json.dumps(data.get("obstacles", [])) + \
            json.dumps(data.get("goals", [])):
        warnings.add(fname, ["header", "ID"], f"the file is not at <package>/{tid}.json, so mesh paths resolve "
                                              f"against {root} (the folder the ID's namespace implies)")
    ts = check_finite(h.get("timeStepSize", 0.01), fname, ["header", "timeStepSize"])
    if ts <= 0:
        raise InputError(f"must be positive, got {ts}", file=fname, path=["header", "timeStepSize"])
    grav = h.get("gravity", [0, 0, -9.81])
    if not isinstance(grav, list) or len(grav) != 3:
        raise InputError(f"expected 3 numbers, got {describe_value(grav)}", file=fname, path=["header", "gravity"])
    gx, gy, gz = (check_finite(g, fname, ["header", "gravity", k]) for k, g in enumerate(grav))
    header = TaskHeader(id=tid, version=str(h.get("version", "2023")), name=str(h.get("taskName", "")),
                        tags=tuple(h.get("tags", [])), date=str(h.get("date", "")), time_step=ts, gravity=(gx, gy, gz),
                        author=tuple(_as_list(h.get("author"))), email=tuple(_as_list(h.get("email"))),
                        affiliation=tuple(_as_list(h.get("affiliation"))))
    frames = _parse_frames(data.get("frames", {}), fname)

    resolver = FrameResolver(frames)

    obstacles = []
    seen = set()
    for i, o in enumerate(data.get("obstacles", [])):
        op: List[PathPart] = ["obstacles", i]
        oid = str(o["ID"])
        if oid in seen:
            raise InputError(f"duplicate obstacle ID {oid!r}", file=fname, path=op + ["ID"])
        seen.add(oid)
        col = parse_geometries(o.get("collision"), root, fname, op + ["collision"], required_files=True)
        vis = parse_geometries(o["visual"], root, fname, op + ["visual"], required_files=False,
                               warnings=warnings) if "visual" in o else col
        mt = mp = None
        if "trajectory" in o:
            mt, mp = _parse_motion(o["trajectory"], ts, fname, op + ["trajectory"])
        obstacles.append(ObstacleSpec(oid, str(o.get("name", oid)), col, vis, mt, mp))
    goals = []
    gseen = set()
    for i, g in enumerate(data.get("goals", [])):
        goal = _parse_goal(g, fname, ["goals", i], resolver, root)
        if goal.id in gseen:
            raise InputError(f"duplicate goal ID {goal.id!r}", file=fname, path=["goals", i, "ID"])
        gseen.add(goal.id)
        goals.append(goal)
    if "constraints" in data:
        constraints = tuple(_parse_constraint(c, fname, ["constraints", i], resolver, True)
                            for i, c in enumerate(data["constraints"]))
    else:
        constraints = default_constraints()
    for i, c in enumerate(constraints):
        if isinstance(c, GoalsInOrder):
            for k, gid in enumerate(c.order):
                if gid not in gseen:
                    raise InputError(f"unknown goal ID {gid!r}", file=fname, path=["constraints", i, "order", k])
    for i, g in enumerate(goals):
        for key, gid in g.referenced_goals:
            if gid not in gseen:
                raise InputError(f"unknown goal ID {gid!r}", file=fname, path=["goals", i, key])
    return Task(header=header, obstacles=tuple(obstacles), goals=tuple(goals), constraints=constraints,
                frames=frames, root=root, source=str(file), warnings=warnings.messages)


class FrameResolver:
    """name → world pose of a task frame (picklable, so tasks can be shipped to worker processes)."""

    def __init__(self, frames: Dict[str, np.ndarray]):
        self.frames = frames

    def __call__(self, name: str) -> np.ndarray:
        if name == "world":
            return np.eye(4)
        if name not in self.frames:
            raise KeyError(name)
        return self.frames[name]


def _as_list(v):
    if v is None:
        return []
    return v if isinstance(v, list) else [v]


def _parse_frames(raw, fname) -> Dict[str, np.ndarray]:
    if not isinstance(raw, dict):
        raise InputError("expected an object {name: {parent, transformation}}", file=fname, path=["frames"])
    local = {}
    for name, f in raw.items():
        fp = ["frames", name]
        if "." in name or name in RESERVED_FRAMES:
            raise InputError(f"invalid frame name {name!r} (no '.', not 'world' or 'nominal')", file=fname, path=fp)
        if not isinstance(f, dict) or "transformation" not in f:
            raise InputError("a frame needs 'transformation' (and optional 'parent')", file=fname, path=fp)
        local[name] = (str(f.get("parent", "world")), parse_pose(f["transformation"], fname, fp + ["transformation"]))
    out: Dict[str, np.ndarray] = {}

    def world(name, stack):
        if name == "world":
            return np.eye(4)
        if name in out:
            return out[name]
        if name not in local:
            raise InputError(f"unknown parent frame {name!r}", file=fname, path=["frames", stack[-1], "parent"])
        if name in stack:
            raise InputError(f"frame cycle: {' → '.join(stack + [name])}", file=fname, path=["frames", name])
        parent, T = local[name]
        out[name] = world(parent, stack + [name]) @ T
        return out[name]
    for name in local:
        world(name, [])
    return out


def _parse_motion(raw, dt, fname, path):
    if not isinstance(raw, dict) or "pose" not in raw:
        raise InputError("a moving obstacle's trajectory needs 'pose' (list of 4x4) and 't'", file=fname, path=path)
    poses = np.array([parse_pose(p, fname, path + ["pose", k]) for k, p in enumerate(raw["pose"])])
    t = raw.get("t", dt)
    if isinstance(t, (int, float)) and not isinstance(t, bool):
        step = check_finite(t, fname, path + ["t"])
        tt = np.arange(len(poses)) * step
    else:
        tt = np.array([check_finite(x, fname, path + ["t", k]) for k, x in enumerate(t)])
        if len(tt) != len(poses):
            raise InputError(f"{len(tt)} times for {len(poses)} poses", file=fname, path=path + ["t"])
        if np.any(np.diff(tt) <= 0):
            raise InputError("times must be strictly increasing", file=fname, path=path + ["t"])
    return tt, poses


def _tolerated(obj, fname, path, resolver, empty_means_any=False) -> ToleratedPose:
    return ToleratedPose.from_json(obj, file=fname, path=path, frame_resolver=resolver,
                                   empty_means_any=empty_means_any)


def _ci(d: dict) -> dict:
    return {k.lower(): (k, v) for k, v in d.items()}


def _parse_constraint(c, fname, path, resolver, task_level) -> TaskConstraint:
    t = c.get("type")
    ci = _ci(c)
    out: TaskConstraint
    if t == "joint":
        parts = c.get("parts", ["q", "dq", "ddq", "tau"])
        if isinstance(parts, str):
            parts = [p.strip() for p in parts.split(",") if p.strip()]
        norm = set()
        for k, p in enumerate(parts):
            pl = str(p).lower()
            if pl not in ("q", "dq", "ddq", "tau"):
                raise InputError(f"unknown joint constraint part {p!r} (q, dq, ddq, tau)", file=fname,
                                 path=path + ["parts", k])
            norm.add(pl)
        out = JointLimitsConstraint(frozenset(norm))
    elif t == "collisionFree":
        m = check_finite(c.get("safety_margin", c.get("safetyMargin", 0.0)), fname, path + ["safety_margin"])
        if m < 0:
            raise InputError(f"must be >= 0, got {m}", file=fname, path=path + ["safety_margin"])
        out = CollisionFree(m)
    elif t == "selfCollisionFree":
        out = SelfCollisionFree()
    elif t == "basePlacement":
        if "pose" not in c:
            raise InputError("basePlacement needs a 'pose'", file=fname, path=path)
        out = BasePlacement(_tolerated(c["pose"], fname, path + ["pose"], resolver, empty_means_any=True))
    elif t == "endEffector":
        pose = _tolerated(c["pose"], fname, path + ["pose"], resolver) if "pose" in c else None
        vals: Dict[str, float] = {}
        for key, d in (("v_min", 0.0), ("v_max", math.inf), ("o_min", 0.0), ("o_max", math.inf)):
            vals[key] = check_finite(c.get(key, d), fname, path + [key], allow_inf=True)
        out = EndEffectorConstraint(pose, **vals)
    elif t == "allGoalsFulfilled":
        out = AllGoalsFulfilled()
    elif t == "allGoalsFulfilledInOrder":
        order = c.get("order")
        if not isinstance(order, list):
            raise InputError("expected a list of goal IDs", file=fname, path=path + ["order"])
        out = GoalsInOrder(tuple(str(x) for x in order))
    elif t in ("validAssembly",):
        out = ValidAssembly()
    elif t in ("alwaysTrue", None):
        out = AlwaysTrue()
    elif t == "goalsBySameRobot":
        raise InputError("goalsBySameRobot is not supported (multi-robot tasks)", file=fname, path=path + ["type"])
    else:
        raise InputError(f"unknown constraint type {describe_value(t)}", file=fname, path=path + ["type"])
    del ci
    if not task_level and isinstance(out, GLOBAL_ONLY):
        raise InputError(f"{t} is a task-level constraint and cannot be used inside a goal", file=fname,
                         path=path + ["type"])
    return out


def _parse_goal(g, fname, path, resolver, root) -> Goal:
    if not isinstance(g, dict):
        raise InputError("expected a goal object", file=fname, path=path)
    ci = _ci(g)
    gid = str(g.get("ID", ci.get("id", (None, None))[1]))
    if gid == "None":
        raise InputError("goal needs an 'ID'", file=fname, path=path)
    gt = goal_type(str(g.get("type", "")), file=fname, path=path + ["type"])
    cons = tuple(_parse_constraint(c, fname, path + ["constraints", k], resolver, False)
                 for k, c in enumerate(g.get("constraints", [])))
    return gt.parse(g, GoalContext(gid, cons, fname, list(path), resolver, root, g))


def _pose_goal(cls):
    def parse(g, ctx: GoalContext) -> Goal:
        k, v = ctx.key("goalPose")
        if v is None:
            raise ctx.fail(f"a {cls.type_name} goal needs 'goalPose'")
        return cls(ctx.id, ctx.constraints, _tolerated(v, ctx.file, ctx.path + [k], ctx.resolver))
    return parse


def _parse_return_to(g, ctx: GoalContext) -> Goal:
    k, v = ctx.key("returnToGoal")
    return ReturnTo(ctx.id, ctx.constraints, None if v is None else str(v))


def _parse_pause(g, ctx: GoalContext) -> Goal:
    k, v = ctx.key("duration")
    if v is None:
        raise ctx.fail("a pause goal needs 'duration'")
    d = check_finite(v, ctx.file, ctx.path + [k])
    if d < 0:
        raise ctx.fail(f"must be >= 0, got {d}", k)
    return Pause(ctx.id, ctx.constraints, d)


def _parse_follow(g, ctx: GoalContext) -> Goal:
    fname, path = ctx.file, ctx.path
    k, traj = ctx.key("trajectory")
    if not isinstance(traj, dict) or "pose" not in traj:
        raise ctx.fail("a follow goal needs 'trajectory': {pose: [...], t?: [...]}")
    poses = tuple(_tolerated(p, fname, path + [k, "pose", i], ctx.resolver) for i, p in enumerate(traj["pose"]))
    if not poses:
        raise ctx.fail("trajectory has no poses", k, "pose")
    tt = None
    if "t" in traj and traj["t"] is not None:
        tv = traj["t"]
        if isinstance(tv, (int, float)) and not isinstance(tv, bool):
            tt = np.arange(len(poses)) * check_finite(tv, fname, path + [k, "t"])
        else:
            tt = np.array([check_finite(x, fname, path + [k, "t", i]) for i, x in enumerate(tv)])
        if len(tt) != len(poses):
            raise ctx.fail(f"{len(tt)} times for {len(poses)} poses", k, "t")
        if np.any(np.diff(tt) <= 0):
            raise ctx.fail("times must be strictly increasing", k, "t")
    fr = ctx.key("forceTorqueReferenceFrame")[1]
    if fr not in (None, "world"):
        raise ctx.fail("only 'world' is supported", "forceTorqueReferenceFrame")
    force = _vec3(ctx.key("externalForce"), fname, path)
    torque = _vec3(ctx.key("externalTorque"), fname, path)
    return Follow(ctx.id, ctx.constraints, poses, tt, force, torque)


def _parse_leave(g, ctx: GoalContext) -> Goal:
    fname, path = ctx.file, ctx.path
    region: Optional[ToleratedPose] = None
    occupied: Tuple[GeometrySpec, ...] = ()
    ko, v = ctx.key("occupiedSpace")
    if v is not None:
        occupied = parse_geometries(v, ctx.root, fname, path + [ko], required_files=True)
    kr, v = ctx.key("region")
    if isinstance(v, dict) and "nominal" in v:
        region = _tolerated(v, fname, path + [kr], ctx.resolver)
    elif v is not None:
        occupied += parse_geometries(v, ctx.root, fname, path + [kr], required_files=True)
    if region is None and not occupied:
        raise ctx.fail("a leave goal needs 'occupiedSpace' (geometries the TCP must leave) or 'region' "
                       "(a tolerated pose)")
    kd, d = ctx.key("duration")
    dur = check_finite(d if d is not None else 0.0, fname, path + [kd])
    if dur < 0:
        raise ctx.fail(f"must be >= 0, got {dur}", kd)
    return Leave(ctx.id, ctx.constraints, region, dur, occupied)


for _cls, _parse in ((At, _pose_goal(At)), (Reach, _pose_goal(Reach)), (ReturnTo, _parse_return_to),
                     (Pause, _parse_pause), (Follow, _parse_follow), (Leave, _parse_leave)):
    register_goal_type(_cls, _parse, builtin=True)


def _vec3(kv, fname, path):
    k, v = kv
    if v is None:
        return np.zeros(3)
    if not isinstance(v, list) or len(v) != 3:
        raise InputError(f"expected 3 numbers, got {describe_value(v)}", file=fname, path=path + [k])
    return np.array([check_finite(x, fname, path + [k, i]) for i, x in enumerate(v)])
