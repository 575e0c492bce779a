"""A base that is free where the task leaves it free (issue 21, point 2): a task without a basePlacement
constraint allows any base pose (as the reference judges it), so the search places the base in the region
around the goals instead of keeping it at the origin."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from robodesign.design.problem import Problem
from robodesign.design.solve import SolveSettings, solve
from robodesign.formats.module_io import load_module_set
from robodesign.model.robot import Robot

RD = [sys.executable, "-m", "robodesign.cli"]
X, Y = 5.0, 0.3  # the drill path: 5 m from the origin, like the reference's FHI drilling task


def _pose(x, y, z):
    return [[-1, 0, 0, x], [0, 1, 0, y], [0, 0, -1, z], [0, 0, 0, 1]]  # the tool's z axis points down


def far_drilling(path: Path) -> Path:
    """A follow task without basePlacement: drill down 9 cm above a workpiece 5 m from the origin
    (±3 mm, 0.05 rad), joint limits (q, dq, τ), collision-free, every goal."""
    tp = [{"nominal": _pose(X, Y, z), "toleranceProjection": ["r_sph", "Theta_R"], "tolerance": [[0, 0.003], [0, 0.05]]}
          for z in (0.45, 0.40, 0.36)]
    task = {
        "header": {"ID": "test/far_drilling", "version": "2023", "taskName": "drill 5 m from the origin",
                   "tags": ["follow"], "date": "2026-11-26", "timeStepSize": 0.01, "gravity": [0, 0, -9.81],
                   "author": ["robodesign tests"], "affiliation": ["robodesign"]},
        "obstacles": [{"ID": "workpiece", "name": "workpiece", "collision": [
            {"type": "box", "parameters": {"x": 0.4, "y": 0.4, "z": 0.3},
             "pose": [[1, 0, 0, X], [0, 1, 0, Y], [0, 0, 1, 0.15], [0, 0, 0, 1]]}]}],
        "constraints": [{"type": "joint", "parts": "q, dq, tau"}, {"type": "collisionFree"},
                        {"type": "allGoalsFulfilled"}],
        "goals": [{"ID": "drill", "type": "follow", "trajectory": {"pose": tp}}],
    }
    path.write_text(json.dumps(task, indent=1))
    return path


@pytest.fixture(scope="module")
def task_file(tmp_path_factory):
    return far_drilling(tmp_path_factory.mktemp("far") / "far_drilling.json")


def test_max_reach_is_the_longest_chain_and_bounds_the_tcp():
    """robodesign_arm, 6 DoF, at most one link between joints: the longest chain is the pedestal (0.5 m between
    its connectors), 7 links of 0.5 m, 6 pitch joints (0.212 m) and the large flange (0.15 m); every design's
    TCP stays within that sum of its own modules' spans of its base, at any configuration."""
    problem = Problem.build("robodesign/pick_and_place", "robodesign_arm", "cyc")
    sp = problem.space
    assert sp.max_reach() == pytest.approx(0.5 + 7 * 0.5 + 6 * 0.212 + 0.15, abs=1e-9)
    assert sp.module_info("7").span == pytest.approx(0.5) and sp.module_info("2").span == pytest.approx(0.5)
    ms = load_module_set("robodesign_arm")
    rng = np.random.default_rng(1)
    for _ in range(8):
        order = sp.random_order(rng)
        span = sum(sp.module_info(m).span for m in order)
        assert span <= sp.max_reach() + 1e-12
        robot = Robot.from_order(ms, order)
        far = max(np.linalg.norm(robot.fk(robot.random_configuration(rng))[:3, 3]) for _ in range(40))
        assert far <= span + 1e-9


def test_missing_base_placement_gives_a_region_around_the_goals(task_file):
    problem = Problem.build(task_file, "robodesign_arm", "cyc")
    bb = problem.base_bounds
    R = problem.space.max_reach()
    assert bb.free == (0, 1, 2, 3) and bb.tolerance is None and np.allclose(bb.nominal, np.eye(4))
    # the box of the points within R (+ 3 mm) of every pose of the path: by hand
    zs = (0.45, 0.40, 0.36)
    assert bb.lower[:3] == pytest.approx((X - R - 0.003, Y - R - 0.003, max(zs) - R - 0.003))
    assert bb.upper[:3] == pytest.approx((X + R + 0.003, Y + R + 0.003, min(zs) + R + 0.003))
    assert bb.lower[3] == pytest.approx(-np.pi) and bb.upper[3] == pytest.approx(np.pi)
    # --fixed-base keeps the old behaviour: the origin
    assert problem.with_(base_search=False).base_bounds.free == ()
    # a sampled base puts every pose of the path within the order's reach: the pipeline's reach stage passes
    rng = np.random.default_rng(0)
    for _ in range(5):
        order = problem.space.random_order(rng)
        base = problem.space.sample_base(rng, order)
        c = problem.space.informed_candidate(rng, orders=2)
        for cand in ((order, base), (c.order, c.base)):
            pose = problem.space.base_bounds.pose(cand[1])
            res = solve(problem.task, problem.module_set, list(cand[0]), pose,
                        settings=SolveSettings(stop_after="reach", check=False))
            assert res.stage == "done", res.message
            assert not any(g.kind == "box" and np.all(np.abs(pose[:3, 3] - [X, Y, 0.15]) <= [0.2, 0.2, 0.15])
                           for g in problem.space.obstacles)  # the base stands clear of the workpiece


@pytest.mark.slow
def test_far_follow_task_is_solved_with_the_base_far_from_the_origin(task_file, tmp_path):
    """`robodesign optimize` finds a design (genetic, 150 evaluations) whose solution `robodesign check` judges
    valid; its base stands metres from the origin. With --fixed-base every candidate stops at reach."""
    sol = tmp_path / "sol.json"
    r = subprocess.run(RD + ["optimize", str(task_file), "--modules", "robodesign_arm", "--optimizer", "genetic",
                             "--budget", "150evals", "--workers", "1", "--seed", "0", "--json", "--out", str(sol)],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    out = json.loads(r.stdout)
    base = np.array(out["best"]["base_pose"])
    assert np.linalg.norm(base[:3, 3]) > 3.0
    written = json.loads(sol.read_text())
    assert np.allclose(np.array(written["basePose"][0]), base, atol=1e-9)
    c = subprocess.run(RD + ["check", str(task_file), str(sol)], capture_output=True, text=True, timeout=300)
    assert c.returncode == 0 and "VALID" in c.stdout, c.stdout + c.stderr
    fixed = subprocess.run(RD + ["optimize", str(task_file), "--modules", "robodesign_arm", "--optimizer", "random",
                                 "--budget", "10evals", "--workers", "1", "--fixed-base", "--json"],
                           capture_output=True, text=True, timeout=600)
    assert fixed.returncode == 1
    assert json.loads(fixed.stdout)["stage_counts"] == {"reach": 10}
