"""URDF export of assembled robots and URDF import of monolithic robots as a one-module set.

Export (:func:`export_urdf`)
----------------------------
* The URDF root link is ``base``: the robot's **base frame** (base connector flipped about x). The file
  is independent of where the robot stands; the current ``Robot.base_pose`` is recorded in a comment
  (``robodesign: base_pose = [...]``) and is applied by whoever places the URDF in a scene.
* One URDF link per pinocchio joint, whose frame is the joint frame; it is named ``<joint name>_link``.
  Its ``<inertial>`` is the lumped inertia of everything rigidly attached to that joint
  (``model.inertias[j]``): mass, CoM as the inertial origin (``rpy="0 0 0"``) and the inertia about the
  CoM in joint axes. The root link ``base`` carries ``model.inertias[0]`` (bodies fixed to the base).
* Every pinocchio joint becomes a ``revolute``/``prismatic`` joint (never ``continuous``: that would
  make pinocchio use a 2-coordinate joint). The origin is the joint placement relative to the parent
  joint frame; the axis is ``0 0 1`` or ``0 0 -1`` for a module mounted backwards.
* ``<limit lower upper effort velocity [acceleration]>``; URDF parsers cannot read ``inf``, so an
  infinite limit is written as ±1.7976931348623157e+308 (the largest double) and read back as ±inf.
* ``<dynamics damping="f_v" friction="f_c"/>`` (viscous and Coulomb friction: pinocchio reads them
  into ``model.damping``/``model.friction``). Gear ratio and motor inertia have no URDF equivalent:
  they are written as ``<drivetrain gear_ratio=".." motor_inertia=".."/>`` inside the ``<joint>``
  (URDF parsers ignore unknown tags; :func:`import_urdf` reads it back).
* Collision geometry: boxes, cylinders and spheres as URDF primitives; triangle meshes reference the
  original file with its ``scale``; convex pieces (the ``.wrl`` convex decompositions IMPROV ships,
  or ``convex_meshes=True`` hulls) are written as binary STL files into ``<urdf stem>_meshes/`` next
  to the URDF, because URDF loaders cannot read VRML — one ``<collision>`` per coal object, so the
  URDF has exactly as many collision geometries as ``robot.geom_model`` (obstacles excluded).
  ``<visual>`` elements come from the bodies' visual specs (a ``.wrl`` visual becomes one STL).
* ``mesh_dir_mode="absolute"``: mesh filenames are absolute paths (the URDF loads from anywhere on
  this machine, no package dirs needed). ``"copy"``: referenced mesh files are copied into
  ``<urdf stem>_meshes/`` and referenced relative to the URDF's folder (a self-contained folder;
  pinocchio needs ``package_dirs=[<urdf folder>]`` for relative paths). Only ``copy`` output can be
  re-imported with :func:`import_urdf`, which rejects absolute paths.
* The TCP becomes a fixed joint ``tcp_joint`` and a massless link ``tcp``.

Import (:func:`import_urdf`)
----------------------------
* One module (ID = ``name`` or the URDF robot name) with one body per URDF link (body ID = link
  name) and one joint per URDF joint (joint ID = joint name). Bodies/joints form the URDF tree.
* A URDF joint with an arbitrary axis ``a`` gets a joint frame whose z-axis is ``a``:
  ``pose_parent = origin · R_align`` and ``pose_child = R_alignᵀ`` with ``R_align e_z = a``; for
  ``a = −z``, ``R_align = Rx(π)``. ``continuous`` joints become revolute with limits ±2π (pinocchio
  needs finite bounds for sampling). ``mimic`` joints, ``floating`` and ``planar`` joints are rejected.
* Gripper fingers (joints whose name contains ``finger``) are fixed at q = 0 unless
  ``include_fingers=True``.
* Inertia: URDF gives it about the CoM in the axes of ``<inertial><origin rpy>``; it is rotated
  into the link frame, ``I_link = R I Rᵀ``; the CoM is the inertial origin's ``xyz``.
* Friction: ``<dynamics damping>`` → viscous, ``friction`` → Coulomb. ``<drivetrain>`` (written by
  :func:`export_urdf`) or a transmission's ``<mechanicalReduction>`` give gear ratio/motor inertia.
* Connectors: ``base`` (type ``base``, gender ``f``, pose Rx(π)) on the root link, so the robot's
  base frame is the root link frame; ``eef`` (type ``eef``, gender ``m``, identity pose) on the TCP
  link: ``tcp_link`` if given, else the deepest leaf link (most joints from the root), not counting
  finger links — for the standard ``panda_arm_hand`` URDF this is ``panda_hand``.
* Mesh files: relative paths are relative to the URDF's folder; ``package://NAME/rest`` is looked up
  in ``package_dirs`` (folder ``NAME`` inside one of them, or a folder named ``NAME``) and else in the
  URDF's ancestors (ROS layout ``NAME/urdf/robot.urdf``). The module set's ``root`` is that package
  folder when it contains the URDF, else the URDF's folder; every mesh must resolve inside it
  (absolute paths and ``..`` escapes are rejected with an :class:`InputError` naming the field).
  Missing visual meshes are skipped with a warning (appended to ``warnings``); missing collision
  meshes are an error.
"""
from __future__ import annotations

import math
import os
import re
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from robodesign.core.errors import InputError
from robodesign.core.jsonio import resolve_inside
from robodesign.core.spatial import RX_PI, homogeneous, inv, pose_to_list, rpy_to_matrix
from robodesign.formats.geometry import GeometrySpec, load_mesh_arrays, mesh_problem
from robodesign.formats.module_spec import Body, Connector, Joint, JointLimits, Module, ModuleHeader, ModuleSet

DBL_MAX = 1.7976931348623157e308
CONTINUOUS_LIMIT = 2.0 * math.pi
MESH_DIR_MODES = ("absolute", "copy")

__all__ = ["export_urdf", "import_urdf", "CONTINUOUS_LIMIT", "MESH_DIR_MODES"]


# =============================================================================================
# small helpers
# =============================================================================================

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


def _matrix_to_rpy(R: np.ndarray) -> np.ndarray:
    """URDF roll-pitch-yaw (R = Rz(y) Ry(p) Rx(r)) of a rotation matrix, exact to ~1e-16."""
    R = np.asarray(R, dtype=float)
    sp = -R[2, 0]
    cp = math.hypot(R[0, 0], R[1, 0])
    p = math.atan2(sp, cp)
    if cp > 1e-10:
        r = math.atan2(R[2, 1], R[2, 2])
        y = math.atan2(R[1, 0], R[0, 0])
    else:  # gimbal lock: only r ∓ y is defined; put it all into r
        y = 0.0
        if sp > 0:  # p = +π/2: R = [[0, sin(r-y), cos(r-y)], [.., cos(r-y), -sin(r-y)], ...]
            r = math.atan2(R[0, 1], R[1, 1])
        else:  # p = −π/2
            r = math.atan2(-R[0, 1], R[1, 1])
    return np.array([r, p, y])


def _origin(parent: ET.Element, T: np.ndarray) -> ET.Element:
    T = np.asarray(T, dtype=float)
    return ET.SubElement(parent, "origin", xyz=_vec(T[:3, 3]), rpy=_vec(_matrix_to_rpy(T[:3, :3])))


_SAFE = re.compile(r"[^A-Za-z0-9_.\-]+")


def _safe_name(s: str) -> str:
    return _SAFE.sub("_", s).strip("._") or "mesh"


# =============================================================================================
# export
# =============================================================================================

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
    see the module docstring for every convention.
    """
    import pinocchio as pin

    if mesh_dir_mode not in MESH_DIR_MODES:
        raise InputError(f"mesh_dir_mode must be one of {MESH_DIR_MODES}, got {mesh_dir_mode!r}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path = path.resolve()
    meshes = _MeshWriter(path, mesh_dir_mode)

    model, gmodel = robot.model, robot.geom_model
    to_base = inv(np.asarray(robot.base_pose, dtype=float))

    # exact base-frame placements of everything on the root (Robot keeps them to apply base poses)
    root_items = {(kind, idx): M for kind, idx, M in getattr(robot, "_root_items", ())}

    def rel(placement, parent_joint: int, item=None) -> np.ndarray:
        """Placement relative to the parent joint frame, with the base pose removed on the root."""
        if parent_joint == 0 and item in root_items:
            return np.asarray(root_items[item], dtype=float)
        M = placement.homogeneous if hasattr(placement, "homogeneous") else np.asarray(placement)
        return to_base @ M if parent_joint == 0 else M

    ms, asm = robot.module_set, robot.assembly
    labels = robot.instance_labels

    root = ET.Element("robot", name=_safe_name(model.name.replace("robodesign:", "robodesign_")) or "robot")
    root.append(ET.Comment(
        " Written by robodesign.formats.urdf.export_urdf. Root link 'base' = the robot's base frame (base connector "
        "flipped about x). Module order: " + ",".join(asm.module_ids) + ". "))
    root.append(ET.Comment(" robodesign: base_pose = " + str(pose_to_list(robot.base_pose, 15)) + " "))
    root.append(ET.Comment(
        " Joints: <dynamics damping=viscous friction=Coulomb>; <drivetrain gear_ratio motor_inertia> is a "
        "robodesign extension (reflected inertia = gear_ratio^2 * motor_inertia, pinocchio 'armature'); "
        "infinite limits are written as +-1.7976931348623157e+308. "))

    # ---- link names: one link per pinocchio joint -------------------------------------------
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

    # ---- collision ------------------------------------------------------------------------------
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

    # ---- visual (from the body specs, at the body frames) --------------------------------------
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

    # ---- joints ---------------------------------------------------------------------------------
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

    # ---- TCP ------------------------------------------------------------------------------------
    tf = model.frames[robot.tcp_frame]
    ET.SubElement(root, "link", name="tcp")
    el = ET.SubElement(root, "joint", name="tcp_joint", type="fixed")
    _origin(el, rel(tf.placement, tf.parentJoint, ("frame", robot.tcp_frame)))
    ET.SubElement(el, "parent", link=link_names[tf.parentJoint])
    ET.SubElement(el, "child", link="tcp")

    tree = ET.ElementTree(root)
    ET.indent(tree, space="  ")
    tmp = path.with_name(path.name + ".tmp")
    tree.write(str(tmp), encoding="utf-8", xml_declaration=True)
    os.replace(tmp, path)
    return path


# =============================================================================================
# import
# =============================================================================================

class _Ctx:
    def __init__(self, file: Path, display: str):
        self.file = file
        self.display = display

    def err(self, msg: str, field: str = "") -> InputError:
        return InputError(msg, file=self.display, path=field or None)

    def floats(self, text: Optional[str], n: int, field: str, default=None) -> np.ndarray:
        if text is None:
            if default is None:
                raise self.err(f"missing, expected {n} number(s)", field)
            return np.asarray(default, dtype=float)
        parts = text.split()
        try:
            vals = [float(p) for p in parts]
        except ValueError:
            raise self.err(f"expected {n} number(s), got {text!r}", field) from None
        if len(vals) != n or not all(math.isfinite(v) for v in vals):
            raise self.err(f"expected {n} finite number(s), got {text!r}", field)
        return np.array(vals, dtype=float)

    def scalar(self, el: Optional[ET.Element], attr: str, field: str, default=None, allow_inf=False) -> float:
        text = None if el is None else el.get(attr)
        f = f"{field}.{attr}"
        if text is None:
            if default is None:
                raise self.err("missing attribute", f)
            return float(default)
        try:
            v = float(text)
        except ValueError:
            raise self.err(f"expected a number, got {text!r}", f) from None
        if math.isnan(v) or (math.isinf(v) and not allow_inf):
            raise self.err(f"expected a finite number, got {text!r}", f)
        if allow_inf and abs(v) >= DBL_MAX:
            v = math.copysign(math.inf, v)
        return v

    def pose(self, el: Optional[ET.Element], field: str) -> np.ndarray:
        """<origin xyz rpy> → 4x4 (identity when absent)."""
        if el is None:
            return np.eye(4)
        xyz = self.floats(el.get("xyz"), 3, f"{field}.xyz", default=(0.0, 0.0, 0.0))
        rpy = self.floats(el.get("rpy"), 3, f"{field}.rpy", default=(0.0, 0.0, 0.0))
        return homogeneous(rpy_to_matrix(*rpy), xyz)


def _align_z_to(axis: np.ndarray) -> np.ndarray:
    """A rotation R with R·e_z = axis (unit); Rx(π) for −z; the shortest rotation otherwise."""
    a = axis / np.linalg.norm(axis)
    z = np.array([0.0, 0.0, 1.0])
    c = float(a @ z)
    v = np.cross(z, a)
    s = float(np.linalg.norm(v))
    if s < 1e-300:  # exactly ±z
        return np.eye(3) if c > 0 else RX_PI[:3, :3].copy()
    k = v / s
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    ang = math.atan2(s, c)
    R = np.eye(3) + math.sin(ang) * K + (1 - math.cos(ang)) * (K @ K)
    U, _, Vt = np.linalg.svd(R)
    return U @ Vt


class _MeshResolver:
    """Turns URDF mesh filenames into absolute paths inside the model folder (see module docstring)."""

    def __init__(self, ctx: _Ctx, urdf_dir: Path, package_dirs: Sequence[Path], package_names: Sequence[str]):
        self.ctx = ctx
        self.urdf_dir = urdf_dir.resolve()
        self.package_dirs = [Path(p).resolve() for p in package_dirs]
        self.packages: Dict[str, Path] = {}
        self.root = self.urdf_dir
        for name in package_names:
            pkg = self._find_package(name)
            if pkg is not None:
                self.packages[name] = pkg
        # the model folder: a package that contains the URDF (ROS layout), else the URDF's folder
        inside = [p for p in self.packages.values() if _is_inside(self.urdf_dir, p)]
        if inside:
            self.root = min(inside, key=lambda p: len(p.parts))

    def _find_package(self, name: str) -> Optional[Path]:
        for d in self.package_dirs:
            if (d / name).is_dir():
                return (d / name).resolve()
            if d.name == name and d.is_dir():
                return d
        for anc in [self.urdf_dir, *self.urdf_dir.parents]:
            if anc.name == name:
                return anc
            if (anc / name).is_dir() and anc != Path(anc.anchor):
                return (anc / name).resolve()
        return None

    def resolve(self, ref: Optional[str], field: str) -> Tuple[Path, str]:
        """(absolute path, path relative to self.root) — raises InputError naming the field."""
        if not ref:
            raise self.ctx.err("missing mesh filename", field)
        if ref.startswith("package://"):
            rest = ref[len("package://"):]
            name, _, sub = rest.partition("/")
            pkg = self.packages.get(name)
            if pkg is None:
                raise self.ctx.err(f"package {name!r} of {ref!r} not found (looked in package_dirs and the "
                                   f"folders above {self.urdf_dir})", field)
            base, rel = pkg, sub
        elif ref.startswith("file://"):
            raise self.ctx.err(f"absolute file paths are not allowed ({ref!r}); give a path relative to "
                               f"{self.urdf_dir}", field)
        else:
            base, rel = self.urdf_dir, ref
        allowed = self.root if _is_inside(base, self.root) else base
        try:
            prefix = os.path.relpath(base, allowed)
            joined = rel if prefix == "." else f"{Path(prefix).as_posix()}/{rel}"
            if rel.startswith(("/", "\\")) or Path(rel).is_absolute() or (len(rel) > 1 and rel[1] == ":"):
                joined = rel  # let resolve_inside reject it
            target = resolve_inside(allowed, joined, self.ctx.display, field)
        except InputError as e:
            # re-word with the reference as written in the URDF
            reason = e.reason.replace(repr(joined), repr(ref)) if isinstance(e.reason, str) else str(e)
            raise self.ctx.err(reason, field) from None
        try:
            shown = target.relative_to(self.root).as_posix()
        except ValueError:
            shown = str(target)
        return target, shown


def _is_inside(p: Path, folder: Path) -> bool:
    try:
        Path(p).resolve().relative_to(Path(folder).resolve())
        return True
    except ValueError:
        return False


def _parse_geometry(ctx: _Ctx, el: ET.Element, field: str, meshes: _MeshResolver, required: bool,
                    warnings: Optional[list]) -> Optional[GeometrySpec]:
    pose = ctx.pose(el.find("origin"), f"{field}.origin")
    g = el.find("geometry")
    if g is None or len(g) == 0:
        raise ctx.err("missing <geometry>", field)
    shape = g[0]
    gf = f"{field}.geometry.{shape.tag}"
    if shape.tag == "box":
        size = ctx.floats(shape.get("size"), 3, f"{gf}.size")
        if np.any(size <= 0):
            raise ctx.err(f"box sizes must be positive, got {shape.get('size')!r}", f"{gf}.size")
        return GeometrySpec("box", pose, tuple(float(s) for s in size))
    if shape.tag == "cylinder":
        r = ctx.scalar(shape, "radius", gf)
        L = ctx.scalar(shape, "length", gf)
        if r <= 0 or L <= 0:
            raise ctx.err("cylinder radius and length must be positive", gf)
        return GeometrySpec("cylinder", pose, (r, L))
    if shape.tag == "sphere":
        r = ctx.scalar(shape, "radius", gf)
        if r <= 0:
            raise ctx.err("sphere radius must be positive", f"{gf}.radius")
        return GeometrySpec("sphere", pose, (r,))
    if shape.tag == "mesh":
        ref = shape.get("filename")
        target, shown = meshes.resolve(ref, f"{gf}.filename")
        scale = ctx.floats(shape.get("scale"), 3, f"{gf}.scale", default=(1.0, 1.0, 1.0))
        if np.any(scale <= 0):
            raise ctx.err(f"scale must be positive, got {shape.get('scale')!r}", f"{gf}.scale")
        if not target.is_file():
            msg = f"mesh file not found: {ref!r} (looked at {target})"
            if required:
                raise ctx.err(msg, f"{gf}.filename")
            if warnings is not None:
                warnings.append(f"{ctx.display}: {gf}.filename: {msg}; the visual is skipped")
            return None
        spec = GeometrySpec("mesh", pose, (), target, (float(scale[0]), float(scale[1]), float(scale[2])), shown)
        # collision meshes must load now (a clear error) rather than vanish when the Robot is built
        problem = mesh_problem(target, spec.scale, full=required)
        if problem and required:
            raise ctx.err(f"collision mesh file {ref!r} {problem}", f"{gf}.filename")
        if problem:
            if warnings is not None:
                warnings.append(f"{ctx.display}: {gf}.filename: visual mesh file {ref!r} {problem}; "
                                "the visual is skipped")
            return None
        return spec
    raise ctx.err(f"unsupported geometry <{shape.tag}> (box, cylinder, sphere, mesh)", gf)


def _is_finger(joint_name: str) -> bool:
    return "finger" in joint_name.lower()


def import_urdf(path: Union[str, Path], name: Optional[str] = None, tcp_link: Optional[str] = None,
                include_fingers: bool = False, package_dirs: Sequence[Union[str, Path]] = (),
                warnings: Optional[list] = None) -> ModuleSet:
    """Read a monolithic robot URDF as a module set with ONE module (see the module docstring).

    ``Robot.from_order(ms, [ms.ids[0]])`` then builds the robot: base frame = root link frame,
    TCP = ``tcp_link`` (default: deepest non-finger leaf link).
    """
    path = Path(path)
    display = str(path)
    ctx = _Ctx(path, display)
    try:
        tree = ET.parse(str(path))
    except FileNotFoundError:
        raise InputError("file not found", file=display) from None
    except IsADirectoryError:
        raise InputError("is a folder, expected a URDF file", file=display) from None
    except ET.ParseError as e:
        raise InputError(f"malformed XML: {e}", file=display) from None
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"cannot read file ({e})", file=display) from None
    robot = tree.getroot()
    if robot.tag != "robot":
        raise InputError(f"root element must be <robot>, got <{robot.tag}>", file=display)
    rname = robot.get("name") or path.stem
    mid = str(name or rname)

    # ---- mesh resolution ------------------------------------------------------------------------
    pkg_names = sorted({m.get("filename", "")[len("package://"):].split("/")[0]
                        for m in robot.iter("mesh") if m.get("filename", "").startswith("package://")})
    meshes = _MeshResolver(ctx, path.parent.resolve(), [Path(p) for p in package_dirs], pkg_names)

    # ---- links ----------------------------------------------------------------------------------
    link_els: Dict[str, ET.Element] = {}
    order: List[str] = []
    for li, le in enumerate(robot.findall("link")):
        ln = le.get("name")
        if not ln:
            raise ctx.err("link without a name", f"link[{li}]")
        if ln in link_els:
            raise ctx.err(f"duplicate link name {ln!r}", f"link[{ln}]")
        link_els[ln] = le
        order.append(ln)
    if not link_els:
        raise ctx.err("the URDF has no <link>")

    # ---- joints (raw) ---------------------------------------------------------------------------
    joint_els: Dict[str, Tuple[ET.Element, str, str]] = {}  # joint → (element, parent link, child link)
    parent_of: Dict[str, str] = {}
    children: Dict[str, List[str]] = {ln: [] for ln in order}
    for ji, je in enumerate(robot.findall("joint")):
        jn = je.get("name")
        if not jn:
            raise ctx.err("joint without a name", f"joint[{ji}]")
        f = f"joint[{jn}]"
        if jn in joint_els:
            raise ctx.err(f"duplicate joint name {jn!r}", f)
        pe, ce = je.find("parent"), je.find("child")
        if pe is None or not pe.get("link"):
            raise ctx.err("missing <parent link=...>", f"{f}.parent")
        if ce is None or not ce.get("link"):
            raise ctx.err("missing <child link=...>", f"{f}.child")
        p, c = pe.get("link", ""), ce.get("link", "")
        for key, ln in (("parent", p), ("child", c)):
            if ln not in link_els:
                raise ctx.err(f"unknown link {ln!r}", f"{f}.{key}.link")
        if c in parent_of:
            raise ctx.err(f"link {c!r} has two parent joints ({parent_of[c]!r} and {jn!r}); loops are not supported",
                          f"{f}.child")
        parent_of[c] = jn
        children[p].append(jn)
        joint_els[jn] = (je, p, c)
    roots = [ln for ln in order if ln not in parent_of]
    if len(roots) != 1:
        raise ctx.err(f"expected exactly one root link, found {len(roots)}: {roots[:5]}")
    root_link = roots[0]
    # reachability / loops
    depth: Dict[str, Tuple[int, int]] = {root_link: (0, 0)}  # link → (actuated joints from root, joints)
    finger_links = set()
    stack = [root_link]
    while stack:
        ln = stack.pop()
        for jn in children[ln]:
            je, _, c = joint_els[jn]
            if c in depth:
                raise ctx.err(f"joint {jn!r} closes a loop", f"joint[{jn}]")
            act = je.get("type") != "fixed"
            depth[c] = (depth[ln][0] + int(act), depth[ln][1] + 1)
            if ln in finger_links or _is_finger(jn):
                finger_links.add(c)
            stack.append(c)
    if len(depth) != len(order):
        missing = [ln for ln in order if ln not in depth]
        raise ctx.err(f"links not connected to the root {root_link!r}: {missing[:5]}")

    # ---- drivetrain from transmissions (fallback) ----------------------------------------------
    reduction: Dict[str, float] = {}
    for ti, te in enumerate(robot.findall("transmission")):
        for tj in te.findall("joint"):
            mr = tj.find("mechanicalReduction")
            if mr is None:
                for actuator in te.findall("actuator"):
                    mr = actuator.find("mechanicalReduction") if mr is None else mr
            if mr is not None and (tjn := tj.get("name")) and mr.text:
                try:
                    reduction[tjn] = abs(float(mr.text))
                except ValueError:
                    raise ctx.err(f"expected a number, got {mr.text!r}",
                                  f"transmission[{te.get('name') or ti}].mechanicalReduction") from None

    # ---- joints (typed) -------------------------------------------------------------------------
    joints: List[Joint] = []
    for jn, (je, p, c) in joint_els.items():
        f = f"joint[{jn}]"
        jtype = je.get("type")
        origin = ctx.pose(je.find("origin"), f"{f}.origin")
        if jtype not in ("revolute", "continuous", "prismatic", "fixed"):
            raise ctx.err(f"unsupported joint type {jtype!r} (revolute, continuous, prismatic, fixed)", f"{f}.type")
        locked = jtype != "fixed" and _is_finger(jn) and not include_fingers
        if je.find("mimic") is not None and jtype != "fixed" and not locked:
            raise ctx.err("mimic joints are not supported (make the joint fixed, or leave fingers out with "
                          "include_fingers=False)", f"{f}.mimic")
        if jtype == "fixed" or locked:
            joints.append(Joint(id=jn, type="fixed", parent=p, child=c, pose_parent=origin, pose_child=np.eye(4),
                                limits=JointLimits(0.0, 0.0)))
            continue
        ax = ctx.floats(axe.get("xyz") if (axe := je.find("axis")) is not None else None, 3, f"{f}.axis.xyz",
                        default=(1.0, 0.0, 0.0))
        if np.linalg.norm(ax) < 1e-12:
            raise ctx.err("joint axis must not be zero", f"{f}.axis.xyz")
        R = _align_z_to(ax)
        lim = je.find("limit")
        lf = f"{f}.limit"
        if jtype == "continuous":
            lower, upper = -CONTINUOUS_LIMIT, CONTINUOUS_LIMIT
        else:
            if lim is None:
                raise ctx.err(f"a {jtype} joint needs a <limit>", lf)
            lower = ctx.scalar(lim, "lower", lf, default=0.0, allow_inf=True)
            upper = ctx.scalar(lim, "upper", lf, default=0.0, allow_inf=True)
            if lower > upper:
                raise ctx.err(f"lower {lower} > upper {upper}", f"{lf}.lower")
        effort = ctx.scalar(lim, "effort", lf, default=math.inf, allow_inf=True)
        velocity = ctx.scalar(lim, "velocity", lf, default=math.inf, allow_inf=True)
        accel = ctx.scalar(lim, "acceleration", lf, default=math.inf, allow_inf=True)
        for nm, v in (("effort", effort), ("velocity", velocity), ("acceleration", accel)):
            if v < 0:
                raise ctx.err(f"must be >= 0, got {v}", f"{lf}.{nm}")
        de = je.find("dynamics")
        damping = ctx.scalar(de, "damping", f"{f}.dynamics", default=0.0)
        friction = ctx.scalar(de, "friction", f"{f}.dynamics", default=0.0)
        dt = je.find("drivetrain")
        gear = ctx.scalar(dt, "gear_ratio", f"{f}.drivetrain", default=reduction.get(jn, 1.0))
        im = ctx.scalar(dt, "motor_inertia", f"{f}.drivetrain", default=0.0)
        for nm, v, fld in (("damping", damping, "dynamics"), ("friction", friction, "dynamics"),
                           ("gear_ratio", gear, "drivetrain"), ("motor_inertia", im, "drivetrain")):
            if v < 0:
                raise ctx.err(f"must be >= 0, got {v}", f"{f}.{fld}.{nm}")
        joints.append(Joint(id=jn, type="prismatic" if jtype == "prismatic" else "revolute", parent=p, child=c,
                            pose_parent=origin @ homogeneous(R), pose_child=homogeneous(R.T),
                            limits=JointLimits(lower, upper, velocity, accel, effort), gear_ratio=gear,
                            motor_inertia=im, friction_coulomb=friction, friction_viscous=damping))

    # ---- TCP link -------------------------------------------------------------------------------
    if tcp_link is not None:
        if tcp_link not in link_els:
            raise InputError(f"tcp_link {tcp_link!r} is not a link of {display} (links: {', '.join(order[:12])}"
                             f"{', ...' if len(order) > 12 else ''})")
        tcp = tcp_link
    else:
        def arm_children(ln):  # child links that are not gripper fingers
            return [jn for jn in children[ln] if joint_els[jn][2] not in finger_links]
        leaves = [ln for ln in order if ln not in finger_links and not arm_children(ln)] or \
                 [ln for ln in order if not children[ln]]
        tcp = max(leaves, key=lambda ln: (depth[ln], order.index(ln)))

    # ---- bodies ---------------------------------------------------------------------------------
    bodies = []
    for ln in order:
        le = link_els[ln]
        f = f"link[{ln}]"
        mass, com, inertia = 0.0, np.zeros(3), np.zeros((3, 3))
        ie = le.find("inertial")
        if ie is not None:
            T = ctx.pose(ie.find("origin"), f"{f}.inertial.origin")
            me = ie.find("mass")
            mass = ctx.scalar(me, "value", f"{f}.inertial.mass") if me is not None else 0.0
            if mass < 0:
                raise ctx.err(f"mass must be >= 0, got {mass}", f"{f}.inertial.mass.value")
            ine = ie.find("inertia")
            inf_ = f"{f}.inertial.inertia"
            vals = {k: ctx.scalar(ine, k, inf_, default=0.0) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
            I = np.array([[vals["ixx"], vals["ixy"], vals["ixz"]],
                          [vals["ixy"], vals["iyy"], vals["iyz"]],
                          [vals["ixz"], vals["iyz"], vals["izz"]]])
            Rn = T[:3, :3]
            inertia = Rn @ I @ Rn.T
            inertia = 0.5 * (inertia + inertia.T)
            com = T[:3, 3].copy()
            if np.linalg.eigvalsh(I).min() < -1e-9 * max(1.0, np.abs(I).max()):
                raise ctx.err("inertia matrix is not positive semi-definite", inf_)
        collision = tuple(s for s in (_parse_geometry(ctx, ce, f"{f}.collision[{k}]", meshes, True, warnings)
                                      for k, ce in enumerate(le.findall("collision"))) if s is not None)
        visual = tuple(s for s in (_parse_geometry(ctx, ve, f"{f}.visual[{k}]", meshes, False, warnings)
                                   for k, ve in enumerate(le.findall("visual"))) if s is not None)
        cons = []
        if ln == root_link:
            cons.append(Connector(id="base", body_id=ln, pose=RX_PI.copy(), gender="f", type="base"))
        if ln == tcp:
            cons.append(Connector(id="eef", body_id=ln, pose=np.eye(4), gender="m", type="eef"))
        bodies.append(Body(id=ln, mass=mass, com=com, inertia=inertia, connectors=tuple(cons), collision=collision,
                           visual=visual))

    module = Module(header=ModuleHeader(id=mid, name=str(rname)), bodies=tuple(bodies), joints=tuple(joints))
    return ModuleSet(name=str(name or rname), modules={mid: module}, root=meshes.root, ignore_collisions="via_joint",
                     source=str(path.resolve()))
