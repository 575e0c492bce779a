"""URDF export/import, checked against pinocchio's own URDF parser as the independent reference."""
from __future__ import annotations

import math
import shutil
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from robodesign.core.errors import InputError
from robodesign.formats.module_io import load_module_set
from robodesign.core.paths import schemas_dir
from robodesign.model.robot import Robot
from robodesign.core.spatial import homogeneous, rpy_to_matrix
from robodesign.formats.urdf import CONTINUOUS_LIMIT, export_urdf, import_urdf

from conftest import COBRA  # noqa: E402
MODULES = COBRA / "modules"
PANDA_DIR = COBRA / "urdf" / "panda"
PANDA = PANDA_DIR / "urdf" / "panda.urdf"
TOL = 1e-9
N_Q = 5

BASE_POSE = homogeneous(rpy_to_matrix(0.3, -0.2, 1.0), [1.0, 2.0, 0.5])
ASSEMBLIES = [
    ("IMPROV", ("1", "21", "4", "21", "23", "12"), None),
    ("IMPROV", ("1", "22", "5", "23", "15", "29", "101"), BASE_POSE),
    ("geometric_primitive_modules", ("base", "J2", "i_30", "J1", "l_15", "J2", "eef"), None),
]
ASSEMBLY_IDS = ["improv-6", "improv-7-moved-base", "primitives-7"]
# Modules mounted backwards (entered through their distal body): joints about -z. Needs an f–f adapter,
# added to a copy of geometric_primitive_modules; connections are explicit (see reversed_robot).
REVERSED = ("reversed", ("base", "ff_15", "J2", "i_30", "J1", "i_15"), None)


def _wait_for_schema(timeout: float = 120.0) -> None:
    """The module schema is written by a colleague; wait for it rather than skip validation."""
    f = schemas_dir() / "modules.schema.json"
    t0 = time.time()
    while not f.is_file() and time.time() - t0 < timeout:
        time.sleep(2.0)


def _module_set(name: str):
    _wait_for_schema()
    return load_module_set(MODULES / name)


def reversed_robot(tmp_root: Path) -> Robot:
    import copy
    from robodesign.formats.assembly import Assembly
    from robodesign.core.jsonio import dumps_json, load_json
    data = load_json(MODULES / "geometric_primitive_modules" / "modules.json")
    ff = copy.deepcopy(next(m for m in data["modules"] if m["header"]["ID"] == "i_15"))
    ff["header"]["ID"], ff["header"]["name"] = "ff_15", "I link f-f 15"
    for c in ff["bodies"][0]["connectors"]:
        c["gender"] = "f"
    data["modules"].append(ff)
    folder = tmp_root / "primitives_ff"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "modules.json").write_text(dumps_json(data))
    _wait_for_schema()
    ms = load_module_set(folder)
    ids = list(REVERSED[1])
    cons = [(1, "8-0", 0, "base2robot"), (2, "J2_distal", 1, "8-1"), (3, "8-1", 2, "J2_proximal"),
            (4, "J1_distal", 3, "8-0"), (5, "8-1", 4, "J1_proximal")]
    robot = Robot(ms, Assembly.from_graph(ms, ids, cons))
    assert [j.reversed for j in robot.joint_infos] == [True, True]
    return robot


def _robot(set_name, order, base_pose, tmp_root: Path = None) -> Robot:
    if set_name == "reversed":
        return reversed_robot(tmp_root)
    return Robot.from_order(_module_set(set_name), list(order), base_pose=base_pose)


def _sym(M):
    return np.triu(M) + np.triu(M, 1).T


def _ref_q(ref: pin.Model, values: dict) -> np.ndarray:
    """A configuration of ``ref`` from joint name → angle (continuous joints use cos/sin)."""
    q = pin.neutral(ref)
    for j in range(1, ref.njoints):
        v = values[ref.names[j]]
        jm = ref.joints[j]
        if jm.nq == 2:
            q[jm.idx_q:jm.idx_q + 2] = [math.cos(v), math.sin(v)]
        else:
            q[jm.idx_q] = v
    return q


def _drivetrain(path: Path) -> dict:
    """Independent read of the <drivetrain> extension: joint name → (gear ratio, motor inertia)."""
    out = {}
    for je in ET.parse(str(path)).getroot().findall("joint"):
        d = je.find("drivetrain")
        if d is not None:
            out[je.get("name")] = (float(d.get("gear_ratio")), float(d.get("motor_inertia")))
    return out


def _collision_count(model, path, package_dirs):
    g = pin.buildGeomFromUrdf(model, str(path), pin.COLLISION, package_dirs=[str(p) for p in package_dirs])
    return len(g.geometryObjects)


# =============================================================================================
# export → pinocchio
# =============================================================================================

@pytest.mark.parametrize("mode", ["absolute", "copy"])
@pytest.mark.parametrize("set_name,order,base_pose", ASSEMBLIES + [REVERSED], ids=ASSEMBLY_IDS + ["reversed-joints"])
def test_export_matches_pinocchio_urdf_parser(tmp_path, set_name, order, base_pose, mode):
    robot = _robot(set_name, order, base_pose, tmp_path)
    out = tmp_path / mode / "robot.urdf"
    path = export_urdf(robot, out, mesh_dir_mode=mode)
    assert path == out.resolve() and path.is_file()
    ref = pin.buildModelFromUrdf(str(path))
    rd = ref.createData()

    # same joints, same order, same types/limits/friction
    assert list(ref.names)[1:] == [j.name for j in robot.joint_infos]
    assert ref.nq == ref.nv == robot.dof
    np.testing.assert_allclose(ref.lowerPositionLimit, robot.q_lower, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ref.upperPositionLimit, robot.q_upper, rtol=0, atol=1e-12)
    finite = lambda a: np.where(np.isfinite(a), a, np.finfo(float).max)  # inf is written as DBL_MAX
    np.testing.assert_array_equal(ref.effortLimit, finite(robot.tau_max))
    np.testing.assert_array_equal(ref.velocityLimit, finite(robot.dq_max))
    np.testing.assert_array_equal(ref.damping, robot.friction_viscous)
    np.testing.assert_array_equal(ref.friction, robot.friction_coulomb)
    # drivetrain extension: reflected motor inertia = pinocchio armature
    dt = _drivetrain(path)
    ref.armature = np.array([dt[n][0] ** 2 * dt[n][1] for n in list(ref.names)[1:]])
    np.testing.assert_allclose(ref.armature, robot.model.armature, rtol=1e-15, atol=0)

    # total mass (every inertia, incl. the one fixed to the base)
    assert abs(sum(Y.mass for Y in ref.inertias) - sum(Y.mass for Y in robot.model.inertias)) < TOL
    assert abs(sum(Y.mass for Y in ref.inertias) - robot.mass) < TOL

    # the URDF root is the base frame: gravity seen in base axes
    Rb = robot.base_pose[:3, :3]
    ref.gravity = pin.Motion(np.r_[Rb.T @ robot.model.gravity.linear, 0.0, 0.0, 0.0])
    tcp = ref.getFrameId("tcp")
    rng = np.random.default_rng(7)
    for _ in range(N_Q):
        q = robot.random_configuration(rng)
        pin.framesForwardKinematics(ref, rd, q)
        np.testing.assert_allclose(robot.base_pose @ rd.oMf[tcp].homogeneous, robot.fk(q), rtol=0, atol=TOL)
        np.testing.assert_allclose(_sym(pin.crba(ref, rd, q)), robot.mass_matrix(q), rtol=0, atol=TOL)
        np.testing.assert_allclose(pin.computeGeneralizedGravity(ref, rd, q), robot.gravity_torque(q),
                                   rtol=0, atol=TOL)

    # one URDF <collision> per coal object; every mesh file loads
    assert _collision_count(ref, path, [path.parent]) == robot.n_collision_geometries
    root = ET.parse(str(path)).getroot()
    for m in root.iter("mesh"):
        f = Path(m.get("filename"))
        assert f.suffix.lower() != ".wrl", "VRML must be converted to STL"
        if mode == "absolute":
            assert f.is_absolute() and f.is_file(), f
        else:  # self-contained folder: relative paths to files next to the URDF
            assert not f.is_absolute() and (path.parent / f).is_file(), f
            assert (path.parent / f).resolve().parent == path.parent / "robot_meshes"
    # base pose recorded in a comment; reversed modules turn about -z
    assert "robodesign: base_pose" in path.read_text()
    axes = [je.find("axis").get("xyz") for je in root.findall("joint") if je.get("type") != "fixed"]
    assert axes == ["0 0 -1" if j.reversed else "0 0 1" for j in robot.joint_infos]


def test_export_writes_convex_parts_as_stl(tmp_path):
    robot = _robot("IMPROV", ("1", "22", "5", "23", "15", "29", "101"), None)
    path = export_urdf(robot, tmp_path / "r.urdf", mesh_dir_mode="absolute")
    parts = [g for g in robot.geom_model.geometryObjects[:robot.n_collision_geometries]
             if type(g.geometry).__name__ == "Convex"]
    assert len(parts) >= 5  # module 5 alone has 3 convex pieces
    root = ET.parse(str(path)).getroot()
    coll = {c.get("name"): c for c in root.iter("collision")}
    import trimesh
    for go in parts:
        mesh = coll[go.name].find("geometry/mesh")
        f = Path(mesh.get("filename"))
        assert f.suffix == ".stl" and f.parent == tmp_path / "r_meshes"
        m = trimesh.load(str(f), force="mesh")
        np.testing.assert_allclose(m.volume, go.geometry.computeVolume(), rtol=1e-5)


# =============================================================================================
# export → import → Robot (our own round trip)
# =============================================================================================

@pytest.mark.parametrize("set_name,order,base_pose", ASSEMBLIES + [REVERSED], ids=ASSEMBLY_IDS + ["reversed-joints"])
def test_export_import_round_trip(tmp_path, set_name, order, base_pose):
    robot = _robot(set_name, order, base_pose, tmp_path)
    path = export_urdf(robot, tmp_path / "rt" / "rt.urdf", mesh_dir_mode="copy")
    ms = import_urdf(path, name="rt")
    assert ms.ids == ("rt",) and ms.root == path.parent
    mod = ms["rt"]
    assert mod.dof == robot.dof
    again = Robot.from_order(ms, ["rt"], base_pose=robot.base_pose)
    assert again.dof == robot.dof
    assert abs(again.mass - robot.mass) < TOL
    for a in ("q_lower", "q_upper", "dq_max", "tau_max", "ddq_max", "gear_ratio", "motor_inertia",
              "friction_coulomb", "friction_viscous"):
        np.testing.assert_array_equal(getattr(again, a), getattr(robot, a), err_msg=a)
    assert again.n_collision_geometries == robot.n_collision_geometries
    rng = np.random.default_rng(3)
    for _ in range(N_Q):
        q = robot.random_configuration(rng)
        np.testing.assert_allclose(again.fk(q), robot.fk(q), rtol=0, atol=TOL)
        np.testing.assert_allclose(again.mass_matrix(q), robot.mass_matrix(q), rtol=0, atol=TOL)
        np.testing.assert_allclose(again.gravity_torque(q), robot.gravity_torque(q), rtol=0, atol=TOL)


# =============================================================================================
# import: panda
# =============================================================================================

def _compare_with_reference(robot: Robot, ref: pin.Model, module_id: str, frames, tcp_frame: str,
                            seed: int = 0) -> None:
    rd = ref.createData()
    ours = [j.name for j in robot.joint_infos]
    assert sorted(ours) == sorted(f"{module_id}.{n}" for n in list(ref.names)[1:])
    rng = np.random.default_rng(seed)
    for _ in range(N_Q):
        q = robot.random_configuration(rng)
        by_name = {n[len(module_id) + 1:]: v for n, v in zip(ours, q)}
        qr = _ref_q(ref, by_name)
        pin.framesForwardKinematics(ref, rd, qr)
        np.testing.assert_allclose(robot.fk(q), rd.oMf[ref.getFrameId(tcp_frame)].homogeneous, rtol=0, atol=TOL)
        for f in frames:
            np.testing.assert_allclose(robot.fk(q, robot.frame_id(f"{module_id}.{f}")),
                                       rd.oMf[ref.getFrameId(f)].homogeneous, rtol=0, atol=TOL, err_msg=f)
        # joint-space inertia and gravity, permuted to our joint order
        perm = [ref.joints[ref.getJointId(n[len(module_id) + 1:])].idx_v for n in ours]
        M = _sym(pin.crba(ref, rd, qr))[np.ix_(perm, perm)]
        np.testing.assert_allclose(robot.mass_matrix(q) - np.diag(robot.model.armature), M, rtol=0, atol=TOL)
        g = pin.computeGeneralizedGravity(ref, rd, qr)[perm]
        np.testing.assert_allclose(robot.gravity_torque(q), g, rtol=0, atol=TOL)


def test_import_panda():
    ms = import_urdf(PANDA)
    assert len(ms) == 1 and ms.ids == ("panda",)
    mod = ms["panda"]
    assert mod.dof == 7
    assert sum(j.type == "revolute" for j in mod.joints) == 7
    assert ms.root == PANDA_DIR.resolve()  # package://panda/... resolves in the package folder
    base = [c for c in mod.connectors if c.type == "base"]
    eef = [c for c in mod.connectors if c.type == "eef"]
    assert len(base) == 1 and base[0].gender == "f" and base[0].body_id == "world"
    assert len(eef) == 1 and eef[0].gender == "m" and eef[0].body_id == "panda_link8"
    for b in mod.bodies:
        for g in b.collision:
            assert g.kind == "mesh" and g.file.is_file() and g.file.suffix == ".stl"
            assert g.ref.startswith("meshes/collision/")
    robot = Robot.from_order(ms, ["panda"])
    ref = pin.buildModelFromUrdf(str(PANDA))
    assert ref.nq == robot.dof == 7
    assert abs(sum(Y.mass for Y in ref.inertias) - robot.mass) < TOL
    assert abs(sum(Y.mass for Y in robot.model.inertias) - robot.mass) < TOL
    np.testing.assert_array_equal(robot.q_lower, ref.lowerPositionLimit)
    np.testing.assert_array_equal(robot.q_upper, ref.upperPositionLimit)
    np.testing.assert_array_equal(robot.tau_max, ref.effortLimit)
    np.testing.assert_array_equal(robot.dq_max, ref.velocityLimit)
    np.testing.assert_array_equal(robot.friction_viscous, ref.damping)
    np.testing.assert_array_equal(robot.ddq_max, [15, 7.5, 12.5, 12.5, 15, 20, 20])  # <limit acceleration>
    links = [f"panda_link{k}" for k in range(9)]
    _compare_with_reference(robot, ref, "panda", links, "panda_link8")
    assert robot.n_collision_geometries == _collision_count(ref, PANDA, [PANDA_DIR.parent]) == 8


HAND = """
  <joint name="panda_hand_joint" type="fixed">
    <parent link="panda_link8"/><child link="panda_hand"/>
    <origin rpy="0 0 -0.7853981633974483" xyz="0 0 0"/>
  </joint>
  <link name="panda_hand">
    <visual><geometry><mesh filename="package://panda/meshes/visual/hand.dae"/></geometry></visual>
    <collision><geometry><mesh filename="package://panda/meshes/collision/hand.stl"/></geometry></collision>
    <inertial><origin rpy="0.1 0.2 0.3" xyz="-0.01 0 0.03"/><mass value="0.73"/>
      <inertia ixx="0.001" ixy="0.0001" ixz="0.0" iyy="0.0025" iyz="-0.0002" izz="0.0017"/></inertial>
  </link>
  <link name="panda_leftfinger">
    <collision><origin xyz="0 0.01 0.02"/><geometry><box size="0.02 0.02 0.05"/></geometry></collision>
    <inertial><origin xyz="0 0.01 0.02"/><mass value="0.015"/>
      <inertia ixx="2.4e-06" ixy="0" ixz="0" iyy="2.4e-06" iyz="0" izz="5e-07"/></inertial>
  </link>
  <link name="panda_rightfinger">
    <collision><origin xyz="0 -0.01 0.02"/><geometry><box size="0.02 0.02 0.05"/></geometry></collision>
    <inertial><origin xyz="0 -0.01 0.02"/><mass value="0.015"/>
      <inertia ixx="2.4e-06" ixy="0" ixz="0" iyy="2.4e-06" iyz="0" izz="5e-07"/></inertial>
  </link>
  <joint name="panda_finger_joint1" type="prismatic">
    <parent link="panda_hand"/><child link="panda_leftfinger"/>
    <origin rpy="0 0 0" xyz="0 0 0.0584"/><axis xyz="0 1 0"/>
    <limit effort="20" lower="0.0" upper="0.04" velocity="0.2"/>
  </joint>
  <joint name="panda_finger_joint2" type="prismatic">
    <parent link="panda_hand"/><child link="panda_rightfinger"/>
    <origin rpy="0 0 0" xyz="0 0 0.0584"/><axis xyz="0 -1 0"/>
    <limit effort="20" lower="0.0" upper="0.04" velocity="0.2"/>
    <mimic joint="panda_finger_joint1"/>
  </joint>
"""


@pytest.fixture(scope="module")
def panda_hand(tmp_path_factory):
    """The panda package copied, plus a URDF with hand and (mimicking) fingers."""
    pkg = tmp_path_factory.mktemp("pkgs") / "panda"
    shutil.copytree(PANDA_DIR, pkg)
    text = PANDA.read_text().replace('<link name="world"/>', HAND + '  <link name="world"/>')
    p = pkg / "urdf" / "panda_hand.urdf"
    p.write_text(text)
    return p


def test_import_panda_with_hand_fingers_locked(panda_hand):
    ms = import_urdf(panda_hand)
    mod = ms["panda"]
    assert mod.dof == 7
    assert {j.id: j.type for j in mod.joints}["panda_finger_joint1"] == "fixed"
    assert [c.body_id for c in mod.connectors if c.type == "eef"] == ["panda_hand"]
    robot = Robot.from_order(ms, ["panda"])
    full = pin.buildModelFromUrdf(str(panda_hand))
    assert full.nq == 9
    fingers = [full.getJointId("panda_finger_joint1"), full.getJointId("panda_finger_joint2")]
    ref = pin.buildReducedModel(full, fingers, pin.neutral(full))
    assert abs(sum(Y.mass for Y in ref.inertias) - robot.mass) < TOL
    assert abs(sum(Y.mass for Y in full.inertias) - robot.mass) < TOL
    _compare_with_reference(robot, ref, "panda", ["panda_link4", "panda_hand", "panda_leftfinger",
                                                   "panda_rightfinger"], "panda_hand", seed=1)
    assert robot.n_collision_geometries == _collision_count(full, panda_hand, [panda_hand.parents[2]]) == 11


def test_import_panda_fingers_and_mimic(panda_hand, tmp_path):
    with pytest.raises(InputError) as e:
        import_urdf(panda_hand, include_fingers=True)
    assert "mimic" in str(e.value) and "panda_finger_joint2" in str(e.value) and str(panda_hand) in str(e.value)
    # without the mimic tag both fingers are ordinary prismatic joints
    p = panda_hand.with_name("panda_free_fingers.urdf")
    p.write_text(panda_hand.read_text().replace('<mimic joint="panda_finger_joint1"/>', ""))
    ms = import_urdf(p, include_fingers=True, tcp_link="panda_leftfinger")
    robot = Robot.from_order(ms, ["panda"])
    assert robot.dof == 9
    ref = pin.buildModelFromUrdf(str(p))
    _compare_with_reference(robot, ref, "panda", ["panda_hand", "panda_rightfinger"], "panda_leftfinger", seed=2)


# =============================================================================================
# import: general joints (arbitrary axes, continuous, inertial rpy, primitives)
# =============================================================================================

GENERAL = """<?xml version="1.0"?>
<robot name="general">
  <link name="root">
    <inertial><origin xyz="0.01 0.02 0.03" rpy="0.4 -0.3 0.2"/><mass value="2.5"/>
      <inertia ixx="0.02" ixy="0.001" ixz="-0.002" iyy="0.03" iyz="0.003" izz="0.04"/></inertial>
    <collision><origin xyz="0 0 0.05" rpy="0 0 0.3"/><geometry><box size="0.2 0.1 0.1"/></geometry></collision>
  </link>
  <joint name="j_tilted" type="revolute">
    <parent link="root"/><child link="a"/>
    <origin xyz="0.1 0 0.2" rpy="0.1 0.2 0.3"/><axis xyz="3 4 0"/>
    <limit lower="-2" upper="1.5" effort="30" velocity="2"/>
    <dynamics damping="0.7" friction="0.2"/>
  </joint>
  <link name="a">
    <inertial><origin xyz="0 0.1 0" rpy="1.0 0.5 -0.5"/><mass value="1.2"/>
      <inertia ixx="0.01" ixy="0.0" ixz="0.0" iyy="0.02" iyz="0.0" izz="0.015"/></inertial>
    <collision><origin xyz="0 0.1 0" rpy="1.5707963267948966 0 0"/><geometry><cylinder radius="0.03" length="0.2"/></geometry></collision>
    <collision><origin xyz="0 0.2 0"/><geometry><sphere radius="0.04"/></geometry></collision>
  </link>
  <joint name="j_cont" type="continuous">
    <parent link="a"/><child link="b"/>
    <origin xyz="0 0.2 0" rpy="0 0 0"/><axis xyz="0 -1 0"/>
  </joint>
  <link name="b">
    <inertial><origin xyz="0.05 0 0"/><mass value="0.8"/>
      <inertia ixx="0.004" ixy="0.0" ixz="0.0" iyy="0.005" iyz="0.0" izz="0.006"/></inertial>
  </link>
  <joint name="j_slide" type="prismatic">
    <parent link="b"/><child link="c"/>
    <origin xyz="0.1 0 0" rpy="0 -0.4 0"/><axis xyz="0.36 0.48 0.8"/>
    <limit lower="-0.1" upper="0.3" effort="100" velocity="0.5"/>
  </joint>
  <link name="c">
    <inertial><origin xyz="0 0 0.05" rpy="0 0 0.7"/><mass value="0.5"/>
      <inertia ixx="0.001" ixy="0.0002" ixz="0.0" iyy="0.002" iyz="0.0" izz="0.0015"/></inertial>
  </link>
  <joint name="j_down" type="revolute">
    <parent link="c"/><child link="d"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 -1"/>
    <limit lower="-1" upper="1" effort="5" velocity="3"/>
  </joint>
  <link name="d">
    <inertial><mass value="0.3"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>
  </link>
  <joint name="to_tool" type="fixed">
    <parent link="d"/><child link="tool"/><origin xyz="0 0 0.05" rpy="0.2 0 0"/>
  </joint>
  <link name="tool"/>
  <joint name="side" type="fixed">
    <parent link="a"/><child link="side_link"/><origin xyz="0.05 0 0"/>
  </joint>
  <link name="side_link">
    <inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial>
  </link>
</robot>
"""


def test_import_general_joints_against_pinocchio(tmp_path):
    p = tmp_path / "general.urdf"
    p.write_text(GENERAL)
    ms = import_urdf(p)
    mod = ms["general"]
    assert {j.id: j.type for j in mod.joints} == {"j_tilted": "revolute", "j_cont": "revolute",
                                                   "j_slide": "prismatic", "j_down": "revolute",
                                                   "to_tool": "fixed", "side": "fixed"}
    jc = {j.id: j for j in mod.joints}["j_cont"]
    assert (jc.limits.lower, jc.limits.upper) == (-CONTINUOUS_LIMIT, CONTINUOUS_LIMIT)
    jt = {j.id: j for j in mod.joints}["j_tilted"]
    assert (jt.friction_viscous, jt.friction_coulomb) == (0.7, 0.2)
    # joint frame z = URDF axis (normalised, as URDF parsers do)
    R_origin = rpy_to_matrix(0.1, 0.2, 0.3)
    np.testing.assert_allclose(jt.pose_parent[:3, 2], R_origin @ [0.6, 0.8, 0.0], atol=1e-15)
    assert [c.body_id for c in mod.connectors if c.type == "eef"] == ["tool"]
    robot = Robot.from_order(ms, ["general"])
    assert robot.dof == 4
    ref = pin.buildModelFromUrdf(str(p))
    assert ref.nq == 5 and ref.nv == 4  # pinocchio: continuous = (cos, sin)
    assert abs(sum(Y.mass for Y in ref.inertias) - robot.mass) < TOL
    _compare_with_reference(robot, ref, "general", ["a", "b", "c", "d", "side_link"], "tool", seed=4)
    assert robot.n_collision_geometries == _collision_count(ref, p, [tmp_path]) == 3


# =============================================================================================
# bad input
# =============================================================================================

EVIL = """<?xml version="1.0"?>
<robot name="evil">
  <link name="base_link">
    <collision><geometry><mesh filename="{ref}"/></geometry></collision>
  </link>
</robot>
"""


def test_mesh_path_escaping_the_folder_is_rejected(tmp_path):
    d = tmp_path / "a" / "b"
    d.mkdir(parents=True)
    p = d / "evil.urdf"
    p.write_text(EVIL.format(ref="../../etc/passwd.stl"))
    with pytest.raises(InputError) as e:
        import_urdf(p)
    msg = str(e.value)
    assert str(p) in msg
    assert "link[base_link].collision[0].geometry.mesh.filename" in msg
    assert "../../etc/passwd.stl" in msg and "escapes" in msg
    assert e.value.file == str(p)


def test_absolute_mesh_path_is_rejected(tmp_path):
    p = tmp_path / "abs.urdf"
    p.write_text(EVIL.format(ref="/etc/passwd.stl"))
    with pytest.raises(InputError, match=r"absolute file paths are not allowed") as e:
        import_urdf(p)
    assert "link[base_link].collision[0].geometry.mesh.filename" in str(e.value)


def test_missing_collision_mesh_is_an_error(tmp_path):
    p = tmp_path / "missing.urdf"
    p.write_text(EVIL.format(ref="meshes/nope.stl"))
    with pytest.raises(InputError, match=r"mesh file not found") as e:
        import_urdf(p)
    assert str(p) in str(e.value)
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "nope.stl").write_text("not a mesh")
    with pytest.raises(InputError, match=r"link\[base_link\]\.collision\[0\]\.geometry\.mesh\.filename: "):
        import_urdf(p)


def test_malformed_xml(tmp_path):
    p = tmp_path / "broken.urdf"
    p.write_text('<robot name="x"><link name="a"></robot>')
    with pytest.raises(InputError, match="malformed XML") as e:
        import_urdf(p)
    assert str(p) in str(e.value) and e.value.file == str(p)


def test_unsupported_joint_and_bad_numbers(tmp_path):
    p = tmp_path / "float.urdf"
    p.write_text('<robot name="x"><link name="a"/><link name="b"/>'
                 '<joint name="f" type="floating"><parent link="a"/><child link="b"/></joint></robot>')
    with pytest.raises(InputError, match=r"joint\[f\]\.type: unsupported joint type 'floating'"):
        import_urdf(p)
    p.write_text('<robot name="x"><link name="a"/><link name="b"/>'
                 '<joint name="r" type="revolute"><parent link="a"/><child link="b"/>'
                 '<limit lower="abc" upper="1" effort="1" velocity="1"/></joint></robot>')
    with pytest.raises(InputError, match=r"joint\[r\]\.limit\.lower: expected a number, got 'abc'"):
        import_urdf(p)


def test_export_rejects_unknown_mesh_mode(tmp_path):
    robot = _robot("geometric_primitive_modules", ("base", "J2", "i_30", "J1", "l_15", "J2", "eef"), None)
    with pytest.raises(InputError, match="mesh_dir_mode"):
        export_urdf(robot, tmp_path / "x.urdf", mesh_dir_mode="relative")
