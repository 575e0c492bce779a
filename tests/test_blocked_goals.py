"""A goal the tool cannot be at (design/blocked.py): every end effector of the set, held at the goal's pose,
lies inside an obstacle deeper than the goal's tolerance can move it. Checked against an independent sampling
of the poses the tolerance accepts, in the IK stage (no restarts) and in `optimize`'s diagnosis."""
from __future__ import annotations

import dataclasses
import json
import math

import coal
import numpy as np
import pytest
from test_reach_bound import FIXED, reach_task_json  # noqa: E402

from robodesign.cli.entry import main
from robodesign.core.spatial import inv
from robodesign.design.blocked import blocked_goal_proof, tool_block
from robodesign.design.search_space import SearchSpace
from robodesign.design.solve import solve
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task

HEAVY = load_module_set("robodesign_heavy")
EEFS = HEAVY.of_kind("eef")  # tool_flange_2 (id 16): TCP 0.135 m above its flange; tool_flange_3 (17): 0.165 m
GOAL = np.array([0.6, 0.0, 0.4])
THETA = math.radians(0.5)
BOX = 0.25


def _task(tmp_path, top: float, collision_free: bool = True, name: str = "t"):
    """A fixed-base task with one full-pose goal at GOAL (tool axis = world z, ±1 mm, 0.5°) and a 0.25 m cube
    under the tool whose top face is at height ``top``."""
    cons = [{"type": "collisionFree"}] if collision_free else []
    data = reach_task_json([tuple(GOAL)], FIXED, name, cons)
    g = data["goals"][0]["goalPose"]
    g["toleranceProjection"].append("Theta_R")
    g["tolerance"].append([0, THETA])
    P = np.eye(4)
    P[:3, 3] = (GOAL[0], GOAL[1], top - BOX / 2)
    data["obstacles"] = [{"ID": "cube", "collision": [{"type": "box", "parameters": {"x": BOX, "y": BOX, "z": BOX},
                                                       "pose": P.tolist()}]}]
    f = tmp_path / f"{name}.json"
    f.write_text(json.dumps(data))
    return f, load_task(f)


def _tcp_offset(eef) -> float:
    return float(next(c for c in eef.connectors if c.type == "eef").pose[2, 3])


def _collides_everywhere(task, eef, n: int, rng) -> bool:
    """Independent check: the end effector's geometry at ``n`` poses the goal accepts (the corners of the
    position box, rotated by the full 0.5° about random axes) against the real cube, with coal."""
    c = next(c for c in eef.connectors if c.type == "eef")
    body = eef.body(c.body_id)
    ob = task.obstacles[0].collision[0]
    cube = coal.Box(*ob.size)
    cube_tf = coal.Transform3s(ob.pose[:3, :3], ob.pose[:3, 3])
    tp = task.goals[0].pose
    for k in range(n):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        th = THETA * (1 - 1e-6)
        R = np.eye(3) + math.sin(th) * K + (1 - math.cos(th)) * K @ K
        T = tp.nominal.copy()
        T[:3, :3] = T[:3, :3] @ R
        T[:3, 3] += 1e-3 * (1 - 1e-6) * np.array([(k >> i) % 2 * 2 - 1 for i in range(3)])
        assert tp.valid(T)
        hit = False
        for g in body.collision:
            M = T @ inv(c.pose) @ g.pose
            shape = coal.Cylinder(g.size[0], g.size[1])
            res = coal.CollisionResult()
            if coal.collide(shape, coal.Transform3s(M[:3, :3], M[:3, 3]), cube, cube_tf, coal.CollisionRequest(), res):
                hit = True
                break
        if not hit:
            return False
    return True


def test_a_tool_deep_in_an_obstacle_is_proven_blocked_and_sampling_agrees(tmp_path):
    low = min(_tcp_offset(e) for e in EEFS)
    assert [round(_tcp_offset(e), 3) for e in EEFS] == [0.135, 0.165]
    # the shorter tool's flange bottom is 0.135 m below the TCP: the cube's top 5 mm above it
    f, task = _task(tmp_path, GOAL[2] - low + 0.005)
    proof = blocked_goal_proof(task, EEFS)
    assert proof is not None and proof.goals == ("g0",) and len(proof.blocks) == 2
    # the slack of the flange plate (r 45 mm, its bottom 135 mm below the TCP): √3 mm of position plus 0.5° times
    # the farthest corner of its bounding box from the TCP
    r = math.hypot(0.045 * math.sqrt(2), 0.135)
    assert proof.blocks[0].slack == pytest.approx(math.sqrt(3) * 1e-3 + THETA * r, rel=1e-9)
    assert proof.blocks[0].slack < 0.005  # hence the proof: 5 mm deep
    rng = np.random.default_rng(0)
    assert all(_collides_everywhere(task, e, 400, rng) for e in EEFS)
    assert "provably out of reach: every end effector of the module set, held at a goal's pose, lies inside" in \
        proof.message


def test_a_shallow_overlap_is_no_proof_and_a_pose_the_tolerance_accepts_clears_it(tmp_path):
    low = min(_tcp_offset(e) for e in EEFS)
    f, task = _task(tmp_path, GOAL[2] - low + 0.0005)  # 0.5 mm: lifting the tool by 1 mm clears it
    short = next(e for e in EEFS if _tcp_offset(e) == low)
    assert tool_block(task, short) is None
    assert blocked_goal_proof(task, EEFS) is None  # the longer tool is blocked, the shorter not: no proof
    assert tool_block(task, next(e for e in EEFS if e is not short)) is not None
    assert not _collides_everywhere(task, short, 8, np.random.default_rng(1))


def test_no_proof_without_collision_free_or_with_a_moving_obstacle(tmp_path):
    low = min(_tcp_offset(e) for e in EEFS)
    _, task = _task(tmp_path, GOAL[2] - low + 0.02, collision_free=False, name="free")
    assert blocked_goal_proof(task, EEFS) is None
    _, task = _task(tmp_path, GOAL[2] - low + 0.02, name="moving")
    assert blocked_goal_proof(task, EEFS) is not None
    ob = dataclasses.replace(task.obstacles[0], motion_t=np.array([0.0, 1.0]), motion_poses=np.stack([np.eye(4)] * 2))
    assert blocked_goal_proof(dataclasses.replace(task, obstacles=(ob,)), EEFS) is None


def test_the_ik_stage_fails_a_blocked_design_at_once(tmp_path):
    low = min(_tcp_offset(e) for e in EEFS)
    _, task = _task(tmp_path, GOAL[2] - low + 0.02)
    space, rng = SearchSpace(HEAVY), np.random.default_rng(3)
    order = next(o for o in (space.random_order(rng) for _ in range(200)) if o[-1] == "16")
    res = solve(task, HEAVY, order, np.eye(4))
    assert res.stage == "ik" and not res.feasible
    assert "at its pose the end effector 16 lies inside obstacle cube deeper than the goal's tolerance" in res.message


def test_optimize_reports_the_blocked_goal_as_provably_out_of_reach(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)  # optimize journals its search beside its output file
    low = min(_tcp_offset(e) for e in EEFS)
    f, _ = _task(tmp_path, GOAL[2] - low + 0.02)
    code = main(["optimize", str(f), "--modules", "robodesign_heavy", "--optimizer", "random", "--budget", "3evals",
                 "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 1 and not out["feasible"], out
    d = out["diagnosis"]
    assert d["verdict"] == "out_of_reach" and d["label"] == "provably out of reach"
    assert d["proof"]["kind"] == "blocked" and d["proof"]["goals"] == ["g0"]
    assert sorted(b["eef"] for b in d["proof"]["blocks"]) == sorted(e.id for e in EEFS)
    assert {b["obstacle"] for b in d["proof"]["blocks"]} == {"cube"}


def test_the_frames_match_the_robot_the_judge_builds():
    """Independent of design/blocked.py's conventions: the tool's collision geometry placed by the Robot
    (pinocchio) equals the TCP pose times the eef pieces."""
    import pinocchio as pin

    from robodesign.design.blocked import _tool_pieces
    from robodesign.formats.assembly import Assembly
    from robodesign.model.robot import Robot
    space, rng = SearchSpace(HEAVY), np.random.default_rng(5)
    for _ in range(6):
        order = space.random_order(rng)
        B = np.eye(4)
        B[:3, :3] = np.linalg.qr(rng.normal(size=(3, 3)))[0] * np.array([1, 1, 1])
        if np.linalg.det(B[:3, :3]) < 0:
            B[:3, 0] *= -1
        B[:3, 3] = rng.uniform(-1, 1, 3)
        robot = Robot(HEAVY, Assembly.from_order(HEAVY, order), base_pose=B)
        q = rng.uniform(-1, 1, robot.dof)
        T = robot.fk(q)
        gd = pin.GeometryData(robot.geom_model)
        pin.forwardKinematics(robot.model, robot.data, q)
        pin.updateGeometryPlacements(robot.model, robot.data, robot.geom_model, gd)
        placed = {o.name: gd.oMg[i].homogeneous for i, o in enumerate(robot.geom_model.geometryObjects)}
        pieces = _tool_pieces(HEAVY[order[-1]])
        mine = [T @ p.pose for p in pieces]
        theirs = [M for name, M in placed.items() if name.startswith(f"{order[-1]}.")]
        assert len(mine) == len(theirs) and len(mine) > 0
        for M in mine:
            assert min(np.abs(M - N).max() for N in theirs) < 1e-9


def _fixed_base_task(tmp_path, centre, name):
    """A fixed-base task (±1 mm, 0.5°) with a reachable full-pose goal and a 0.25 m cube at ``centre``."""
    data = reach_task_json([(0.6, 0.0, 0.4)], None, name, [{"type": "collisionFree"}])
    data["constraints"].append({"type": "basePlacement", "pose": {
        "nominal": np.eye(4).tolist(), "toleranceProjection": ["x", "y", "z", "Theta_R"],
        "tolerance": [[-1e-3, 1e-3]] * 3 + [[0, THETA]]}})
    P = np.eye(4)
    P[:3, 3] = centre
    data["obstacles"] = [{"ID": "cube", "collision": [{"type": "box", "parameters": {"x": BOX, "y": BOX, "z": BOX},
                                                       "pose": P.tolist()}]}]
    f = tmp_path / f"{name}.json"
    f.write_text(json.dumps(data))
    return load_task(f)


def test_a_cube_over_a_fixed_base_blocks_every_design_and_every_sampled_design_agrees(tmp_path):
    from robodesign.design.blocked import fixed_part_proof
    from robodesign.design.problem import Problem
    from robodesign.formats.assembly import Assembly
    from robodesign.model.cell import build_robot
    task = _fixed_base_task(tmp_path, (0.0, 0.0, 0.3), "over")  # the cube spans z 0.175–0.425 above the base
    problem = Problem.build(task, HEAVY, "cyc")
    proof = fixed_part_proof(task, problem.space)
    assert proof is not None and proof.part == "fixed" and all(b.obstacle == "cube" for b in proof.blocks)
    assert "provably out of reach: every design of the module set has a part that no joint moves" in proof.message
    # independently: random designs of the space, at base poses the placement allows (corners of the ±1 mm box,
    # turned by 0.5°), all collide whatever the joints do (the Robot's own test against the real cube)
    space, rng = problem.space, np.random.default_rng(2)
    for k in range(40):
        order = space.random_order(rng)
        B = np.eye(4)
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        B[:3, :3] = np.eye(3) + math.sin(THETA * 0.999) * K + (1 - math.cos(THETA * 0.999)) * K @ K
        B[:3, 3] = 0.999e-3 * np.array([(k >> i) % 2 * 2 - 1 for i in range(3)])
        assert task.base_placement.valid(B)
        assert build_robot(task, HEAVY, Assembly.from_order(HEAVY, order), B).base_collisions()
    # the same cube 0.6 m to the side: the designs can stand, no proof
    aside = _fixed_base_task(tmp_path, (0.0, 0.6, 0.3), "aside")
    assert fixed_part_proof(aside, Problem.build(aside, HEAVY, "cyc").space) is None


def test_a_free_base_gives_no_fixed_part_proof(tmp_path):
    from robodesign.design.blocked import fixed_part_proof
    from robodesign.design.problem import Problem
    task = _fixed_base_task(tmp_path, (0.0, 0.0, 0.3), "free")
    free = dataclasses.replace(task, constraints=tuple(c for c in task.constraints
                                                       if type(c).__name__ != "BasePlacement"))
    assert free.base_placement is None
    assert fixed_part_proof(free, Problem.build(free, HEAVY, "cyc").space) is None
