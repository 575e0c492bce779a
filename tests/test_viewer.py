"""The viewer: scene data, the self-contained HTML page, the plots and ``robodesign view``.

The robot is the built-in arm with the STL gripper (module 13); the task is written here: a box
obstacle and two obstacles sharing one STL file (a dense sphere that must be decimated), an ``at``
goal with an ``r_sph`` tolerance and a ``reach`` goal with an x/y/z box in world axes.
"""
import json
import re

import numpy as np
import pytest

from robodesign import Robot, load_module_set
from robodesign.cli.entry import main as cli_main
from robodesign.core.trajectory import Trajectory
from robodesign.formats.solution import Solution, load_solution
from robodesign.formats.task_io import load_task
from robodesign.viewer import build_scene, render_html, solution_page, trajectory_plots
from robodesign.viewer.html import asset, decode_page_data
from robodesign.viewer.meshes import MAX_TRIANGLES, decimate, decode_b64, mesh_entry, weld
from robodesign.viewer.scene import animation_samples

ORDER = ("1", "21", "22", "4", "22", "3", "23", "24", "23", "13")  # 13: gripper_S (STL mesh)
N = 201  # samples, dt = 0.01 → 2 s
G2T = {"A": 0.55, "B": 1.234}  # A on a sample off the 25 fps grid, B between samples
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _pose(R=None, p=(0, 0, 0)):
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    T[:3, 3] = p
    return np.round(T, 12).tolist()


def _rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    import trimesh
    root = tmp_path_factory.mktemp("viewer")
    (root / "assets").mkdir()
    (root / "cell").mkdir()
    ball = trimesh.creation.icosphere(subdivisions=6, radius=0.1)  # 81 920 triangles → decimated
    ball.export(root / "assets" / "ball.stl")
    mesh = lambda p: {"type": "mesh", "parameters": {"file": "assets/ball.stl", "scale": 1.0}, "pose": _pose(p=p)}
    task = {
        "header": {"ID": "cell/view", "timeStepSize": 0.01, "gravity": [0, 0, -9.81]},
        "obstacles": [
            {"ID": "table", "name": "table", "collision": [{"type": "box", "parameters": {"x": 1.0, "y": 0.6, "z": 0.05},
                                                             "pose": _pose(p=(0.6, 0, -0.05))}]},
            {"ID": "ball1", "collision": [mesh((0.5, 0.5, 0.3))], "visual": [mesh((0.5, 0.5, 0.3))]},
            {"ID": "ball2", "collision": [mesh((0.5, -0.5, 0.3))]},
        ],
        "constraints": [{"type": "joint", "parts": ["q", "tau"]}, {"type": "allGoalsFulfilled"}],
        "goals": [
            {"ID": "A", "type": "at", "goalPose": {"nominal": _pose(p=(0.4, 0.1, 0.5)), "toleranceProjection": ["r_sph"],
                                                   "tolerance": [[0, 0.02]]}},
            {"ID": "B", "type": "reach", "goalPose": {
                "nominal": _pose(_rot_x(np.pi / 2), (0.3, -0.2, 0.6)),
                "toleranceProjection": ["x", "y", "z"], "toleranceFrame": ["world", "world", "world"],
                "tolerance": [[-0.01, 0.03], [-0.02, 0.02], [0.0, 0.05]]}},
        ],
    }
    task_file = root / "cell" / "view.json"
    task_file.write_text(json.dumps(task))
    ms = load_module_set("robodesign_arm")
    robot = Robot.from_order(ms, ORDER)
    t = np.arange(N) * 0.01
    q = 0.6 * np.sin(np.pi * t / 2)[:, None] * np.linspace(1.0, 0.3, robot.dof)[None, :]
    dq = np.gradient(q, t, axis=0)
    ddq = np.gradient(dq, t, axis=0)
    traj = Trajectory(t, q, dq, ddq, dict(G2T))
    sol = Solution(task_id="cell/view", cost_function="cyc", module_set="robodesign_arm", module_order=ORDER,
                   base_pose=np.eye(4), trajectory=traj)
    sol_file = sol.write(root / "sol.json")
    tk = load_task(task_file)
    scene = build_scene(tk, robot, traj)
    return {"root": root, "task_file": task_file, "task": tk, "ms": ms, "robot": robot, "traj": traj, "sol": sol,
            "sol_file": sol_file, "scene": scene}


# ---------------------------------------------------------------------------------------------
def test_animation_frames_rule():
    t = np.arange(N) * 0.01
    frames = animation_samples(t, (), 25)
    assert [k for _, k in frames] == list(range(0, N, 4))  # every 0.04 s, first and last included
    frames = animation_samples(t, G2T.values(), 25)
    assert len(frames) == 51 + 2
    assert (0.55, 55) in [(round(tt, 9), k) for tt, k in frames]
    assert (1.234, -1) in [(round(tt, 9), k) for tt, k in frames]
    assert all(b[0] > a[0] for a, b in zip(frames, frames[1:]))
    # a trajectory sampled slower than the frame rate keeps every sample
    assert [k for _, k in animation_samples(np.arange(5) * 0.1, (), 25)] == [0, 1, 2, 3, 4]
    # 10 fps: every 0.1 s; the last sample is kept even off the grid
    assert [k for _, k in animation_samples(np.arange(26) * 0.01, (), 10)] == [0, 10, 20, 25]


def test_scene_has_one_node_per_body_with_the_specs_visuals(world):
    scene, robot, ms = world["scene"], world["robot"], world["ms"]
    json.dumps(scene)  # plain data
    nodes = [n for n in scene["nodes"] if n["group"] == "robot"]
    bodies = [(robot.instance_labels[i], b) for i, mid in enumerate(ORDER) for b in ms[mid].bodies]
    assert len(nodes) == len(bodies) == 16  # 4 one-body modules + 6 joints × 2 bodies
    for n, (label, body) in zip(nodes, bodies):
        assert n["frame"] == f"{label}.{body.id}" and robot.model.existFrame(n["frame"])
        visuals = [g for g in n["geometries"] if g["role"] == "visual"]
        assert len(visuals) == len(body.visual)
        assert [g["type"] for g in visuals] == [g.kind for g in body.visual]
    # the gripper's STL is embedded once, welded (STL repeats each vertex per triangle)
    grip = [g for n in nodes for g in n["geometries"] if g["type"] == "mesh"]
    assert len(grip) == 1
    rec = scene["meshes"][grip[0]["mesh"]]
    assert rec["name"] == "gripper_S.stl" and rec["n_triangles"] == 228 and rec["n_vertices"] == 122


def test_animated_poses_are_forward_kinematics(world):
    scene, robot, traj = world["scene"], world["robot"], world["traj"]
    anim = scene["animation"]
    assert len(anim["t"]) == len(anim["sample"]) == len(anim["poses"]) == 53
    assert anim["goal_frames"] == {"A": anim["sample"].index(55), "B": anim["sample"].index(-1)}
    i_tcp = anim["nodes"].index("robot/TCP")
    i_body = anim["nodes"].index("robot/24.24_distal")
    for j, (tt, k) in enumerate(zip(anim["t"], anim["sample"])):
        q = traj.q[k] if k >= 0 else np.array([np.interp(tt, traj.t, traj.q[:, c]) for c in range(robot.dof)])
        P = np.asarray(anim["poses"][j])
        assert np.abs(P[i_tcp] - robot.fk(q)[:3]).max() < 1e-9
        assert np.abs(P[i_body] - robot.fk_all(q)["24.24_distal"][:3]).max() < 1e-9
    # static node poses are the first frame; the TCP path runs through every sample
    tcp_node = next(n for n in scene["nodes"] if n["id"] == "robot/TCP")
    assert np.allclose(np.asarray(tcp_node["pose"]), robot.fk(traj.q[0]), atol=1e-12)
    assert len(scene["paths"]["tcp"]) == N
    assert np.allclose(scene["paths"]["tcp"][77], robot.fk(traj.q[77])[:3, 3], atol=1e-12)


def test_goals_obstacles_and_tolerance_shapes(world):
    scene = world["scene"]
    nodes = {n["id"]: n for n in scene["nodes"]}
    tolA = [g for g in nodes["goal/A"]["geometries"] if g["role"] == "tolerance"]
    assert [(g["type"], g["radius"]) for g in tolA] == [("sphere", 0.02)]
    tolB = [g for g in nodes["goal/B"]["geometries"] if g["role"] == "tolerance"]
    assert len(tolB) == 1 and tolB[0]["type"] == "box"
    assert np.allclose(tolB[0]["size"], [0.04, 0.04, 0.05])
    # world-frame box: axis-aligned in the world although the nominal is rotated; centred on the interval
    W = np.asarray(nodes["goal/B"]["pose"]) @ np.asarray(tolB[0]["pose"])
    assert np.allclose(W[:3, :3], np.eye(3), atol=1e-12)
    assert np.allclose(W[:3, 3], [0.3 + 0.01, -0.2, 0.6 + 0.025], atol=1e-12)
    assert [g["id"] for g in scene["goals"]] == ["A", "B"] and scene["goals"][0]["time"] == 0.55
    # obstacles: the shared STL is one mesh record used by both balls, decimated to the limit
    mesh_ids = {g["mesh"] for k in ("obstacle/ball1", "obstacle/ball2") for g in nodes[k]["geometries"]}
    assert len(mesh_ids) == 1
    rec = scene["meshes"][mesh_ids.pop()]
    assert rec["source_triangles"] == 81920 and rec["decimated"]
    assert 5000 < rec["n_triangles"] <= MAX_TRIANGLES
    assert nodes["obstacle/table"]["geometries"][0]["type"] == "box"
    assert nodes["obstacle/table"]["geometries"][0]["opacity"] < 1


def test_decimation_keeps_the_shape():
    import trimesh
    ball = trimesh.creation.icosphere(subdivisions=6, radius=1.0)
    soup = ball.vertices[ball.faces.reshape(-1)]  # as STL stores it: three vertices per triangle
    v, f = weld(soup, np.arange(len(soup)).reshape(-1, 3))
    assert len(v) == len(ball.vertices) and len(f) == len(ball.faces)  # welding undoes the STL split
    v2, f2 = decimate(v, f, 2000)
    assert 500 < len(f2) <= 2000 and f2.max() < len(v2)
    r = np.linalg.norm(v2, axis=1)
    assert r.min() > 0.9 and r.max() < 1.0 + 1e-9  # cluster means stay on/inside the sphere


def test_page_is_self_contained_with_animation_and_meshes(world):
    scene = world["scene"]
    page = render_html(scene, {"q": b"\x89PNG fake"}, title="view <test>")
    assert not re.search(r"""(?:src|href)\s*=\s*["']?\s*(?:https?:)?//""", page, re.I)
    assert not re.search(r"""@import|url\(\s*["']?https?:""", page, re.I)
    assert asset("three/three.module.min.js") in page and "Copyright 2010-2024 Three.js Authors" in page
    assert asset("three/OrbitControls.js") in page
    assert "view &lt;test&gt;" in page and 'src="data:image/png;base64,' in page
    data = decode_page_data(page)
    anim = data["animation"]
    F, n_nodes = len(scene["animation"]["t"]), len(scene["animation"]["nodes"])
    assert anim["shape"] == [F, n_nodes, 12] and F == 53 and "poses" not in anim
    poses = decode_b64(anim["poses_b64"], np.float32).reshape(F, n_nodes, 12)
    assert np.abs(poses - np.asarray(scene["animation"]["poses"]).reshape(F, n_nodes, 12)).max() < 1e-6
    # meshes decode to the recorded arrays: the gripper's 122 welded vertices
    grip = next(m for m in data["meshes"].values() if m["name"] == "gripper_S.stl")
    v = decode_b64(grip["vertices"], np.float32).reshape(-1, 3)
    idx = decode_b64(grip["indices"], np.uint16 if grip["index_type"] == "uint16" else np.uint32)
    assert len(v) == grip["n_vertices"] == 122 and len(idx) == 3 * 228 and idx.max() == 121
    import trimesh
    src = trimesh.load(str(world["ms"]["13"].bodies[0].visual[0].file), force="mesh", process=False)
    assert len(np.unique(np.asarray(src.vertices), axis=0)) == 122
    assert np.allclose(np.sort(v[:, 2]), np.sort(np.unique(np.asarray(src.vertices), axis=0)[:, 2]), atol=1e-6)
    tcp = decode_b64(data["paths"]["tcp_b64"], np.float32)
    assert len(tcp) == 3 * N


def test_trajectory_plots(world, tmp_path):
    from matplotlib.image import imread
    pngs = trajectory_plots(world["task"], world["sol"], world["ms"], out_dir=tmp_path, stem="sol")
    assert set(pngs) == {"q", "dq", "ddq", "tau", "tcp"}
    for name, png in pngs.items():
        f = tmp_path / f"sol_{name}.png"
        assert f.read_bytes() == png and png[:8] == PNG_SIGNATURE
        img = imread(f)
        assert img.shape[1] == 720 and img.shape[2] in (3, 4)
        # joint plots: 3 rows of panels (6 joints, 2 columns)
        assert img.shape[0] == (round(80 * (1.0 + 1.55 * 3)) if name != "tcp" else 336)
        assert img[..., :3].std() > 0.05  # not a blank image


def test_cli_view_solution_task_and_robot(world, tmp_path, capsys):
    out = tmp_path / "site" / "page.html"
    rc = cli_main(["view", str(world["sol_file"]), "--task", str(world["task_file"]), "--out", str(out)])
    assert rc == 0 and "wrote" in capsys.readouterr().out
    page = out.read_text()
    for name in ("q", "dq", "ddq", "tau", "tcp"):
        assert (out.parent / f"page_{name}.png").read_bytes()[:8] == PNG_SIGNATURE
    assert page.count('src="data:image/png;base64,') == 5
    data = decode_page_data(page)
    assert data["animation"]["shape"][0] == 53 and data["info"]["task"] == "cell/view"

    # the task alone: cell and goals, no robot, no animation
    out2 = tmp_path / "task.html"
    assert cli_main(["view", "--task", str(world["task_file"]), "--out", str(out2)]) == 0
    d2 = decode_page_data(out2.read_text())
    assert d2["animation"] is None and {n["group"] for n in d2["nodes"]} == {"obstacle", "goal"}

    # a bare assembly at q: a static robot
    out3 = tmp_path / "robot.html"
    q = [0.1, -0.2, 0.3, 0.4, -0.5, 0.6]
    assert cli_main(["view", "--modules", "robodesign_arm", "--order", ",".join(ORDER), "--q",
                     ",".join(map(str, q)), "--out", str(out3)]) == 0
    d3 = decode_page_data(out3.read_text())
    tcp = next(n for n in d3["nodes"] if n["id"] == "robot/TCP")
    assert d3["animation"] is None and np.allclose(tcp["pose"], world["robot"].fk(np.array(q)), atol=1e-12)
    assert cli_main(["view", "--modules", "robodesign_arm", "--order", "1,21", "--q", "1,2",
                     "--out", str(out3)]) == 2  # wrong number of joint values


def test_solution_page_survives_a_bad_assembly(world):
    bad = world["sol"].with_(module_order=("1", "23"))  # size L base → size S joint: does not connect
    page = solution_page(world["task"], bad, world["ms"], plots=False)
    data = decode_page_data(page)
    assert data["animation"] is None and any("cannot be built" in m for m in data["messages"])
    assert any(n["group"] == "goal" for n in data["nodes"])
    # and a good one lists the verdict handed to it
    page = solution_page(world["task"], world["sol"], "robodesign_arm", plots=False,
                         verdict={"valid": False, "violations": [{"constraint": "joint.q", "message": "x"}]})
    assert "INVALID" in page and decode_page_data(page)["animation"]["shape"][0] == 53
    assert load_solution(world["sol_file"]).module_order == ORDER
