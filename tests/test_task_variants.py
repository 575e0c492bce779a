"""Every variant of the task format that the reference reads loads to the same Task as its canonical form;
unknown keys are warned about once; real defects are exit-2 errors naming file and JSON path; broken
collision meshes are errors, broken visual meshes warnings; published ``leave`` goals load, are judged and
solved. Variant files are built in tmp folders from ../shared/cobra/tasks (never copied into the repo)."""
import copy
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from robodesign import Robot, load_module_set
from robodesign.judge.checker import check
from robodesign.cli.entry import main
from robodesign.core.errors import InputError
from robodesign.formats.geometry import GeometrySpec, contains_point, load_mesh_arrays
from robodesign.formats.solution import parse_solution
from robodesign.formats.task_io import load_task
from robodesign.formats.task_spec import Leave

from conftest import IMPROV, ROOT, TASKS

ORDER = ["1", "21", "4", "22", "5", "23", "12"]


def source(name):
    if name == "timed_follow":  # robodesign's own task (a follow goal; the CoBRA samples have none)
        return json.loads((ROOT / "assets" / "tasks" / "robodesign" / "timed_follow.json").read_text())
    return json.loads((TASKS / "simple" / f"{name}.json").read_text())


def write_task(pkg: Path, data: dict, assets=True) -> Path:
    """<pkg>/<ID>.json, with <pkg>/assets linked to the CoBRA assets (as the published layout has it)."""
    f = pkg / f"{data['header']['ID']}.json"
    f.parent.mkdir(parents=True, exist_ok=True)
    if assets and not (pkg / "assets").exists():
        (pkg / "assets").symlink_to(TASKS / "assets", target_is_directory=True)
    f.write_text(json.dumps(data))
    return f


def load_variant(tmp_path, data, tag):
    return load_task(write_task(tmp_path / tag, data))


# ------------------------------------------------------------------------------------------------------
# typed comparison of two tasks
# ------------------------------------------------------------------------------------------------------
def geometry_key(g: GeometrySpec):
    return (g.kind, np.round(g.pose, 12).tolist(), tuple(g.size), str(g.file.resolve()) if g.file else None,
            tuple(g.scale))


def pose_key(tp):
    if tp is None:
        return None
    return (np.round(tp.nominal, 12).tolist(), [(p, tuple(np.round(iv, 12)), f) for p, iv, f in tp.entries],
            tp.is_unconstrained)


def constraint_key(c):
    d = {k: v for k, v in vars(c).items()}
    return (c.type, tuple(sorted((k, pose_key(v) if hasattr(v, "entries") else (sorted(v) if isinstance(v, frozenset)
                                                                               else v)) for k, v in d.items())))


def goal_key(g):
    out = [g.type, g.id, [constraint_key(c) for c in g.constraints]]
    for k, v in vars(g).items():
        if k in ("id", "constraints"):
            continue
        if hasattr(v, "entries"):
            v = pose_key(v)
        elif isinstance(v, tuple) and v and hasattr(v[0], "entries"):
            v = [pose_key(p) for p in v]
        elif isinstance(v, tuple) and v and isinstance(v[0], GeometrySpec):
            v = [geometry_key(x) for x in v]
        elif isinstance(v, np.ndarray):
            v = np.round(v, 12).tolist()
        out.append((k, v))
    return out


def task_key(t):
    h = t.header
    return {"header": (h.id, h.version, h.name, h.tags, h.date, h.time_step, h.gravity, h.author, h.email,
                       h.affiliation),
            "obstacles": [(o.id, o.name, [geometry_key(g) for g in o.collision], [geometry_key(g) for g in o.visual])
                          for o in t.obstacles],
            "goals": [goal_key(g) for g in t.goals],
            "constraints": [constraint_key(c) for c in t.constraints],
            "frames": {k: np.round(v, 12).tolist() for k, v in t.frames.items()}}


def assert_same_task(a, b):
    ka, kb = task_key(a), task_key(b)
    for part in ka:
        assert ka[part] == kb[part], part


# ------------------------------------------------------------------------------------------------------
# variants → the same Task
# ------------------------------------------------------------------------------------------------------
def _base_placement(d):
    return next(c for c in d["constraints"] if c["type"] == "basePlacement")


def v_name_null(d):
    d["obstacles"][0]["name"] = None


def c_name_null(d):
    del d["obstacles"][0]["name"]


def v_header_nulls(d):
    d["header"].update(taskName=None, date=None, tags=["unitTest", None, "PTP"], author="Matthias Mayer")


def c_header_nulls(d):
    del d["header"]["taskName"], d["header"]["date"]
    d["header"].update(tags=["unitTest", "PTP"], author=["Matthias Mayer"])


def v_header_numbers(d):
    d["header"].update(version=2022, taskName=7)


def c_header_numbers(d):
    d["header"].update(version="2022", taskName="7")


def v_frame_key(d):
    _base_placement(d)["pose"].update(toleranceProjection=["x", "z", "N_z"], tolerance=[[-1, 1], [0, 0.5], [-3, 3]],
                                      frame=["nominal", "world", "world"])


def c_frame_key(d):
    _base_placement(d)["pose"].update(toleranceProjection=["x", "z", "N_z"], tolerance=[[-1, 1], [0, 0.5], [-3, 3]],
                                      toleranceFrame=["nominal", "world", "world"])


def v_obstacle_pose_tolerated(d):
    o = d["obstacles"][0]
    o["pose"] = {"nominal": o["pose"], "toleranceProjection": [], "tolerance": []}
    o["acknowledgement"] = "someone on GrabCAD"


def v_goal_key_case(d):
    g = d["goals"][0]
    g["GoalPose"] = g.pop("goalPose")
    g["Type"] = g.pop("type").capitalize()


def v_theta_signed(d):
    d["goals"][0]["goalPose"]["tolerance"][1] = [-0.2, 0.05]   # |θ| ≤ 0.2


def c_theta_signed(d):
    d["goals"][0]["goalPose"]["tolerance"][1] = [0.0, 0.2]


def v_empty_constraint(d):
    d["constraints"].append({})


def c_empty_constraint(d):
    d["constraints"].append({"type": "alwaysTrue"})


def v_geometry_case_and_params(d):
    d["obstacles"].append({"ID": "table", "collision": {"type": "BOX", "parameters": {"x": 1, "y": 2, "z": 0.1,
                                                                                        "color": "grey"}}})


def c_geometry_case_and_params(d):
    d["obstacles"].append({"ID": "table", "collision": {"type": "box", "parameters": {"x": 1, "y": 2, "z": 0.1}}})


def v_package_prefix(d):
    p = d["obstacles"][0]["collision"][0]["parameters"]
    p["file"] = "package://" + p["file"]


def v_leave_lists(d):
    d["goals"].append({"ID": "out", "type": "Leave", "duration": 0.1,
                       "occupiedSpace": {"type": "sphere", "parameters": {"r": 0.2}, "pose": np.eye(4).tolist()}})


def c_leave_lists(d):
    d["goals"].append({"ID": "out", "type": "leave", "duration": 0.1,
                       "occupiedSpace": [{"type": "sphere", "parameters": {"r": 0.2}, "pose": np.eye(4).tolist()}]})


def v_end_effector_extra(d):
    d["goals"][0]["constraints"] = [{"type": "endEffector", "v_max": 0.5, "comment": "slow"}, {}]


def c_end_effector_extra(d):
    d["goals"][0]["constraints"] = [{"type": "endEffector", "v_max": 0.5}, {"type": "alwaysTrue"}]


def v_follow_trajectory(d):
    traj = next(g for g in d["goals"] if g["type"] == "follow")["trajectory"]
    traj.update(t=[0.4], goal2time={})   # as the reference's Trajectory writes a timed pose trajectory


def nothing(d):
    pass


VARIANTS = {
    "obstacle name null": ("PTP_2", v_name_null, c_name_null),
    "header nulls, string author": ("PTP_3", v_header_nulls, c_header_nulls),
    "header numbers where strings are expected": ("PTP_2", v_header_numbers, c_header_numbers),
    "frame = toleranceFrame": ("PTP_2", v_frame_key, c_frame_key),
    "obstacle pose as tolerated pose + acknowledgement": ("PTP_2", v_obstacle_pose_tolerated, nothing),
    "goal keys in any case": ("PTP_3", v_goal_key_case, nothing),
    "signed Theta_R bounds": ("PTP_2", v_theta_signed, c_theta_signed),
    "{} constraint": ("PTP_1", v_empty_constraint, c_empty_constraint),
    "geometry type case, ignored parameter": ("Empty", v_geometry_case_and_params, c_geometry_case_and_params),
    "package:// mesh path": ("PTP_2", v_package_prefix, nothing),
    "leave goal: single geometry, type case": ("PTP_1", v_leave_lists, c_leave_lists),
    "ignored endEffector key, {} goal constraint": ("PTP_3", v_end_effector_extra, c_end_effector_extra),
    "follow trajectory: goal2time {}, t = [step]": ("timed_follow", v_follow_trajectory, nothing),
}


@pytest.mark.parametrize("name", list(VARIANTS))
def test_variant_loads_to_the_same_task_as_its_canonical_form(tmp_path, name):
    src, variant, canonical = VARIANTS[name]
    dv, dc = source(src), source(src)
    variant(dv)
    canonical(dc)
    tv, tc = load_variant(tmp_path, dv, "v"), load_variant(tmp_path, dc, "c")
    assert_same_task(tv, tc)
    # and the variant differs from the untouched source where it should (the test is not vacuous)
    if canonical is not nothing:
        assert task_key(tc) != task_key(load_variant(tmp_path, source(src), "s"))


def test_frame_key_has_the_meaning_of_tolerance_frame(tmp_path):
    """A base pose rotated 90° about z; x ∈ [0, 0.1] in the *world* frame (written as "frame"): a base
    moved 5 cm along world −x is invalid — it would be valid in the nominal frame, whose x is world y."""
    d = source("PTP_2")
    bp = _base_placement(d)["pose"]
    bp.update(nominal=[[0, -1, 0, 0], [1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], toleranceProjection=["x"],
              tolerance=[[0, 0.1]], frame=["world"])
    tp = load_variant(tmp_path, d, "f").base_placement
    bp["frame"] = ["nominal"]
    tp_nominal = load_variant(tmp_path, d, "n").base_placement
    n = np.array(bp["nominal"], dtype=float)
    plus_x, minus_x = n.copy(), n.copy()
    plus_x[0, 3] += 0.05
    minus_x[0, 3] -= 0.05
    assert tp.frames == ("world",) and tp_nominal.frames == ("nominal",)
    assert tp.valid(plus_x) and not tp.valid(minus_x)
    assert tp_nominal.valid(minus_x) and tp_nominal.valid(plus_x)


def test_signed_theta_r_bounds_allow_the_absolute_angle(tmp_path):
    from robodesign.core.spatial import homogeneous, rot_z
    d = source("PTP_2")
    d["goals"][0]["goalPose"]["tolerance"][1] = [-0.1, 0.05]
    tp = load_variant(tmp_path, d, "t").goals[0].pose
    n = tp.nominal
    assert tp.intervals[1] == (0.0, 0.1)
    assert tp.valid(n @ homogeneous(rot_z(0.09)))          # 0.09 rad about any axis: inside |θ| ≤ 0.1
    assert tp.valid(n @ homogeneous(rot_z(-0.09)))
    assert not tp.valid(n @ homogeneous(rot_z(0.11)))


def test_mesh_names_with_spaces_and_ply_meshes(tmp_path):
    """The same machine mesh as 'DMU 125P compress.stl' (a name with spaces) and as a .ply file: the
    collision geometry has the same vertices and triangles as the original STL."""
    import trimesh
    pkg = tmp_path / "pkg"
    (pkg / "meshes").mkdir(parents=True)
    stl = TASKS / "assets" / "DMU_125P_compress.stl"
    shutil.copy(stl, pkg / "meshes" / "DMU 125P compress.stl")
    trimesh.load(str(stl), force="mesh", process=False).export(str(pkg / "meshes" / "dmu.ply"))
    ref = load_mesh_arrays(str(stl), (0.001,) * 3)[0]
    for fname in ("meshes/DMU 125P compress.stl", "meshes/dmu.ply"):
        d = source("PTP_2")
        d["obstacles"][0]["collision"][0]["parameters"]["file"] = fname
        del d["obstacles"][0]["visual"]
        t = load_task(write_task(pkg, d, assets=False))
        g = t.obstacles[0].collision[0]
        assert g.file.name == Path(fname).name
        v, f = load_mesh_arrays(str(g.file), g.scale)[0]
        assert len(f) == len(ref[1]) > 1000
        np.testing.assert_allclose(v[f], ref[0][ref[1]], atol=1e-9)


# ------------------------------------------------------------------------------------------------------
# warnings: once
# ------------------------------------------------------------------------------------------------------
def test_unknown_keys_are_dropped_and_warned_once(tmp_path, capsys):
    d = source("PTP_2")
    for i in range(3):
        d["obstacles"].append({"ID": f"box{i}", "comment": "from CAD", "collision": {"type": "box", "parameters": {
            "x": 0.1, "y": 0.1, "z": 0.1}, "pose": [[1, 0, 0, 3 + i], [0, 1, 0, 3], [0, 0, 1, 0], [0, 0, 0, 1]]}})
    for g in d["goals"]:
        g["difficulty"] = "easy"
        g["goalPose"]["tolerances"] = []
    f = write_task(tmp_path / "w", d)
    t = load_task(f)
    ours = [w for w in t.warnings if "unknown key" in w]
    assert ours == [
        "PTP_2.json: obstacles[1].comment: unknown key 'comment' ignored (and at 2 more places like it)",
        "PTP_2.json: goals[0].difficulty: unknown key 'difficulty' ignored (and at 2 more places like it)",
        "PTP_2.json: goals[0].goalPose.tolerances: unknown key 'tolerances' ignored (did you mean 'tolerance'?) "
        "(and at 2 more places like it)"]
    assert len(t.obstacles) == 4 and not hasattr(t.obstacles[1], "comment")
    # the CLI shows each once, then judges as usual
    sol = tmp_path / "none.json"
    code = main(["check", str(f), str(sol), "--modules", str(IMPROV)])
    err = capsys.readouterr().err
    assert code == 2 and "none.json: file not found" in err  # the solution is read after the task's warnings
    assert err.count("unknown key 'comment'") == 1 and err.count("unknown key 'difficulty'") == 1


def test_shared_tasks_load_as_before():
    """All published sample tasks load without new warnings: PTP_2 names a visual mesh that is not shipped."""
    for f in sorted((TASKS / "simple").glob("*.json")):
        t = load_task(f)
        if f.stem == "PTP_2":
            assert len(t.warnings) == 1 and "visual[0].parameters.file: mesh file not found: 'assets/DMU_125P.stl'" \
                in t.warnings[0]
            assert t.obstacles[0].visual == () and len(t.obstacles[0].collision) == 1
        else:
            assert t.warnings == ()


# ------------------------------------------------------------------------------------------------------
# real defects: exit 2, file and JSON path named
# ------------------------------------------------------------------------------------------------------
def _nonrigid(d):
    d["goals"][0]["goalPose"]["nominal"][0][0] = 2


def _inverted(d):
    d["goals"][0]["goalPose"]["tolerance"][0] = [0.02, 0.01]


def _escape(d):
    d["obstacles"][0]["collision"][0]["parameters"]["file"] = "package://../../etc/passwd"


def _conflict(d):
    _base_placement(d)["pose"].update(toleranceProjection=["x"], tolerance=[[0, 1]], frame=["world"],
                                      toleranceFrame=["nominal"])


def _leave_nothing(d):
    d["goals"].append({"ID": "out", "type": "leave", "duration": 0.1})


def _goal_key_twice(d):
    d["goals"][0]["goalpose"] = d["goals"][0]["goalPose"]


def _bad_box(d):
    d["goals"].append({"ID": "out", "type": "leave", "occupiedSpace": [{"type": "box", "parameters": {"x": 1, "y": -1,
                                                                                                     "z": 1}}]})


ERRORS = [
    (_nonrigid, "PTP_2.json: goals[0].goalPose.nominal"),
    (_inverted, "PTP_2.json: goals[0].goalPose.tolerance[0]: lower bound 0.02 is greater than upper bound 0.01"),
    (_escape, "PTP_2.json: obstacles[0].collision[0].parameters.file: file reference 'package://../../etc/passwd' "
              "escapes its folder"),
    (_conflict, "PTP_2.json: constraints[4].pose.toleranceFrame: 'frame' and 'toleranceFrame' are both given, with "
                "different frames"),
    (_leave_nothing, "PTP_2.json: goals[3]: a leave goal needs 'occupiedSpace'"),
    (_goal_key_twice, "PTP_2.json: goals[0].goalpose: 'goalpose' is given twice"),
    (_bad_box, "PTP_2.json: goals[3].occupiedSpace[0].parameters.y"),
]


@pytest.mark.parametrize("mutate, message", ERRORS, ids=[m.__name__ for m, _ in ERRORS])
def test_malformed_tasks_exit_2_naming_file_and_path(tmp_path, capsys, mutate, message):
    d = source("PTP_2")
    mutate(d)
    f = write_task(tmp_path / "e", d)
    code = main(["check", str(f), str(tmp_path / "sol.json"), "--modules", str(IMPROV)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and message in err[0], err


def test_nan_in_a_task_is_exit_2(tmp_path, capsys):
    f = write_task(tmp_path / "n", source("PTP_1"))
    f.write_text(f.read_text().replace('"timeStepSize": 0.01', '"timeStepSize": NaN'))
    assert main(["check", str(f), str(tmp_path / "sol.json")]) == 2
    assert "PTP_1.json: header.timeStepSize: NaN is not a valid value" in capsys.readouterr().err


# ------------------------------------------------------------------------------------------------------
# broken meshes (issue 13): collision → exit 2, visual → warning
# ------------------------------------------------------------------------------------------------------
def _broken_meshes(folder: Path):
    folder.mkdir(parents=True, exist_ok=True)
    stl = (TASKS / "assets" / "QUASER_MV205_v3_compressed.stl").read_bytes()
    files = {"empty.stl": b"",
             "lfs.stl": b"version https://git-lfs.github.com/spec/v1\noid sha256:4d7a\nsize 160062\n",
             "truncated.stl": stl[:120],
             "flat.stl": b"solid f\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 2 0 0\n"
                         b"endloop\nendfacet\nendsolid f\n"}
    for name, data in files.items():
        (folder / name).write_bytes(data)
    return {"empty.stl": "is empty (0 bytes)", "lfs.stl": "is a Git LFS pointer",
            "truncated.stl": "has no triangles (truncated or not a mesh?)", "flat.stl": "is degenerate"}


@pytest.mark.parametrize("name", ["empty.stl", "lfs.stl", "truncated.stl", "flat.stl"])
def test_broken_collision_mesh_in_a_task_is_exit_2(tmp_path, capsys, name):
    pkg = tmp_path / "pkg"
    expected = _broken_meshes(pkg / "bad")
    d = source("PTP_2")
    d["obstacles"][0]["collision"][0]["parameters"]["file"] = f"bad/{name}"
    f = write_task(pkg, d, assets=False)
    code = main(["check", str(f), str(tmp_path / "sol.json"), "--modules", str(IMPROV)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert err.startswith(f"robodesign: error: PTP_2.json: obstacles[0].collision[0].parameters.file: "
                          f"collision mesh file 'bad/{name}' {expected[name]}") or \
        (f"PTP_2.json: obstacles[0].collision[0].parameters.file: collision mesh file 'bad/{name}' "
         f"{expected[name]}") in err, err


@pytest.mark.parametrize("name", ["empty.stl", "lfs.stl", "truncated.stl"])
def test_broken_collision_mesh_in_a_module_set_is_exit_2(tmp_path, capsys, name):
    ms_dir = tmp_path / "IMPROV"
    ms_dir.mkdir()
    (ms_dir / "STLfiles").symlink_to(IMPROV / "STLfiles", target_is_directory=True)
    expected = _broken_meshes(ms_dir / "bad")
    data = json.loads((IMPROV / "modules.json").read_text())
    body = data["modules"][2]["bodies"][0]  # module "12", the last of ORDER
    col = body["collision"] if isinstance(body["collision"], list) else [body["collision"]]
    col[0]["parameters"]["file"] = f"bad/{name}"
    body["collision"] = col
    (ms_dir / "modules.json").write_text(json.dumps(data))
    code = main(["robot", str(ms_dir), "--order", ",".join(ORDER)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert (f"IMPROV/modules.json: modules[2].bodies[0].collision[0].parameters.file: collision mesh file "
            f"'bad/{name}' {expected[name]}") in err, err


def test_missing_or_empty_visual_mesh_is_only_a_warning(tmp_path, capsys):
    pkg = tmp_path / "pkg"
    _broken_meshes(pkg / "bad")
    d = source("PTP_2")
    d["obstacles"][0]["visual"] = [dict(d["obstacles"][0]["visual"][0], parameters={"file": "bad/empty.stl"}),
                                   dict(d["obstacles"][0]["visual"][0], parameters={"file": "bad/missing.stl"})]
    d["obstacles"][0]["collision"][0]["parameters"]["file"] = "assets/DMU_125P_compress.stl"
    (pkg / "assets").symlink_to(TASKS / "assets", target_is_directory=True)
    t = load_task(write_task(pkg, d, assets=False))
    assert t.obstacles[0].visual == () and len(t.obstacles[0].collision) == 1
    assert t.warnings == (
        "PTP_2.json: obstacles[0].visual[0].parameters.file: visual mesh file 'bad/empty.stl' is empty (0 bytes); "
        "the visual is skipped",
        f"PTP_2.json: obstacles[0].visual[1].parameters.file: mesh file not found: 'bad/missing.stl' "
        f"(looked at {pkg / 'bad' / 'missing.stl'}); the visual is skipped")


# ------------------------------------------------------------------------------------------------------
# leave goals with occupiedSpace: point-in-geometry, the judge, the solver
# ------------------------------------------------------------------------------------------------------
def test_contains_point_matches_analytic_shapes(tmp_path):
    """Boxes, cylinders and spheres against their formulas; a closed STL box mesh against the primitive."""
    import trimesh
    from robodesign.core.spatial import homogeneous, rot_x, rot_z
    rng = np.random.default_rng(3)
    pose = homogeneous(rot_z(0.7) @ rot_x(0.3), (0.2, -0.1, 0.5))
    box = GeometrySpec("box", pose, (0.4, 0.2, 0.6))
    cyl = GeometrySpec("cylinder", pose, (0.15, 0.5))
    sph = GeometrySpec("sphere", pose, (0.25,))
    trimesh.creation.box(extents=(0.4, 0.2, 0.6)).export(str(tmp_path / "box.stl"))
    mesh = GeometrySpec("mesh", pose, (), tmp_path / "box.stl", (1.0, 1.0, 1.0))
    pts = pose[:3, 3] + rng.uniform(-0.4, 0.4, size=(400, 3))
    inside = {"box": 0, "mesh": 0}
    for p in pts:
        local = np.linalg.solve(pose, np.append(p, 1))[:3]
        in_box = bool(np.all(np.abs(local) <= [0.2, 0.1, 0.3]))
        assert contains_point(box, p) == in_box
        assert contains_point(mesh, p) == in_box
        assert contains_point(cyl, p) == bool(math.hypot(local[0], local[1]) <= 0.15 and abs(local[2]) <= 0.25)
        assert contains_point(sph, p) == bool(np.linalg.norm(local) <= 0.25)
        inside["box"] += in_box
    assert 10 < inside["box"] < 390  # both outcomes are exercised


@pytest.fixture(scope="module")
def improv():
    return load_module_set(IMPROV)


def _leave_task_and_solution(tmp_path, improv, box_center, duration=0.1, q_at=None):
    """A robot at rest at q0 for 1 s, leave goal at t = 0.5 s; the box to leave is 0.2 m wide around
    ``box_center``. ``q_at`` = {sample: q} overrides single samples."""
    d = {"header": {"ID": "leave_probe"}, "obstacles": [], "constraints": [{"type": "allGoalsFulfilled"}],
         "goals": [{"ID": "away", "type": "leave", "duration": duration,
                    "occupiedSpace": [{"type": "box", "parameters": {"x": 0.2, "y": 0.2, "z": 0.2},
                                       "pose": [[1, 0, 0, box_center[0]], [0, 1, 0, box_center[1]],
                                                [0, 0, 1, box_center[2]], [0, 0, 0, 1]]}]}]}
    task = load_task(write_task(tmp_path, d, assets=False))
    q0 = np.array([0.0, 0.5, 0.0, 1.0, 0.0, 0.5])
    q = np.tile(q0, (101, 1))
    for k, qk in (q_at or {}).items():
        q[k] = qk
    sol = parse_solution({"taskID": "leave_probe", "costFunction": "cyc", "moduleSet": "IMPROV",
                          "moduleOrder": ORDER, "basePose": [np.eye(4).tolist()],
                          "trajectory": {"t": 0.01, "q": q.tolist(), "dq": np.zeros_like(q).tolist(),
                                         "ddq": np.zeros_like(q).tolist(), "goal2time": {"away": 0.5}}}, "sol.json")
    return task, sol, q0


def test_leave_goal_judged_on_hand_built_trajectories(tmp_path, improv):
    robot = Robot.from_order(improv, ORDER)
    q0 = np.array([0.0, 0.5, 0.0, 1.0, 0.0, 0.5])
    tcp = robot.fk(q0)[:3, 3]
    # TCP inside the box at the goal time → violation
    task, sol, _ = _leave_task_and_solution(tmp_path / "a", improv, tcp + [0.05, 0, 0])
    assert isinstance(task.goals[0], Leave) and task.goals[0].region is None
    v = check(task, sol, improv)
    assert v.goals == {"away": False} and not v.valid
    msg = [x for x in v.violations if x.goal == "away"]
    assert msg[0].sample == 50 and "inside the region to leave at 11 samples" in msg[0].message
    # box 0.3 m away → achieved
    task, sol, _ = _leave_task_and_solution(tmp_path / "b", improv, tcp + [0.3, 0, 0])
    v = check(task, sol, improv)
    assert v.goals == {"away": True} and v.valid
    # outside at t_g, but back inside 0.05 s later (within the 0.1 s duration) → violation at that sample
    q1 = q0 + np.array([0, -0.3, 0, -0.3, 0, 0])   # a configuration whose TCP is elsewhere
    box_at = robot.fk(q1)[:3, 3]
    assert np.abs(box_at - tcp).max() > 0.15
    task, sol, _ = _leave_task_and_solution(tmp_path / "d", improv, box_at, q_at={55: q1})
    v = check(task, sol, improv)
    assert v.goals == {"away": False}
    assert [x.sample for x in v.violations if x.goal == "away"] == [55]
    # … and inside only after the window (t = 0.65 s > 0.5 + 0.1 s) → achieved
    task, sol, _ = _leave_task_and_solution(tmp_path / "e", improv, box_at, q_at={65: q1})
    assert check(task, sol, improv).goals == {"away": True}


def _inside_box(p, center, size):
    return bool(np.all(np.abs(np.asarray(p) - center) <= np.asarray(size) / 2))


@pytest.mark.slow
def test_published_leave_task_is_solved_and_checked(tmp_path, improv):
    """The reference's sample task PTP_leave (occupiedSpace box, as published): solve → check VALID, and the
    TCP is outside the box at the leave goal's time (independent box test)."""
    from robodesign.design.solve import SolveSettings, solve
    d = source("PTP_2")
    d["header"]["ID"] = "simple/PTP_leave"
    d["obstacles"][0]["pose"] = [[1, 0, 0, -4.5], [0, 1, 0, 0.25], [0, 0, 1, -1], [0, 0, 0, 1]]
    for g in ("collision", "visual"):
        d["obstacles"][0][g][0]["pose"] = d["obstacles"][0]["pose"]
    d["obstacles"][0]["collision"][0]["parameters"]["file"] = "assets/QUASER_MV205_v3_compressed.stl"
    d["obstacles"][0]["visual"][0]["parameters"]["file"] = "assets/QUASER_MV205_v3.stl"
    d["constraints"] = [{"type": "joint", "parts": ["q", "tau"]}, {"type": "selfCollisionFree"},
                        {"type": "collisionFree"}, {"type": "allGoalsFulfilled"},
                        {"type": "allGoalsFulfilledInOrder", "order": ["1", "2"]},
                        {"type": "basePlacement", "pose": {"nominal": np.eye(4).tolist()}}]
    tol = {"toleranceProjection": ["r_sph", "Theta_R"], "tolerance": [[0.0, 0.01], [-0.01, 0.01]]}
    d["goals"] = [
        {"ID": "1", "type": "reach", "goalPose": dict(tol, nominal=[[-1, 0, 0, -0.4], [0, 1, 0, 0], [0, 0, -1, 0.25],
                                                                   [0, 0, 0, 1]])},
        {"ID": "2", "type": "reach", "goalPose": dict(tol, nominal=[[-1, 0, 0, 0], [0, 1, 0, 0.5], [0, 0, -1, 0.25],
                                                                   [0, 0, 0, 1]])},
        {"ID": "3", "type": "leave", "duration": 0.01, "occupiedSpace": [
            {"type": "box", "parameters": {"x": 2.5, "y": 1.0, "z": 1.5},
             "pose": [[1, 0, 0, -0.25], [0, 1, 0, 0.75], [0, 0, 1, 0.9], [0, 0, 0, 1]]}]}]
    task = load_task(write_task(tmp_path, d))
    # (an IK solution that touches itself by a few µm at goal 2 can make planning out of it fail: next seed)
    res = next(r for r in (solve(task, improv, ORDER, settings=SolveSettings(seed=s)) for s in range(4)) if r.feasible)
    v = check(task, res.solution, improv)
    assert v.valid and v.goals == {"1": True, "2": True, "3": True}
    tr = res.solution.trajectory
    robot = Robot.from_order(improv, ORDER)
    center, size = np.array([-0.25, 0.75, 0.9]), np.array([2.5, 1.0, 1.5])
    k2 = int(np.argmin(np.abs(tr.t - tr.goal2time["2"])))
    k3 = int(np.argmin(np.abs(tr.t - tr.goal2time["3"])))
    assert _inside_box(robot.fk(tr.q[k2])[:3, 3], center, size)        # goal 2 lies inside the space …
    assert not _inside_box(robot.fk(tr.q[k3])[:3, 3], center, size)    # … which the TCP has left at goal 3
    assert tr.goal2time["3"] > tr.goal2time["2"]
    # the same solution with the TCP put back at goal 2's configuration at goal 3's time fails
    q = tr.q.copy()
    q[k3] = tr.q[k2]
    bad = parse_solution(copy.deepcopy(res.solution.to_json()) | {"trajectory": {
        "t": tr.t.tolist(), "q": q.tolist(), "dq": tr.dq.tolist(), "ddq": tr.ddq.tolist(),
        "goal2time": tr.goal2time}}, "bad.json")
    assert check(task, bad, improv).goals["3"] is False


def test_direct_api_stays_strict_about_unknown_tolerance_keys():
    from robodesign.formats.tolerance import ToleratedPose
    with pytest.raises(InputError, match=r"unknown key 'frames'"):
        ToleratedPose.from_json({"nominal": np.eye(4).tolist(), "frames": []}, "x.json", ["p"])


def test_null_optional_strings_in_a_solution_mean_absent():
    base = {"taskID": "simple/PTP_1", "costFunction": "cyc", "moduleSet": "IMPROV", "moduleOrder": ORDER,
            "trajectory": {"t": 0.01, "q": [[0.0] * 6] * 3, "goal2time": {}}}
    plain = parse_solution(base, "s.json")
    nulls = parse_solution(dict(base, notes=None, publication=None, processorName=None, computationTime=None,
                                author=["A. Author", None], tags=None), "s.json")
    fields = ("notes", "publication", "processor_name", "computation_time", "tags")
    assert [getattr(nulls, f) for f in fields] == [getattr(plain, f) for f in fields] == ["", "", "", -1.0, ()]
    assert nulls.author == ("A. Author",)


def test_module_set_variants_build_the_same_robot(tmp_path):
    """Joint and limit keys in any case, null optional header strings, geometry type case and ignored geometry
    parameters (warned once): the same robot as the canonical IMPROV set."""
    data = json.loads((IMPROV / "modules.json").read_text())
    var = copy.deepcopy(data)
    for m in var["modules"]:
        m["header"].update(author=None, email=[None, "x@y.z"])
        for j in m.get("joints") or []:
            j["PoseParent"] = j.pop("poseParent")
            j["LIMITS"] = {k.upper(): v for k, v in j.pop("limits").items()}
        for b in m["bodies"]:
            for g in b.get("collision") or []:
                g["type"] = g["type"].upper()
                g["parameters"]["material"] = "steel"
    sets = {}
    for tag, d in (("canonical", data), ("variant", var)):
        folder = tmp_path / tag / "IMPROV"
        folder.mkdir(parents=True)
        (folder / "STLfiles").symlink_to(IMPROV / "STLfiles", target_is_directory=True)
        (folder / "modules.json").write_text(json.dumps(d))
        sets[tag] = load_module_set(folder, use_cache=False)
    assert sets["canonical"].warnings == ()
    assert len(sets["variant"].warnings) == 1 and "parameters.material: unknown key 'material' ignored (and at " \
        in sets["variant"].warnings[0]
    assert sets["variant"]["12"].header.email == ("x@y.z",) and sets["variant"]["12"].header.author == ()
    a, b = (Robot.from_order(sets[k], ORDER) for k in ("canonical", "variant"))
    q = np.array([0.3, -0.4, 0.5, 0.2, -0.7, 0.1])
    np.testing.assert_array_equal(a.fk(q), b.fk(q))
    np.testing.assert_array_equal(a.q_upper, b.q_upper)
    np.testing.assert_array_equal(a.tau_max, b.tau_max)
    np.testing.assert_array_equal(a.gravity_torque(q), b.gravity_torque(q))
    assert a.in_collision(q) == b.in_collision(q) and a.min_distances(q) == b.min_distances(q)


def test_website_rejects_broken_collision_meshes_and_warns_about_visual_ones(tmp_path):
    pytest.importorskip("fastapi")
    from fastapi.testclient import TestClient
    from robodesign.web import create_app
    lfs = b"version https://git-lfs.github.com/spec/v1\noid sha256:4d7a\nsize 160062\n"
    stl = (TASKS / "assets" / "QUASER_MV205_v3_compressed.stl").read_bytes()

    def task(tid, visual=None):
        ob = {"ID": "cnc", "collision": {"type": "mesh", "parameters": {"file": "assets/cnc.stl", "scale": 0.001}},
              "cad": "vendor X"}
        if visual:
            ob["visual"] = {"type": "mesh", "parameters": {"file": visual, "scale": 0.001}}
        return json.dumps({"header": {"ID": tid}, "obstacles": [ob], "goals": []})

    app = create_app(data_dir=tmp_path / "data", seed=[], seed_builtin=False, open_registration=True)
    with TestClient(app) as c:
        r = c.post("/api/tasks", files=[("task", ("a.json", task("up/lfs"))), ("files", ("assets/cnc.stl", lfs))])
        assert r.status_code == 400
        assert ("obstacles[0].collision.parameters.file: collision mesh file 'assets/cnc.stl' is a Git LFS "
                "pointer") in r.json()["detail"]
        r = c.post("/api/tasks", files=[("task", ("b.json", task("up/ok", visual="assets/look.stl"))),
                                        ("files", ("assets/cnc.stl", stl)), ("files", ("assets/look.stl", lfs))])
        assert r.status_code == 201, r.text
        (created,) = r.json()["tasks"]
        assert any("visual.parameters.file: visual mesh file 'assets/look.stl' is a Git LFS pointer" in w
                   for w in created["warnings"])
        assert "ok.json: obstacles[0].cad: unknown key 'cad' ignored" in created["warnings"]  # named by its ID


def test_broken_collision_mesh_in_a_urdf_is_exit_2(tmp_path, capsys):
    """A URDF is a one-module set: an LFS pointer as a collision mesh is exit 2, as a visual mesh a warning."""
    (tmp_path / "lfs.stl").write_bytes(b"version https://git-lfs.github.com/spec/v1\noid sha256:1\nsize 9\n")
    shutil.copy(TASKS / "assets" / "QUASER_MV205_v3_compressed.stl", tmp_path / "ok.stl")

    def urdf(col, vis):
        return f"""<robot name="r"><link name="base">
          <collision><geometry><mesh filename="{col}"/></geometry></collision>
          <visual><geometry><mesh filename="{vis}"/></geometry></visual></link>
          <link name="tool"/><joint name="j" type="revolute"><parent link="base"/><child link="tool"/>
          <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="10" velocity="1"/></joint></robot>"""
    (tmp_path / "bad.urdf").write_text(urdf("lfs.stl", "ok.stl"))
    assert main(["robot", str(tmp_path / "bad.urdf"), "--order", "bad"]) == 2
    err = capsys.readouterr().err
    assert "collision mesh file 'lfs.stl' is a Git LFS pointer" in err and len(err.strip().splitlines()) == 1
    (tmp_path / "vis.urdf").write_text(urdf("ok.stl", "lfs.stl"))
    from robodesign.formats.urdf import import_urdf
    warnings = []
    ms = import_urdf(tmp_path / "vis.urdf", warnings=warnings)
    assert len(warnings) == 1 and "visual mesh file 'lfs.stl' is a Git LFS pointer" in warnings[0]
    (body,) = [b for m in ms for b in m.bodies if b.collision]
    assert body.visual == () or all(g.file.name != "lfs.stl" for g in body.visual)


def test_viewer_shows_the_space_to_leave(tmp_path):
    from robodesign.viewer.scene import build_scene
    d = source("PTP_1")
    box_pose = [[1, 0, 0, -0.25], [0, 1, 0, 0.75], [0, 0, 1, 0.9], [0, 0, 0, 1]]
    d["goals"].append({"ID": "out", "type": "leave", "duration": 0.01, "occupiedSpace": [
        {"type": "box", "parameters": {"x": 2.5, "y": 1.0, "z": 1.5}, "pose": box_pose}]})
    scene = build_scene(load_task(write_task(tmp_path, d, assets=False)))
    (node,) = [n for n in scene["nodes"] if n["id"] == "goal/out"]
    (geom,) = node["geometries"]
    assert geom["type"] == "box" and geom["size"] == [2.5, 1.0, 1.5] and geom["role"] == "tolerance"
    np.testing.assert_allclose(np.asarray(node["pose"]).reshape(4, 4) @ np.asarray(geom["pose"]).reshape(4, 4),
                               box_pose, atol=1e-12)


def test_a_task_file_not_at_its_id_path_warns_where_meshes_resolve(tmp_path):
    d = source("PTP_2")
    pkg = tmp_path / "pkg"
    write_task(pkg, d)                                   # pkg/simple/PTP_2.json: at its ID path
    renamed = pkg / "simple" / "my copy.json"
    renamed.write_text(json.dumps(d))
    assert not any("header.ID" in w for w in load_task(pkg / "simple" / "PTP_2.json").warnings)
    t = load_task(renamed)
    assert t.root == pkg.resolve() and len(t.obstacles[0].collision) == 1
    assert f"my copy.json: header.ID: the file is not at <package>/simple/PTP_2.json, so mesh paths resolve " \
           f"against {pkg.resolve()}" in t.warnings[0]
