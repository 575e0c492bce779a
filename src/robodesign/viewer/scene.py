"""The viewer's scene: plain, JSON-serialisable data describing what the page draws.

:func:`build_scene` turns a task (workcell + goals), a robot and a trajectory into a dict::

    {"format": "robodesign-scene/1",
     "info":      {...},                      # what the page lists next to the 3-D view
     "meshes":    {mesh_id: mesh record},     # once per (file, scale), see viewer.meshes
     "nodes":     [node, ...],                # rigid groups of geometry with a world pose
     "animation": None | {...},               # per frame the world pose of each animated node
     "paths":     {"tcp": [[x, y, z], ...]},  # TCP position at every trajectory sample (≤ 5000 points)
     "goals":     [goal record, ...],
     "bounds":    {"min": [x, y, z], "max": [x, y, z]},   # what the camera frames first
     "messages":  [str, ...]}

A *node* is ``{"id", "name", "group", "pose" (4×4 world, row-major nested lists), "geometries":
[...]}`` plus ``"frame"`` (the robot frame it follows) for robot nodes. Groups: ``robot`` (one node per
body, named ``<instance label>.<body id>`` like the robot's frames), ``tcp``, ``base``, ``obstacle``,
``goal``, ``placement`` (the task's base-placement tolerance). A geometry is ``{"type": box | cylinder |
sphere | mesh | triad | line, "pose": 4×4 relative to the node, "role": visual | collision | tolerance |
marker, "color", "opacity"}`` with ``size`` [x, y, z] (box, full lengths), ``radius`` / ``length``
(cylinder along its local z, centred), ``radius`` (sphere), ``mesh`` (an id of ``meshes``), ``size``
(triad axis length) or ``points`` (line, node coordinates). ``wireframe: true`` marks a tolerance
shape cut to the display size because an interval is unbounded.

Animation: ``{"fps", "t": [...], "sample": [...], "nodes": [node ids], "poses": F×N×3×4 nested lists,
"goal_frames": {goal id: frame}}``. ``sample[j]`` is the trajectory sample shown at frame j, or −1 for
a frame interpolated at a goal instant that lies between samples (q linear in t, as the checker does).
Frame selection (:func:`animation_samples`): the first sample, then every sample at least 1/fps after
the previously selected one, the last sample, and every goal instant (``goal2time``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable, Dict, Iterable, List, Optional, Sequence, Tuple

import numpy as np
import numpy.typing as npt

from robodesign.formats.geometry import GeometrySpec
from robodesign.formats.task_spec import At, Follow, Leave, ObstacleSpec, Pause, Reach, ReturnTo
from robodesign.viewer.meshes import MAX_TRIANGLES, mesh_entry
from robodesign.viewer.tolerances import TOLERANCE_CLIP as TOLERANCE_CLIP
from robodesign.viewer.tolerances import TOLERANCE_OPACITY as TOLERANCE_OPACITY
from robodesign.viewer.tolerances import _pose, tolerance_geometries, tolerance_text

if TYPE_CHECKING:  # (the viewer loads them only when it draws a robot)
    from robodesign.core.trajectory import Trajectory
    from robodesign.model.robot import Robot

    OtherRobot = Tuple[str, Robot, Optional[Trajectory]]  # a further robot of a cell: ID, robot, motion

SCENE_FORMAT = "robodesign-scene/1"
DEFAULT_FPS = 25.0
TIME_EPS = 1e-9
MAX_PATH_POINTS = 5000

COLORS = {
    "base": "#4a4f57", "joint": "#2f6db5", "link": "#b9bdc4", "eef": "#e08a1e",
    "obstacle": "#8d99ae", "collision": "#e4572e", "goal": "#2ca02c", "leave": "#d62728",
    "placement": "#9467bd", "path": "#ff7f0e", "follow": "#17becf", "returnTo": "#7f7f7f",
}
OBSTACLE_OPACITY = 0.25
GOAL_TRIAD = 0.08
BASE_TRIAD = 0.15
TCP_TRIAD = 0.06


# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------
class _MeshTable:
    def __init__(self, max_triangles: int):
        self.max_triangles = max_triangles
        self.ids: Dict[Tuple[str, Tuple[float, ...]], str] = {}
        self.meshes: Dict[str, dict] = {}

    def add(self, spec: GeometrySpec) -> str:
        key = (str(spec.file), tuple(float(s) for s in spec.scale))
        mid = self.ids.get(key)
        if mid is None:
            mid = f"mesh{len(self.ids)}"
            self.ids[key] = mid
            self.meshes[mid] = dict(mesh_entry(key[0], key[1], self.max_triangles))
        return mid


def geometry_record(spec: GeometrySpec, meshes: _MeshTable, role: str = "visual", color: str = "#b9bdc4",
                    opacity: float = 1.0, pose: Optional[np.ndarray] = None) -> Optional[dict]:
    """One geometry of a node; ``pose`` overrides the spec's pose (relative to the node)."""
    rec = {"type": spec.kind, "pose": _pose(spec.pose if pose is None else pose), "role": role, "color": color,
           "opacity": float(opacity)}
    if spec.kind == "box":
        rec["size"] = [float(s) for s in spec.size]
    elif spec.kind == "cylinder":
        rec["radius"], rec["length"] = float(spec.size[0]), float(spec.size[1])
    elif spec.kind == "sphere":
        rec["radius"] = float(spec.size[0])
    elif spec.kind == "mesh":
        rec["mesh"] = meshes.add(spec)
    else:
        return None
    return rec


def _triad(size: float, pose=None) -> dict:
    return {"type": "triad", "size": float(size), "pose": _pose(np.eye(4) if pose is None else pose),
            "role": "marker", "color": "#000000", "opacity": 1.0}


# ---------------------------------------------------------------------------------------------
# animation frames
# ---------------------------------------------------------------------------------------------
def animation_samples(t: npt.ArrayLike, goal_times: Iterable[float] = (), fps: float = DEFAULT_FPS
                      ) -> List[Tuple[float, int]]:
    """The frames of the animation as ``(time, sample index or -1)``, sorted by time.

    The first sample, then greedily every sample at least ``1/fps`` after the previously selected one,
    the last sample, and every goal instant: the sample at that time if there is one (checker rule:
    ``numpy.isclose(t, t_g, rtol=1e-5, atol=1e-8)``), else an interpolated frame (index −1).
    """
    t = np.asarray(t, dtype=float)
    n = len(t)
    if n == 0:
        return []
    step = 1.0 / float(fps)
    chosen = {0}
    last = t[0]
    for k in range(1, n):
        if t[k] - last >= step - TIME_EPS:
            chosen.add(k)
            last = t[k]
    chosen.add(n - 1)
    frames = {(float(t[k]), int(k)) for k in chosen}
    for tg in goal_times:
        tg = float(tg)
        close = np.nonzero(np.isclose(t, tg, rtol=1e-5, atol=1e-8))[0]
        if len(close):
            k = int(close[np.argmin(np.abs(t[close] - tg))])
            frames.add((float(t[k]), k))
        elif t[0] <= tg <= t[-1]:
            frames.add((tg, -1))
    return sorted(frames, key=lambda f: (f[0], f[1]))


def _q_at(t: np.ndarray, q: np.ndarray, time_: float) -> np.ndarray:
    return np.array([np.interp(time_, t, q[:, j]) for j in range(q.shape[1])])


# ---------------------------------------------------------------------------------------------
# the scene
# ---------------------------------------------------------------------------------------------
def _add_robot_nodes(robot, prefix: str, include_collision: bool, meshes: "_MeshTable", nodes: List[dict]
                     ) -> List[Tuple[str, int]]:
    """Append the nodes of ``robot`` (one per body, the TCP triad, the base triad) to ``nodes``, their ids
    prefixed by ``prefix`` (``""`` for the only robot, ``"<robot ID>/"`` in a collaborative cell); returns
    [(node id, frame id)] of the nodes that move with the joints."""
    ms, asm = robot.module_set, robot.assembly
    robot_nodes: List[Tuple[str, int]] = []
    for i, mid in enumerate(asm.module_ids):
        mod = ms[mid]
        label = robot.instance_labels[i]
        color = COLORS.get(mod.kind, COLORS["link"])
        for body in mod.bodies:
            frame = f"{label}.{body.id}"
            geoms = []
            visuals = body.visual
            from_collision = False
            if not visuals:
                visuals, from_collision = body.collision, True
            for g in visuals:
                rec = geometry_record(g, meshes, "visual", color)
                if rec is not None:
                    if from_collision:
                        rec["from_collision"] = True
                    geoms.append(rec)
            if include_collision:
                for g in body.collision:
                    rec = geometry_record(g, meshes, "collision", COLORS["collision"], 0.5)
                    if rec is not None:
                        geoms.append(rec)
            nid = f"{prefix}robot/{frame}"
            nodes.append({"id": nid, "name": prefix + frame, "group": "robot", "frame": frame, "module": str(mid),
                          "module_name": mod.name, "instance": i, "kind": mod.kind, "geometries": geoms})
            robot_nodes.append((nid, robot.frame_id(frame)))
    nodes.append({"id": f"{prefix}robot/TCP", "name": prefix + "TCP", "group": "tcp", "frame": "TCP",
                  "geometries": [_triad(TCP_TRIAD)]})
    robot_nodes.append((f"{prefix}robot/TCP", robot.tcp_frame))
    nodes.append({"id": f"{prefix}base", "name": prefix + "base pose", "group": "base", "pose": _pose(robot.base_pose),
                  "geometries": [_triad(BASE_TRIAD)]})
    return robot_nodes


def _frame_poses(robot, q_frames, robot_nodes) -> List[List[np.ndarray]]:
    """Per animation frame, the world pose of every node of ``robot_nodes``."""
    out = []
    for qf in q_frames:
        robot.fk(qf)  # updates robot.data.oMf
        oMf = robot.data.oMf
        out.append([oMf[fid].homogeneous.copy() for _, fid in robot_nodes])
    return out


def build_scene(task=None, robot=None, trajectory=None, *, q: Optional[npt.ArrayLike] = None,
                fps: float = DEFAULT_FPS, include_collision: bool = False, max_triangles: int = MAX_TRIANGLES,
                info: Optional[dict] = None, others: Sequence[OtherRobot] = ()) -> dict:
    """Scene data for :func:`robodesign.viewer.html.render_html` (see the module docstring).

    ``task``: a :class:`~robodesign.formats.task_spec.Task` (obstacles, goals, base placement) or None.
    ``robot``: a :class:`~robodesign.model.robot.Robot` (at its ``base_pose``) or None.
    ``trajectory``: a :class:`~robodesign.core.trajectory.Trajectory` for ``robot``, or None for a static robot
    at ``q`` (default zeros). ``include_collision`` adds the collision geometry (hidden by default on
    the page). Meshes with more than ``max_triangles`` triangles are decimated. ``others``: further robots
    of a collaborative cell as ``(robot ID, Robot, trajectory on the same time base)``; they animate with
    the first robot and the moving obstacles.
    """
    meshes = _MeshTable(max_triangles)
    nodes: List[dict] = []
    messages: List[str] = []
    info = dict(info or {})
    focus: List[np.ndarray] = []
    goal_records: List[dict] = []
    anim = None
    paths: Dict[str, list] = {}

    frames_t: List[Tuple[float, int]] = []
    robot_nodes: List[Tuple[str, int]] = []  # (node id, frame id)
    poses: List[List[np.ndarray]] = []  # per frame, per robot node: 4x4
    if robot is not None:
        frames_t, robot_nodes, poses = _robot_part(robot, trajectory, q, fps, include_collision, others, meshes,
                                                   nodes, info, focus, paths)
    obstacle_anim: List[Tuple[str, ObstacleSpec]] = []
    if task is not None:
        goal_records, obstacle_anim = _task_part(task, robot, trajectory, frames_t, include_collision, meshes, nodes,
                                                 info, focus, paths)
    if robot is not None and trajectory is not None:
        anim = _animation(trajectory, fps, frames_t, robot_nodes, poses, obstacle_anim)
    bounds = _bounds(focus, nodes, meshes, robot)
    return {"format": SCENE_FORMAT, "info": info, "meshes": meshes.meshes, "nodes": nodes, "animation": anim,
            "paths": paths, "goals": goal_records, "bounds": bounds, "messages": messages}


def _robot_part(robot, trajectory, q, fps: float, include_collision: bool, others: Sequence[OtherRobot],
                meshes: "_MeshTable", nodes: List[dict], info: dict, focus: List[np.ndarray], paths: Dict[str, list]
                ) -> Tuple[List[Tuple[float, int]], List[Tuple[str, int]], List[List[np.ndarray]]]:
    """The robot's nodes (and the other robots' of a collaborative cell), its frames and TCP path. → (frame times
    with their sample index, (node id, frame id) of every robot node, per frame the 4x4 pose of every robot node)."""
    ms, asm = robot.module_set, robot.assembly
    info.setdefault("module_set", ms.name)
    info.setdefault("modules", list(asm.module_ids))
    info.setdefault("dof", int(robot.dof))
    info.setdefault("base_pose", _pose(robot.base_pose))
    robot_nodes = _add_robot_nodes(robot, "", include_collision, meshes, nodes)
    focus.append(robot.base_pose[:3, 3])

    frames_t: List[Tuple[float, int]] = []
    if trajectory is not None:
        t = np.asarray(trajectory.t, dtype=float)
        Q = np.asarray(trajectory.q, dtype=float)
        if Q.ndim != 2 or Q.shape[1] != robot.dof:
            raise ValueError(f"trajectory has {Q.shape[-1]} joint columns, the robot {robot.dof} joints")
        g2t = dict(trajectory.goal2time or {})
        frames_t = animation_samples(t, g2t.values(), fps)
        q_frames = [Q[k] if k >= 0 else _q_at(t, Q, tt) for tt, k in frames_t]
        info.setdefault("duration", float(t[-1] - t[0]))
        info.setdefault("samples", int(len(t)))
        # TCP path at the samples (strided to ≤ MAX_PATH_POINTS)
        stride = max(1, int(math.ceil(len(t) / MAX_PATH_POINTS)))
        ks = list(range(0, len(t), stride))
        if ks[-1] != len(t) - 1:
            ks.append(len(t) - 1)
        paths["tcp"] = [robot.fk(Q[k])[:3, 3].tolist() for k in ks]
    else:
        q0 = np.zeros(robot.dof) if q is None else np.asarray(q, dtype=float)
        q_frames = [q0]
        info.setdefault("q", q0.tolist())

    poses = _frame_poses(robot, q_frames, robot_nodes)  # per frame, per robot node: 4x4
    for name, other, tr in others:  # further robots of a collaborative cell, on the same time base
        o_nodes = _add_robot_nodes(other, f"{name}/", include_collision, meshes, nodes)
        focus.append(other.base_pose[:3, 3])
        if tr is not None and frames_t:
            to, Qo = np.asarray(tr.t, dtype=float), np.asarray(tr.q, dtype=float)
            if Qo.ndim != 2 or Qo.shape[1] != other.dof:
                raise ValueError(f"robot {name}: trajectory has {Qo.shape[-1]} joint columns, the robot {other.dof}")
            qo = [_q_at(to, Qo, tt) for tt, _ in frames_t]
        else:
            qo = [np.zeros(other.dof)] * len(q_frames)
        o_poses = _frame_poses(other, qo, o_nodes)
        poses = [a + b for a, b in zip(poses, o_poses)]
        robot_nodes = robot_nodes + o_nodes
    for j, (nid, _) in enumerate(robot_nodes):
        node = next(n for n in nodes if n["id"] == nid)
        node["pose"] = _pose(poses[0][j])
    for frame_poses in poses:
        for P in frame_poses:
            focus.append(P[:3, 3])
    return frames_t, robot_nodes, poses


def _task_part(task, robot, trajectory, frames_t: List[Tuple[float, int]], include_collision: bool,
               meshes: "_MeshTable", nodes: List[dict], info: dict, focus: List[np.ndarray], paths: Dict[str, list]
               ) -> Tuple[List[dict], List[Tuple[str, ObstacleSpec]]]:
    """The task's obstacles, goals and base placement. → (the goal records, (node id, obstacle) of the moving
    obstacles)."""
    info.setdefault("task", task.id)
    if task.header.name:
        info.setdefault("task_name", task.header.name)
    t0 = frames_t[0][0] if frames_t else 0.0
    obstacle_anim: List[Tuple[str, ObstacleSpec]] = []
    for ob in task.obstacles:
        geoms = _obstacle_geometries(ob, meshes, include_collision)
        nid = f"obstacle/{ob.id}"
        nodes.append({"id": nid, "name": ob.name or ob.id, "group": "obstacle", "moving": bool(ob.moving),
                      "pose": _pose(ob.transform_at(t0)), "geometries": geoms})
        if ob.moving:
            obstacle_anim.append((nid, ob))
    g2t = dict(trajectory.goal2time) if (trajectory is not None and robot is not None) else {}
    times = [f[0] for f in frames_t]
    goal_records = [_goal(g, g2t, times, nodes, focus, paths, meshes) for g in task.goals]
    _merge_labels([n for n in nodes if n["group"] == "goal"])
    bp = task.base_placement
    if bp is not None and not bp.is_unconstrained:
        geoms = [_triad(BASE_TRIAD * 0.6)] + tolerance_geometries(bp, COLORS["placement"])
        nodes.append({"id": "placement", "name": "base placement", "group": "placement",
                      "pose": _pose(bp.nominal), "geometries": geoms})
        focus.append(bp.nominal[:3, 3])
    info.setdefault("base_placement", tolerance_text(bp) if bp is not None else ["any pose"])
    return goal_records, obstacle_anim


def _obstacle_geometries(ob: ObstacleSpec, meshes: "_MeshTable", include_collision: bool) -> List[dict]:
    """An obstacle's visual geometry (its collision geometry when it has none), and its collision geometry too
    when asked."""
    geoms = []
    vis = ob.visual or ob.collision
    for g in vis:
        rec = geometry_record(g, meshes, "visual", COLORS["obstacle"], OBSTACLE_OPACITY)
        if rec is not None:
            if not ob.visual:
                rec["from_collision"] = True
            geoms.append(rec)
    if include_collision and ob.visual:
        for g in ob.collision:
            rec = geometry_record(g, meshes, "collision", COLORS["collision"], 0.3)
            if rec is not None:
                geoms.append(rec)
    return geoms


def _animation(trajectory, fps: float, frames_t: List[Tuple[float, int]], robot_nodes: List[Tuple[str, int]],
               poses: List[List[np.ndarray]], obstacle_anim: List[Tuple[str, ObstacleSpec]]) -> dict:
    """The animation: per frame the poses of the robot nodes and the moving obstacles, and each goal's frame."""
    anim_ids = [nid for nid, _ in robot_nodes] + [nid for nid, _ in obstacle_anim]
    all_poses = []
    for j, (tt, _) in enumerate(frames_t):
        row = [P[:3, :].tolist() for P in poses[j]]
        row += [np.asarray(ob.transform_at(tt), float)[:3, :].tolist() for _, ob in obstacle_anim]
        all_poses.append(row)
    times = [f[0] for f in frames_t]
    goal_frames = {}
    for gid, tg in (trajectory.goal2time or {}).items():
        goal_frames[str(gid)] = int(np.argmin(np.abs(np.asarray(times) - float(tg))))
    return {"fps": float(fps), "t": times, "sample": [int(k) for _, k in frames_t], "nodes": anim_ids,
            "poses": all_poses, "goal_frames": goal_frames}


def _bounds(focus: List[np.ndarray], nodes: List[dict], meshes: "_MeshTable", robot) -> dict:
    """The box the camera frames: the focus points padded (the obstacles' corners when there are none)."""
    if not focus:
        for n in nodes:
            if n["group"] != "obstacle":
                continue
            T = np.asarray(n["pose"])
            for g in n["geometries"]:
                for c in _geometry_corners(g, meshes.meshes):
                    focus.append((T @ np.asarray(g["pose"]) @ np.append(c, 1.0))[:3])
    if focus:
        pts = np.asarray(focus, dtype=float)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        pad = max(0.1, 0.1 * float(np.linalg.norm(hi - lo)))
        if robot is None:  # goals only: leave room for the robot that will reach them
            pad = max(0.4, 0.25 * float(np.linalg.norm(hi - lo)))
        return {"min": (lo - pad).tolist(), "max": (hi + pad).tolist()}
    return {"min": [-1.0, -1.0, -0.1], "max": [1.0, 1.0, 1.5]}


def _merge_labels(goal_nodes: List[dict]) -> None:
    """Goals at the same place share one label ("1, 3") instead of drawing labels on top of each other."""
    seen: List[Tuple[np.ndarray, dict]] = []
    for n in goal_nodes:
        at = np.asarray(n.get("label_at") or np.asarray(n["pose"])[:3, 3], dtype=float)
        for p, first in seen:
            if np.linalg.norm(p - at) < 1e-6:
                first["label"] += ", " + n["label"]
                n.pop("label", None)
                break
        else:
            seen.append((at, n))


def _geometry_corners(g: dict, meshes: dict) -> List[np.ndarray]:
    if g["type"] == "mesh":
        lo, hi = (np.asarray(x) for x in meshes[g["mesh"]]["bbox"])
    elif g["type"] == "box":
        hi = np.asarray(g["size"]) / 2
        lo = -hi
    elif g["type"] in ("sphere", "cylinder"):
        r = g["radius"]
        h = g.get("length", 2 * r) / 2
        lo, hi = np.array([-r, -r, -h]), np.array([r, r, h])
    else:
        return []
    return [np.array([a[0], b[1], c[2]]) for a in (lo, hi) for b in (lo, hi) for c in (lo, hi)]


@dataclass
class GoalView:
    """What a goal's view function adds to: the scene's nodes, the points the camera frames, the TCP path
    (``paths["tcp"]``), the mesh table, and ``rec``, the goal's record in the side panel (``tolerance``,
    ``position``, ``details``)."""
    rec: dict
    nodes: List[dict]
    focus: List[np.ndarray]
    paths: Dict[str, list]
    meshes: "_MeshTable"

    def node(self, g, geometries: list, pose: np.ndarray, kind: Optional[str] = None, **extra) -> None:
        self.nodes.append({"id": f"goal/{g.id}", "name": f"goal {g.id} ({kind or g.type})", "group": "goal",
                           "label": f"{g.id}", **extra, "pose": _pose(pose), "geometries": geometries})


#: goal class → its view function (looked up along the class's MRO: a subclass is shown as its base)
GOAL_VIEWS: Dict[type, Callable[[object, GoalView], None]] = {}


def register_goal_view(cls: type, view: Callable[[object, GoalView], None]) -> None:
    """Show goals of class ``cls`` (and its subclasses without a view of their own) with ``view``."""
    GOAL_VIEWS[cls] = view


def _goal(g, g2t: Dict[str, float], times: List[float], nodes: List[dict], focus: List[np.ndarray],
          paths: Dict[str, list], meshes: "_MeshTable") -> dict:
    tg = g2t.get(g.id)
    rec = {"id": g.id, "type": g.type, "time": None if tg is None else float(tg), "frame": None,
           "tolerance": [], "position": None, "details": ""}
    if tg is not None and times:
        rec["frame"] = int(np.argmin(np.abs(np.asarray(times) - float(tg))))
    view = next((GOAL_VIEWS[c] for c in type(g).__mro__ if c in GOAL_VIEWS), None)
    if view is not None:
        view(g, GoalView(rec, nodes, focus, paths, meshes))
    return rec


def _view_pose_goal(g, v: GoalView) -> None:
    tp = g.target_poses[0] if g.target_poses else None
    if tp is None:
        return
    v.node(g, [_triad(GOAL_TRIAD)] + tolerance_geometries(tp, COLORS["goal"]), tp.nominal)
    v.rec["tolerance"] = tolerance_text(tp)
    v.rec["position"] = tp.nominal[:3, 3].tolist()
    v.focus.append(tp.nominal[:3, 3])
    if getattr(g, "velocity_tolerance", None) is not None:
        v.rec["details"] = f"TCP twist ≤ {g.velocity_tolerance:g}"


def _view_leave(g, v: GoalView) -> None:
    tp = g.region
    at = tp.nominal if tp is not None else np.eye(4)   # node pose; the space's geometries are world poses
    geoms = [_triad(GOAL_TRIAD)] + tolerance_geometries(tp, COLORS["leave"]) if tp is not None else []
    for spec in g.occupied_space:
        r = geometry_record(spec, v.meshes, "tolerance", COLORS["leave"], 0.2, pose=np.linalg.inv(at) @ spec.pose)
        if r is not None:
            geoms.append(r)
    v.node(g, geoms, at, kind="leave")
    v.rec["tolerance"] = tolerance_text(tp) if tp is not None else []
    v.rec["position"] = g.center.tolist()
    v.rec["details"] = f"stay outside for {g.duration:g} s" + (
        f" ({len(g.occupied_space)} geometr{'y' if len(g.occupied_space) == 1 else 'ies'} to leave)"
        if g.occupied_space else "")
    v.focus.append(g.center)


def _view_follow(g, v: GoalView) -> None:
    if not g.poses:
        return
    pts = [p.nominal[:3, 3].tolist() for p in g.poses]
    geoms = [{"type": "line", "points": pts, "pose": _pose(np.eye(4)), "role": "marker",
              "color": COLORS["follow"], "opacity": 1.0}]
    step = max(1, int(math.ceil(len(g.poses) / 20)))
    shown = list(range(0, len(g.poses), step))
    if shown[-1] != len(g.poses) - 1:
        shown.append(len(g.poses) - 1)
    for i in shown:
        tp = g.poses[i]
        geoms.append(_triad(GOAL_TRIAD * 0.6, tp.nominal))
        for tg_ in tolerance_geometries(tp, COLORS["follow"], opacity=0.12):
            tg_["pose"] = _pose(tp.nominal @ np.asarray(tg_["pose"]))
            geoms.append(tg_)
    v.node(g, geoms, np.eye(4), kind="follow", label_at=pts[0])
    rec = v.rec
    rec["tolerance"] = tolerance_text(g.poses[0]) + ([f"… {len(g.poses)} poses"] if len(g.poses) > 1 else [])
    rec["position"] = pts[0]
    rec["details"] = f"{len(g.poses)} poses" + (", timed" if g.t is not None else "")
    if np.any(g.external_force) or np.any(g.external_torque):
        rec["details"] += f", wrench f={np.round(g.external_force, 3).tolist()} τ={np.round(g.external_torque, 3).tolist()}"
    v.focus.extend(np.asarray(pts))


def _view_return_to(g, v: GoalView) -> None:
    if g.return_to:
        v.rec["details"] = f"return to the configuration of goal {g.return_to}"
    else:
        v.rec["details"] = "return to the start configuration"
        if v.paths.get("tcp"):
            v.rec["position"] = v.paths["tcp"][0]


def _view_pause(g, v: GoalView) -> None:
    v.rec["details"] = f"pause {g.duration:g} s"


for _cls, _view in ((At, _view_pose_goal), (Reach, _view_pose_goal), (Leave, _view_leave), (Follow, _view_follow),
                    (ReturnTo, _view_return_to), (Pause, _view_pause)):
    register_goal_view(_cls, _view)
