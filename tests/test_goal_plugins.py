"""A goal type that subclasses no built-in goal (tests/plugins/hover_goal.py) is found through its entry point,
read, and judged by the checker through its own methods (issue 23: goals as objects, found like optimizers),
in the driver and in a spawned worker process. The toy robot and motion of test_checker: the TCP position is
computed here by hand (test_checker.tcp), independently of the checker."""
import json
import shutil
import sys
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path

import numpy as np
import pytest

from robodesign.formats import goal_types
from robodesign.formats.module_io import load_module_set
from robodesign.core.trajectory import Trajectory
from robodesign.formats.solution import Solution
from robodesign.formats.task_io import load_task
from robodesign.formats.task_spec import BUILTIN_GOAL_TYPES
from robodesign.judge.checker import check

from conftest import toy_module_set
from test_checker import QA, plan, tcp

PLUGINS = Path(__file__).parent / "plugins"
RADIUS = 0.002
T_GOAL = 1.5  # the plan holds still at QA from t = 1.0 s to 1.5 s


@pytest.fixture
def installed(tmp_path, monkeypatch):
    """The plugin installed as a distribution would be: its module and a .dist-info folder declaring the entry
    point ``hover = hover_goal:Hover`` in the group robodesign.goal_types, in a folder on sys.path (which
    spawned workers inherit). The registry forgets what it read before and what this test registers."""
    site = tmp_path / "site"
    site.mkdir()
    shutil.copy(PLUGINS / "hover_goal.py", site / "hover_goal.py")
    info = site / "hover_goal_plugin-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: hover-goal-plugin\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[{goal_types.ENTRY_POINT_GROUP}]\nhover = hover_goal:Hover\n")
    monkeypatch.syspath_prepend(str(site))
    monkeypatch.delitem(sys.modules, "hover_goal", raising=False)
    monkeypatch.setattr(goal_types, "_TYPES", dict(goal_types._TYPES))
    monkeypatch.setattr(goal_types, "_entry_points_loaded", False)
    return site


def _task(folder: Path, duration: float) -> Path:
    goal = {"ID": "H", "type": "hover", "position": [float(x) for x in tcp(*QA)[:3, 3]], "radius": RADIUS,
            "duration": duration}
    task = {"header": {"ID": "toy/hover", "timeStepSize": 0.01, "gravity": [0, 0, -9.81]}, "obstacles": [],
            "goals": [goal], "constraints": [{"type": "joint", "parts": ["q", "dq", "ddq", "tau"]},
                                             {"type": "selfCollisionFree"}, {"type": "allGoalsFulfilled"}]}
    f = folder / "toy" / f"hover_{duration}.json"
    f.parent.mkdir(parents=True, exist_ok=True)
    f.write_text(json.dumps(task))
    return f


def _solution() -> Solution:
    t, q, dq, ddq, _ = plan()
    return Solution(task_id="toy/hover", cost_function="cyc", module_set="toy", module_order=("B", "J", "J", "E"),
                    base_pose=np.eye(4), trajectory=Trajectory(t, q, dq, ddq, {"H": T_GOAL}))


def _judge(task_file: str, solution: Solution, modules: str):
    """Read the task and judge the solution (in whichever process runs this)."""
    task = load_task(task_file)
    v = check(task, solution, load_module_set(modules))
    return type(task.goals[0]).__module__, v.valid, v.goals, [(x.constraint, x.goal, x.sample, x.message)
                                                             for x in v.violations]


def test_the_plugin_goal_subclasses_no_built_in_goal():
    sys.path.insert(0, str(PLUGINS))
    try:
        from hover_goal import Hover
    finally:
        sys.path.remove(str(PLUGINS))
    assert not issubclass(Hover, BUILTIN_GOAL_TYPES)


def test_found_through_its_entry_point_read_and_judged(installed, tmp_path):
    ms = toy_module_set(tmp_path)
    assert "hover" in goal_types.known_goal_types()  # listing the types reads the entry-point group
    assert goal_types.goal_type("hover").cls.__module__ == "hover_goal"
    t, q, *_ = plan()
    target = tcp(*QA)[:3, 3]
    # independently of the checker: the TCP is still at QA's TCP over [1.0, 1.5] s, and moving before
    dist = np.array([np.linalg.norm(tcp(*qk)[:3, 3] - target) for qk in q])
    assert dist[100:151].max() < 1e-12 and dist[70] > RADIUS

    # achieved: hovering for 0.4 s up to t_g = 1.5 s
    module, valid, goals, violations = _judge(str(_task(tmp_path, 0.4)), _solution(), str(ms))
    assert module == "hover_goal" and valid and goals == {"H": True} and violations == []

    # missed: hovering for 0.8 s would start at 0.7 s, while the arm is still approaching
    task = load_task(_task(tmp_path, 0.8))
    k0 = int(np.searchsorted(t, 0.7 - 1e-9))
    far = [k for k in range(k0, 151) if dist[k] > RADIUS]
    kk = far[0]
    assert kk == k0 and t[kk] == pytest.approx(0.7)
    v = check(task, _solution(), load_module_set(ms))
    assert not v.valid and v.goals == {"H": False}
    [miss] = v.violations
    assert (miss.constraint, miss.goal, miss.sample) == ("goal", "H", kk)
    assert miss.value == pytest.approx(dist[kk], rel=1e-9) and miss.bound == RADIUS
    assert miss.message == (f"hover: the TCP is {dist[kk]:.6g} m from the point at t={t[kk]:.4f} s, farther than "
                            f"the radius {RADIUS:g} m ({len(far)} samples of the window)")
    # the goal's own time window is the one its goal-level constraints are judged over
    from robodesign.judge.quantities import TrajectoryQuantities
    from robodesign.model.cell import solution_robot
    sol = _solution()
    tq = TrajectoryQuantities.from_solution(solution_robot(task, sol, load_module_set(ms)), sol, task)
    assert tq.goal_windows == {"H": (k0, 150)}


def test_the_plugin_reads_its_own_variant(installed, tmp_path):
    """The task reader hands the goal's JSON to the class's canonical_json before the schema check."""
    f = _task(tmp_path, 0.4)
    data = json.loads(f.read_text())
    x, y, z = data["goals"][0]["position"]
    data["goals"][0]["Position"] = {"x": x, "y": y, "z": z}  # keys match case-insensitively, as for built-ins
    del data["goals"][0]["position"]
    f.write_text(json.dumps(data))
    task = load_task(f)
    assert task.goals[0].position == (x, y, z)
    assert any("goals[0].position" in w and "read as [x, y, z]" in w for w in task.warnings), task.warnings


def test_a_spawned_worker_finds_the_goal_type(installed, tmp_path):
    """A worker started with the spawn method imports nothing of the driver's: it finds the goal type through
    the entry point and judges the plugin goal as the driver does."""
    ms = toy_module_set(tmp_path)
    with ProcessPoolExecutor(max_workers=1, mp_context=get_context("spawn")) as pool:
        ok = pool.submit(_judge, str(_task(tmp_path, 0.4)), _solution(), str(ms)).result(timeout=600)
        bad = pool.submit(_judge, str(_task(tmp_path, 0.8)), _solution(), str(ms)).result(timeout=600)
    assert ok == ("hover_goal", True, {"H": True}, [])
    assert bad[:3] == ("hover_goal", False, {"H": False})
    assert [(c, g, k) for c, g, k, _ in bad[3]] == [("goal", "H", 70)]
    assert bad[3][0][3].startswith("hover: the TCP is ")


def test_without_the_entry_point_the_type_is_unknown(tmp_path, monkeypatch):
    monkeypatch.setattr(goal_types, "_TYPES", {k: v for k, v in goal_types._TYPES.items() if v.builtin})
    monkeypatch.setattr(goal_types, "_entry_points_loaded", False)
    from robodesign.core.errors import InputError
    with pytest.raises(InputError, match=r"goals\[0\]\.type"):
        load_task(_task(tmp_path, 0.4))
