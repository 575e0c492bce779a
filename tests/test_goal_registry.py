"""Goal types dispatch through the goal classes and the registry (issue 23 §3): a goal type defined outside
``src/`` (tests/plugins/approach_goal.py) is read, validated, solved, checked and viewed without touching
robodesign, and the registry's errors name file and field."""
import json
import pickle
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from robodesign.core.errors import InputError
from robodesign.design.solve import SolveSettings, solve
from robodesign.formats.goal_types import goal_type, known_goal_types
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.formats.task_spec import At, Follow, Leave, Pause, Reach, ReturnTo
from robodesign.judge.checker import check
from robodesign.model.robot import Robot
from robodesign.viewer.scene import build_scene

from conftest import IMPROV

PLUGINS = Path(__file__).parent / "plugins"
ORDER = ["1", "21", "4", "22", "5", "23", "12"]
TARGETS = [(-0.4, 0.0, 0.25), (0.0, 0.5, 0.25), (-0.4, 0.0, 0.25)]


def _approach_task(folder: Path, radius=0.01, extra=None) -> Path:
    goals = [{"ID": str(i + 1), "type": "approach", "position": list(p), "radius": radius}
             for i, p in enumerate(TARGETS)]
    goals[0].update(extra or {})
    task = {"header": {"ID": "plugin/approach", "version": "2022", "timeStepSize": 0.01, "gravity": [0, 0, -9.81]},
            "obstacles": [], "goals": goals,
            "constraints": [{"type": "joint", "parts": ["q", "tau"]}, {"type": "selfCollisionFree"},
                            {"type": "allGoalsFulfilled"}, {"type": "allGoalsFulfilledInOrder", "order": ["1", "2", "3"]}]}
    f = folder / "plugin" / "approach.json"
    f.parent.mkdir(parents=True, exist_ok=True)
    f.write_text(json.dumps(task))
    return f


@pytest.fixture(scope="module")
def approach():
    sys.path.insert(0, str(PLUGINS))
    try:
        import approach_goal
    finally:
        sys.path.remove(str(PLUGINS))
    return approach_goal


def test_builtin_goal_types_are_registered_classes():
    assert known_goal_types()[:6] == ["at", "reach", "returnTo", "pause", "follow", "leave"]
    for cls in (At, Reach, ReturnTo, Pause, Follow, Leave):
        assert goal_type(cls.type_name).cls is cls and goal_type(cls.type_name.upper()).cls is cls
    with pytest.raises(InputError) as e:
        goal_type("retrunTo", file="t.json", path=["goals", 2, "type"])
    assert str(e.value).startswith("t.json: goals[2].type: unknown goal type 'retrunTo' (did you mean 'returnTo'?)")


def test_without_the_plugin_the_type_is_unknown(tmp_path):
    """In a fresh process (the plugin not imported) the file is bad input naming the field."""
    f = _approach_task(tmp_path)
    p = subprocess.run([sys.executable, "-m", "robodesign.cli", "check", str(f), str(f), "--modules", str(IMPROV)],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 2, p.stderr
    assert re.search(r'approach.json: goals\[[0-2]\]\.type: "approach" is not one of \[\'at\'', p.stderr), p.stderr
    assert "Traceback" not in p.stderr


def test_a_plugin_goal_type_loads_solves_checks_and_views(approach, tmp_path):
    task = load_task(_approach_task(tmp_path))
    assert [type(g) for g in task.goals] == [approach.Approach] * 3
    g = task.goals[1]
    assert g.type == "approach" and g.solver_kind == "pose" and g.radius == 0.01
    assert np.allclose(g.target_poses[0].nominal[:3, 3], TARGETS[1]) and g.anchor is g.pose
    assert pickle.loads(pickle.dumps(task)).goals[1].type == "approach"  # ships to worker processes

    ms = load_module_set(IMPROV)
    res = solve(task, ms, ORDER, settings=SolveSettings(seed=1))
    assert res.feasible, (res.stage, res.message)
    assert res.verdict.goals == {"1": True, "2": True, "3": True}
    # independent of the checker: the TCP at each goal time is within the radius of the target
    sol = res.solution
    robot = Robot.from_order(ms, ORDER, base_pose=sol.base_pose)
    tr = sol.trajectory
    for gid, target in zip(("1", "2", "3"), TARGETS):
        k = int(np.argmin(np.abs(tr.t - tr.goal2time[gid])))
        assert np.linalg.norm(robot.fk(tr.q[k])[:3, 3] - np.asarray(target)) <= 0.01 + 1e-9
    # the same trajectory with goal 2's time moved to a sample where the TCP is far from its target: the
    # checker judges the plugin goal as missed
    far = int(np.argmax([np.linalg.norm(robot.fk(q)[:3, 3] - np.asarray(TARGETS[1])) for q in tr.q]))
    moved = sol.with_(trajectory=type(tr)(tr.t, tr.q, tr.dq, tr.ddq, {**tr.goal2time, "2": float(tr.t[far])}))
    assert check(task, moved, ms).goals["2"] is False

    scene = build_scene(task, robot, tr)
    rec = {r["id"]: r for r in scene["goals"]}
    assert rec["2"]["type"] == "approach" and np.allclose(rec["2"]["position"], TARGETS[1])
    assert rec["2"]["tolerance"] and any(n["id"] == "goal/2" and n["name"] == "goal 2 (approach)" for n in scene["nodes"])


def test_a_plugin_goal_is_schema_checked_with_file_and_field(approach, tmp_path):
    with pytest.raises(InputError) as e:
        load_task(_approach_task(tmp_path, radius=-1))
    assert str(e.value) == "approach.json: goals[2].radius: -1 is less than or equal to the minimum of 0"
    with pytest.raises(InputError) as e:
        load_task(_approach_task(tmp_path, extra={"goalPose": {"nominal": np.eye(4).tolist()}}))
    assert "approach.json: goals[0]" in str(e.value)
