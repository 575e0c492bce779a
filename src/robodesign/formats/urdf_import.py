"""URDF import of monolithic robots as a one-module set (:func:`import_urdf`): the document read part by part
(links, joint tree, transmissions, joints, TCP, bodies); the conventions are in :mod:`robodesign.formats.urdf`."""
from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Set, Tuple, Union

import numpy as np

from robodesign.core.errors import InputError
from robodesign.core.jsonio import resolve_inside
from robodesign.core.spatial import RX_PI, homogeneous, rpy_to_matrix
from robodesign.formats.geometry import GeometrySpec, mesh_problem
from robodesign.formats.module_spec import Body, Connector, Joint, JointLimits, Module, ModuleHeader, ModuleSet
from robodesign.formats.urdf_export import DBL_MAX

CONTINUOUS_LIMIT = 2.0 * math.pi

#: joint name → (its element, parent link, child link), in document order
_JointEls = Dict[str, Tuple[ET.Element, str, str]]


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
    """Read a monolithic robot URDF as a module set with ONE module (see the module docstring of
    :mod:`robodesign.formats.urdf`).

    ``Robot.from_order(ms, [ms.ids[0]])`` then builds the robot: base frame = root link frame,
    TCP = ``tcp_link`` (default: deepest non-finger leaf link).
    """
    path = Path(path)
    display = str(path)
    ctx = _Ctx(path, display)
    robot = _read_robot(path, display)
    rname = robot.get("name") or path.stem
    mid = str(name or rname)

    pkg_names = sorted({m.get("filename", "")[len("package://"):].split("/")[0]
                        for m in robot.iter("mesh") if m.get("filename", "").startswith("package://")})
    meshes = _MeshResolver(ctx, path.parent.resolve(), [Path(p) for p in package_dirs], pkg_names)

    link_els, order = _link_elements(ctx, robot)
    joint_els, children = _joint_tree(ctx, robot, link_els, order)
    root_link, depth, finger_links = _walk_tree(ctx, order, joint_els, children)
    reduction = _reductions(ctx, robot)
    joints = [_joint(ctx, jn, je, p, c, include_fingers, reduction) for jn, (je, p, c) in joint_els.items()]
    tcp = _tcp_link(tcp_link, display, order, joint_els, children, depth, finger_links)
    bodies = [_body(ctx, ln, link_els[ln], meshes, warnings, root_link, tcp) for ln in order]

    module = Module(header=ModuleHeader(id=mid, name=str(rname)), bodies=tuple(bodies), joints=tuple(joints))
    return ModuleSet(name=str(name or rname), modules={mid: module}, root=meshes.root, ignore_collisions="via_joint",
                     source=str(path.resolve()))


def _read_robot(path: Path, display: str) -> ET.Element:
    """The <robot> element of the file; unreadable or malformed files are InputErrors."""
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
    return robot


def _link_elements(ctx: _Ctx, robot: ET.Element) -> Tuple[Dict[str, ET.Element], List[str]]:
    """→ (link name → element, the names in document order); names are required and distinct."""
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
    return link_els, order


def _joint_tree(ctx: _Ctx, robot: ET.Element, link_els: Dict[str, ET.Element], order: List[str]
                ) -> Tuple[_JointEls, Dict[str, List[str]]]:
    """The joints as written (names, parent and child links; each link has at most one parent joint).
    → (joint elements, link → its child joints)."""
    joint_els: _JointEls = {}
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
    return joint_els, children


def _walk_tree(ctx: _Ctx, order: List[str], joint_els: _JointEls, children: Dict[str, List[str]]
               ) -> Tuple[str, Dict[str, Tuple[int, int]], Set[str]]:
    """The one root link, every link reached from it without a loop. → (root link, link → (actuated joints from
    the root, joints from the root), the finger links)."""
    has_parent = {c for _, _, c in joint_els.values()}
    roots = [ln for ln in order if ln not in has_parent]
    if len(roots) != 1:
        raise ctx.err(f"expected exactly one root link, found {len(roots)}: {roots[:5]}")
    root_link = roots[0]
    depth: Dict[str, Tuple[int, int]] = {root_link: (0, 0)}
    finger_links: Set[str] = set()
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
    return root_link, depth, finger_links


def _reductions(ctx: _Ctx, robot: ET.Element) -> Dict[str, float]:
    """Joint name → gear ratio from the transmissions' <mechanicalReduction> (the fallback of <drivetrain>)."""
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
    return reduction


def _joint(ctx: _Ctx, jn: str, je: ET.Element, p: str, c: str, include_fingers: bool,
           reduction: Dict[str, float]) -> Joint:
    """One typed joint: fixed (or a locked finger), else revolute/prismatic with its axis aligned to z, its
    limits, friction and drivetrain."""
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
        return Joint(id=jn, type="fixed", parent=p, child=c, pose_parent=origin, pose_child=np.eye(4),
                     limits=JointLimits(0.0, 0.0))
    ax = ctx.floats(axe.get("xyz") if (axe := je.find("axis")) is not None else None, 3, f"{f}.axis.xyz",
                    default=(1.0, 0.0, 0.0))
    if np.linalg.norm(ax) < 1e-12:
        raise ctx.err("joint axis must not be zero", f"{f}.axis.xyz")
    R = _align_z_to(ax)
    limits = _joint_limits(ctx, je, f, jtype)
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
    return Joint(id=jn, type="prismatic" if jtype == "prismatic" else "revolute", parent=p, child=c,
                 pose_parent=origin @ homogeneous(R), pose_child=homogeneous(R.T), limits=limits, gear_ratio=gear,
                 motor_inertia=im, friction_coulomb=friction, friction_viscous=damping)


def _joint_limits(ctx: _Ctx, je: ET.Element, f: str, jtype: str) -> JointLimits:
    """The <limit> of a moving joint (a continuous one: ±CONTINUOUS_LIMIT); absent bounds are infinite."""
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
    return JointLimits(lower, upper, velocity, accel, effort)


def _tcp_link(tcp_link: Optional[str], display: str, order: List[str], joint_els: _JointEls,
              children: Dict[str, List[str]], depth: Dict[str, Tuple[int, int]], finger_links: Set[str]) -> str:
    """``tcp_link`` (which must be a link), else the deepest leaf link that is not a gripper finger."""
    if tcp_link is not None:
        if tcp_link not in order:
            raise InputError(f"tcp_link {tcp_link!r} is not a link of {display} (links: {', '.join(order[:12])}"
                             f"{', ...' if len(order) > 12 else ''})")
        return tcp_link

    def arm_children(ln):  # child links that are not gripper fingers
        return [jn for jn in children[ln] if joint_els[jn][2] not in finger_links]
    leaves = [ln for ln in order if ln not in finger_links and not arm_children(ln)] or \
             [ln for ln in order if not children[ln]]
    return max(leaves, key=lambda ln: (depth[ln], order.index(ln)))


def _inertial(ctx: _Ctx, ie: Optional[ET.Element], f: str) -> Tuple[float, np.ndarray, np.ndarray]:
    """A link's <inertial> → (mass, CoM, inertia about the CoM in link axes); zero when absent."""
    mass, com, inertia = 0.0, np.zeros(3), np.zeros((3, 3))
    if ie is None:
        return mass, com, inertia
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
    return mass, com, inertia


def _body(ctx: _Ctx, ln: str, le: ET.Element, meshes: _MeshResolver, warnings: Optional[list], root_link: str,
          tcp: str) -> Body:
    """One body per link: inertia, collision and visual geometry, the base / eef connector."""
    f = f"link[{ln}]"
    mass, com, inertia = _inertial(ctx, le.find("inertial"), f)
    collision = tuple(s for s in (_parse_geometry(ctx, ce, f"{f}.collision[{k}]", meshes, True, warnings)
                                  for k, ce in enumerate(le.findall("collision"))) if s is not None)
    visual = tuple(s for s in (_parse_geometry(ctx, ve, f"{f}.visual[{k}]", meshes, False, warnings)
                               for k, ve in enumerate(le.findall("visual"))) if s is not None)
    cons = []
    if ln == root_link:
        cons.append(Connector(id="base", body_id=ln, pose=RX_PI.copy(), gender="f", type="base"))
    if ln == tcp:
        cons.append(Connector(id="eef", body_id=ln, pose=np.eye(4), gender="m", type="eef"))
    return Body(id=ln, mass=mass, com=com, inertia=inertia, connectors=tuple(cons), collision=collision,
                visual=visual)
