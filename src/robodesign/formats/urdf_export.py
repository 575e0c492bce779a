"""URDF export of assembled robots (:func:`export_urdf`): one document written part by part (links, collision,
visual, joints, TCP); the conventions are in :mod:`robodesign.formats.urdf`."""
from __future__ import annotations

import math
import os
import re
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Callable, Dict, List, Optional, Tuple, Union

import numpy as np

from robodesign.core.errors import InputError
from robodesign.core.spatial import inv, matrix_to_rpy, pose_to_list
from robodesign.formats.geometry import GeometrySpec, load_mesh_arrays
from robodesign.formats.module_spec import Body

DBL_MAX = 1.7976931348623157e308
MESH_DIR_MODES = ("absolute", "copy")

#: placement of a pinocchio placement relative to its parent joint frame (the base pose removed on the root)
_Rel = Callable[..., np.ndarray]


def _num(x: float) -> str:
    """Shortest text that round-trips the double; ±inf → ±DBL_MAX (URDF parsers cannot read inf)."""
    x = float(x)
    if math.isnan(x):
        raise ValueError("NaN cannot be written to a URDF")
    if math.isinf(x):
        x = math.copysign(DBL_MAX, x)
    return repr(x + 0.0)  # + 0.0: no "-0.0"


def _vec(v) -> str:
    return " ".join(_num(x) for x in v)


def _origin(parent: ET.Element, T: np.ndarray) -> ET.Element:
    T = np.asarray(T, dtype=float)
    return ET.SubElement(parent, "origin", xyz=_vec(T[:3, 3]), rpy=_vec(matrix_to_rpy(T[:3, :3])))


_SAFE = re.compile(r"[^A-Za-z0-9_.\-]+")


def _safe_name(s: str) -> str:
    return _SAFE.sub("_", s).strip("._") or "mesh"


class _MeshWriter:
    """Mesh files of one export: generated STLs and (copy mode) copied originals, de-duplicated."""

    def __init__(self, urdf_path: Path, mode: str):
        self.urdf_dir = urdf_path.parent
        self.mesh_dir = urdf_path.parent / f"{urdf_path.stem}_meshes"
        self.mode = mode
        self._done: Dict[object, str] = {}
        self._names: set = set()

    def _unique(self, name: str) -> Path:
        stem, suffix = os.path.splitext(_safe_name(name))
        cand, k = stem + suffix, 1
        while cand in self._names:
            cand = f"{stem}_{k}{suffix}"
            k += 1
        self._names.add(cand)
        return self.mesh_dir / cand

    def _ref(self, p: Path) -> str:
        if self.mode == "absolute":
            return str(p.resolve())
        return Path(os.path.relpath(p, self.urdf_dir)).as_posix()

    def original(self, file: Path) -> str:
        """Reference to an existing mesh file (copied next to the URDF in copy mode)."""
        file = Path(file).resolve()
        if self.mode == "absolute":
            return str(file)
        key = ("copy", str(file))
        if key not in self._done:
            self.mesh_dir.mkdir(parents=True, exist_ok=True)
            dst = self._unique(file.name)
            shutil.copyfile(file, dst)
            self._done[key] = self._ref(dst)
        return self._done[key]

    def generated(self, key, name: str, vertices: np.ndarray, faces: np.ndarray) -> str:
        """Write a triangle mesh as binary STL (once per key) and return its reference."""
        if key not in self._done:
            import trimesh
            self.mesh_dir.mkdir(parents=True, exist_ok=True)
            dst = self._unique(name + ".stl")
            trimesh.Trimesh(np.asarray(vertices, float), np.asarray(faces, np.int64), process=False).export(str(dst))
            self._done[key] = self._ref(dst)
        return self._done[key]


def _convex_triangles(shape) -> Tuple[np.ndarray, np.ndarray]:
    pts = np.asarray(shape.points(), dtype=float)
    try:
        faces = np.array([[shape.polygons(i)[k] for k in range(3)] for i in range(shape.num_polygons)],
                         dtype=np.int64).reshape(-1, 3)
    except Exception:  # pragma: no cover - coal without polygon access
        faces = np.zeros((0, 3), dtype=np.int64)
    if len(faces) == 0:
        import trimesh
        hull = trimesh.convex.convex_hull(pts)
        return np.asarray(hull.vertices, float), np.asarray(hull.faces, np.int64)
    return pts, faces


def _bvh_triangles(shape) -> Tuple[np.ndarray, np.ndarray]:
    pts = np.asarray(shape.vertices(), dtype=float).reshape(-1, 3)
    faces = np.array([[shape.tri_indices(i)[k] for k in range(3)] for i in range(shape.num_tris)], dtype=np.int64)
    return pts, faces


def _geometry_element(parent: ET.Element, tag: str, name: str, pose: np.ndarray, spec: Optional[GeometrySpec],
                      shape, meshes: _MeshWriter, key_base) -> None:
    """One <collision>/<visual>. ``shape`` is the coal object (collision) or None (visual, from spec)."""
    import coal
    el = ET.Element(tag, name=name)
    _origin(el, pose)
    geo = ET.SubElement(el, "geometry")
    if shape is not None:
        if isinstance(shape, coal.Box):
            ET.SubElement(geo, "box", size=_vec(2.0 * np.asarray(shape.halfSide)))
        elif isinstance(shape, coal.Cylinder):
            ET.SubElement(geo, "cylinder", radius=_num(shape.radius), length=_num(2.0 * shape.halfLength))
        elif isinstance(shape, coal.Sphere):
            ET.SubElement(geo, "sphere", radius=_num(shape.radius))
        elif (isinstance(shape, coal.BVHModelBase) and spec is not None and spec.kind == "mesh"
              and spec.file is not None and spec.file.suffix.lower() != ".wrl"):
            ET.SubElement(geo, "mesh", filename=meshes.original(spec.file), scale=_vec(spec.scale))
        elif isinstance(shape, coal.BVHModelBase):
            v, f = _bvh_triangles(shape)
            ET.SubElement(geo, "mesh", filename=meshes.generated(key_base, name, v, f), scale="1.0 1.0 1.0")
        elif isinstance(shape, coal.ConvexBase):
            v, f = _convex_triangles(shape)
            ET.SubElement(geo, "mesh", filename=meshes.generated(key_base, name, v, f), scale="1.0 1.0 1.0")
        else:
            raise InputError(f"collision object {name!r}: cannot write a {type(shape).__name__} to URDF")
    else:
        assert spec is not None  # a visual is written from its spec (only collisions pass their coal shape)
        if spec.kind == "box":
            ET.SubElement(geo, "box", size=_vec(spec.size))
        elif spec.kind == "cylinder":
            ET.SubElement(geo, "cylinder", radius=_num(spec.size[0]), length=_num(spec.size[1]))
        elif spec.kind == "sphere":
            ET.SubElement(geo, "sphere", radius=_num(spec.size[0]))
        elif spec.kind == "mesh" and spec.file is not None and spec.file.suffix.lower() == ".wrl":
            parts = load_mesh_arrays(str(spec.file), tuple(spec.scale))
            verts, faces, off = [], [], 0
            for v, f in parts:
                verts.append(v)
                faces.append(f + off)
                off += len(v)
            if not verts or off == 0:
                return
            ref = meshes.generated(("visual", str(spec.file), tuple(spec.scale)), spec.file.name.split(".")[0] + "_visual",
                                   np.vstack(verts), np.vstack(faces))
            ET.SubElement(geo, "mesh", filename=ref, scale="1.0 1.0 1.0")
        elif spec.kind == "mesh" and spec.file is not None:
            ET.SubElement(geo, "mesh", filename=meshes.original(spec.file), scale=_vec(spec.scale))
        else:
            return
    parent.append(el)


def _inertial(link: ET.Element, Y) -> None:
    if Y.mass <= 0:
        return
    el = ET.SubElement(link, "inertial")
    ET.SubElement(el, "origin", xyz=_vec(np.asarray(Y.lever)), rpy="0.0 0.0 0.0")
    ET.SubElement(el, "mass", value=_num(Y.mass))
    I = np.asarray(Y.inertia)
    ET.SubElement(el, "inertia", ixx=_num(I[0, 0]), ixy=_num(I[0, 1]), ixz=_num(I[0, 2]),
                  iyy=_num(I[1, 1]), iyz=_num(I[1, 2]), izz=_num(I[2, 2]))



def export_urdf(robot, path: Union[str, Path], mesh_dir_mode: str = "absolute") -> Path:
    """Write ``robot`` (a :class:`robodesign.model.robot.Robot`) as a URDF file; returns the path written.

    The root link ``base`` is the robot's base frame (the base pose is only recorded in a comment);
    see the module docstring of :mod:`robodesign.formats.urdf` for every convention.
    """
    if mesh_dir_mode not in MESH_DIR_MODES:
        raise InputError(f"mesh_dir_mode must be one of {MESH_DIR_MODES}, got {mesh_dir_mode!r}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path = path.resolve()
    meshes = _MeshWriter(path, mesh_dir_mode)
    robot.add_frames()   # the body frames (the visuals are placed at them)
    rel = _relative_placer(robot)

    root = _robot_element(robot)
    link_names, links = _links(root, robot.model)
    _collisions(robot, links, rel, meshes)
    _visuals(robot, links, rel, meshes)
    _joints(root, robot, link_names, links, rel)
    _tcp(root, robot, link_names, rel)

    tree = ET.ElementTree(root)
    ET.indent(tree, space="  ")
    tmp = path.with_name(path.name + ".tmp")
    tree.write(str(tmp), encoding="utf-8", xml_declaration=True)
    os.replace(tmp, path)
    return path


def _relative_placer(robot) -> _Rel:
    """``rel(placement, parent_joint, item=None)``: the placement relative to the parent joint frame, with the base
    pose removed on the root (exactly, from the base-frame placements the Robot keeps to apply base poses)."""
    to_base = inv(np.asarray(robot.base_pose, dtype=float))
    root_items = {(kind, idx): M for kind, idx, M in getattr(robot, "_root_items", ())}

    def rel(placement, parent_joint: int, item=None) -> np.ndarray:
        """Placement relative to the parent joint frame, with the base pose removed on the root."""
        if parent_joint == 0 and item in root_items:
            return np.asarray(root_items[item], dtype=float)
        M = placement.homogeneous if hasattr(placement, "homogeneous") else np.asarray(placement)
        return to_base @ M if parent_joint == 0 else M
    return rel


def _robot_element(robot) -> ET.Element:
    """The <robot> root with the comments that record the module order, the base pose and the extensions."""
    model, asm = robot.model, robot.assembly
    root = ET.Element("robot", name=_safe_name(model.name.replace("robodesign:", "robodesign_")) or "robot")
    root.append(ET.Comment(
        " Written by robodesign.formats.urdf.export_urdf. Root link 'base' = the robot's base frame (base connector "
        "flipped about x). Module order: " + ",".join(asm.module_ids) + ". "))
    root.append(ET.Comment(" robodesign: base_pose = " + str(pose_to_list(robot.base_pose, 15)) + " "))
    root.append(ET.Comment(
        " Joints: <dynamics damping=viscous friction=Coulomb>; <drivetrain gear_ratio motor_inertia> is a "
        "robodesign extension (reflected inertia = gear_ratio^2 * motor_inertia, pinocchio 'armature'); "
        "infinite limits are written as +-1.7976931348623157e+308. "))
    return root


def _links(root: ET.Element, model) -> Tuple[List[str], List[ET.Element]]:
    """One link per pinocchio joint with its lumped inertia. → (link names, link elements) by joint index."""
    joint_names = set(model.names)
    link_names: List[str] = []
    used = set()
    for j in range(model.njoints):
        nm = "base" if j == 0 else f"{model.names[j]}_link"
        while nm in used or (j > 0 and nm in joint_names) or nm == "tcp":
            nm += "_"
        used.add(nm)
        link_names.append(nm)
    links = []
    for j in range(model.njoints):
        links.append(ET.SubElement(root, "link", name=link_names[j]))
        _inertial(links[j], model.inertias[j])
    return link_names, links


def _collisions(robot, links: List[ET.Element], rel: _Rel, meshes: _MeshWriter) -> None:
    """One <collision> per robot coal object (obstacles excluded), in the link of its joint."""
    gmodel, ms, asm = robot.geom_model, robot.module_set, robot.assembly
    labels = robot.instance_labels
    n_robot = robot.n_collision_geometries
    geom_body = robot._geom_body  # (instance, body id) of each robot collision object
    for k in range(n_robot):
        go = gmodel.geometryObjects[k]
        i, body_id = geom_body[k]
        prefix = f"{labels[i]}.{body_id}.c"
        spec, part = None, 0
        m = re.fullmatch(r"(\d+)(?:\.(\d+))?", go.name[len(prefix):]) if go.name.startswith(prefix) else None
        if m:
            body = ms[asm.module_ids[i]].body(body_id)
            gi = int(m.group(1))
            part = int(m.group(2) or 0)
            if gi < len(body.collision):
                spec = body.collision[gi]
        if spec is not None and spec.kind == "mesh" and spec.file is not None:
            # generated STL of a convex part / hull: shared by every copy of the same (file, scale, part)
            key: tuple = ("collision", str(spec.file), tuple(spec.scale), part, type(go.geometry).__name__)
        else:
            key = ("collision", go.name)
        _geometry_element(links[go.parentJoint], "collision", go.name, rel(go.placement, go.parentJoint, ("geom", k)), spec,
                          go.geometry, meshes, key)


def _visuals(robot, links: List[ET.Element], rel: _Rel, meshes: _MeshWriter) -> None:
    """The <visual>s of the body specs, at the body frames."""
    import pinocchio as pin
    model, ms, asm = robot.model, robot.module_set, robot.assembly
    labels = robot.instance_labels
    body_of_frame: Dict[str, Body] = {}
    for i, mid in enumerate(asm.module_ids):
        for b in ms[mid].bodies:
            body_of_frame[f"{labels[i]}.{b.id}"] = b
    for fi, f in enumerate(model.frames):
        if f.type != pin.FrameType.BODY or f.name not in body_of_frame:
            continue
        B = rel(f.placement, f.parentJoint, ("frame", fi))
        for vi, spec in enumerate(body_of_frame[f.name].visual):
            _geometry_element(links[f.parentJoint], "visual", f"{f.name}.v{vi}", B @ spec.pose, spec, None, meshes,
                              None)


def _joints(root: ET.Element, robot, link_names: List[str], links: List[ET.Element], rel: _Rel) -> None:
    """One revolute/prismatic <joint> per pinocchio joint, with limits, dynamics and drivetrain, placed just
    before its child link."""
    model = robot.model
    infos = robot.joint_infos
    for j in range(1, model.njoints):
        info = infos[j - 1]
        if info.name != model.names[j]:  # pragma: no cover - guards the Robot's bookkeeping
            raise RuntimeError(f"joint bookkeeping mismatch: {info.name} vs {model.names[j]}")
        k = j - 1
        jt = "revolute" if info.type == "revolute" else "prismatic"
        el = ET.SubElement(root, "joint", name=model.names[j], type=jt)
        _origin(el, rel(model.jointPlacements[j], model.parents[j], ("joint", j)))
        ET.SubElement(el, "parent", link=link_names[model.parents[j]])
        ET.SubElement(el, "child", link=link_names[j])
        ET.SubElement(el, "axis", xyz="0 0 -1" if info.reversed else "0 0 1")
        lim = dict(lower=_num(robot.q_lower[k]), upper=_num(robot.q_upper[k]), effort=_num(robot.tau_max[k]),
                   velocity=_num(robot.dq_max[k]))
        if math.isfinite(robot.ddq_max[k]):
            lim["acceleration"] = _num(robot.ddq_max[k])
        ET.SubElement(el, "limit", lim)
        ET.SubElement(el, "dynamics", damping=_num(robot.friction_viscous[k]),
                      friction=_num(robot.friction_coulomb[k]))
        ET.SubElement(el, "drivetrain", gear_ratio=_num(robot.gear_ratio[k]),
                      motor_inertia=_num(robot.motor_inertia[k]))
        # keep each joint next to its child link for readability: move the element after the link
        root.remove(el)
        root.insert(list(root).index(links[j]), el)


def _tcp(root: ET.Element, robot, link_names: List[str], rel: _Rel) -> None:
    """The TCP: a massless link ``tcp`` on the fixed joint ``tcp_joint``."""
    tf = robot.model.frames[robot.tcp_frame]
    ET.SubElement(root, "link", name="tcp")
    el = ET.SubElement(root, "joint", name="tcp_joint", type="fixed")
    _origin(el, rel(tf.placement, tf.parentJoint, ("frame", robot.tcp_frame)))
    ET.SubElement(el, "parent", link=link_names[tf.parentJoint])
    ET.SubElement(el, "child", link="tcp")
