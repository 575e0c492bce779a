import json
import os
import sys
from pathlib import Path

import numpy as np
import pytest

os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
os.environ.setdefault("RAY_AUTH_MODE", "disabled")


def pytest_sessionstart(session):
    """Compile the IK kernels into numba's cache before the first test (a fresh checkout's cache is cold,
    and a process that finds it cold runs the Python loop for its whole life): every test process, and
    every subprocess a test starts, then uses the compiled loop. tests/test_cold_start.py tests the cold
    path with caches of its own."""
    from robodesign.solvers import ik_kernel
    if ik_kernel.available() and not ik_kernel.compiled():
        ik_kernel.compile_into_cache()


def pytest_collection_modifyitems(config, items):
    """Order for ``pytest -n 2`` (README's test command; pytest-xdist with ``--dist loadfile`` from pyproject's
    addopts: each file runs whole on one worker, so its module-scoped fixtures are built once, and the files go
    to the workers in the order of the collection). In each worker, the files with the most tests marked
    ``slow`` come first, so the two workers start with the long files and neither is left alone with one
    at the end; a file's tests keep their order. A run without ``-n`` is left as collected. (Not ``--dist
    loadgroup`` with ``xdist_group`` marks: with pytest 9.2 and xdist 3.8 it silently stops grouping, because
    xdist renames the tests' ``_nodeid``, which pytest 9.2 no longer reads: pytest-xdist issue 1386.)"""
    if not hasattr(config, "workerinput"):  # not an xdist worker
        return
    slow = {}
    for item in items:
        slow[item.path] = slow.get(item.path, 0) + (item.get_closest_marker("slow") is not None)
    items.sort(key=lambda item: -slow[item.path])  # stable: the files keep their order, their tests too


ROOT = Path(__file__).resolve().parents[1]
COBRA = ROOT.parent / "shared" / "cobra"
# assets/tasks/make_tasks.py (the built-in tasks' script) is importable as `make_tasks` in every test
sys.path.insert(0, str(ROOT / "assets" / "tasks"))
IMPROV = COBRA / "modules" / "IMPROV"
PRIMITIVES = COBRA / "modules" / "geometric_primitive_modules"
TASKS = COBRA / "tasks"


def _eye():
    return np.eye(4).tolist()


def _T(x=0.0, y=0.0, z=0.0, rx=0.0):
    c, s = np.cos(rx), np.sin(rx)
    T = np.array([[1, 0, 0, x], [0, c, -s, y], [0, s, c, z], [0, 0, 0, 1.0]])
    return np.round(T, 15).tolist()


def toy_module_set(folder: Path) -> Path:
    """A tiny hand-computable module set: base B (connector at z=0.1), revolute joint module J (joint
    0.05 above its flange, axis = -y of the flange, a 0.2 m link of 2 kg with its CoM 0.1 up) and an
    end effector E (TCP 0.1 above its flange)."""
    prox = {"pose": _T(rx=np.pi), "gender": "f", "type": "t", "size": [1]}
    cyl = lambda r, z, zc: {"type": "cylinder", "parameters": {"r": r, "z": z}, "pose": _T(z=zc)}
    data = {"ignore_collisions": "rigid_via_joint", "modules": [
        {"header": {"ID": "B", "name": "base"}, "bodies": [{
            "ID": "b", "mass": 1.0, "r_com": [0, 0, 0.05], "inertia": np.diag([0.01, 0.01, 0.01]).tolist(),
            "connectors": [{"ID": "base", "pose": _T(rx=np.pi), "gender": "f", "type": "base", "size": []},
                           {"ID": "out", "pose": _T(z=0.1), "gender": "m", "type": "t", "size": [1]}],
            "collision": [cyl(0.05, 0.1, 0.05)]}], "joints": []},
        {"header": {"ID": "J", "name": "joint"}, "bodies": [
            {"ID": "p", "mass": 0.0, "r_com": [0, 0, 0], "inertia": np.zeros((3, 3)).tolist(),
             "connectors": [dict(prox, ID="in")], "collision": [cyl(0.03, 0.05, 0.025)]},
            {"ID": "c", "mass": 2.0, "r_com": [0, 0, 0.1], "inertia": np.diag([0.02, 0.02, 0.001]).tolist(),
             "connectors": [{"ID": "out", "pose": _T(z=0.2), "gender": "m", "type": "t", "size": [1]}],
             "collision": [cyl(0.03, 0.2, 0.1)]}],
         "joints": [{"ID": "j", "parent": "p", "child": "c", "type": "revolute", "poseParent": _T(z=0.05, rx=np.pi / 2),
                     "poseChild": _T(rx=-np.pi / 2),
                     "limits": {"positionLower": -3.2, "positionUpper": 3.2, "peakTorque": 50, "velocity": 2,
                                "acceleration": 10},
                     "gearRatio": 100, "motorInertia": 1e-5, "frictionCoulomb": 2.0, "frictionViscous": 3.0}]},
        {"header": {"ID": "E", "name": "eef"}, "bodies": [{
            "ID": "e", "mass": 0.5, "r_com": [0, 0, 0.05], "inertia": np.diag([1e-3, 1e-3, 1e-3]).tolist(),
            "connectors": [dict(prox, ID="in"), {"ID": "tcp", "pose": _T(z=0.1), "gender": "m", "type": "eef",
                                                 "size": []}],
            "collision": [cyl(0.02, 0.1, 0.05)]}], "joints": []},
    ]}
    d = folder / "toy"
    d.mkdir(parents=True, exist_ok=True)
    (d / "modules.json").write_text(json.dumps(data, indent=1))
    return d


@pytest.fixture
def toy_set(tmp_path):
    from robodesign import load_module_set
    return load_module_set(toy_module_set(tmp_path))


def boxes_around(robot, seed, n=6):
    """Boxes of 10–40 cm within 0.9 m of the robot's base, at random orientations (obstacles for collision tests)."""
    import coal
    import pinocchio as pin

    from robodesign.model.robot import Obstacle
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        T = np.eye(4)
        T[:3, :3] = pin.exp3(rng.normal(0.0, 1.0, 3))
        T[:3, 3] = robot.base_pose[:3, 3] + rng.uniform(-0.9, 0.9, 3)
        out.append(Obstacle(f"box{i}", coal.Box(*rng.uniform(0.1, 0.4, 3)), T))
    return out


def assert_within_limits(robot, tr):
    """Every limit at every sample of a trajectory, torques computed independently per sample with
    Robot.drivetrain_torques, with the sample's own ddq (the acceleration just after it) and with the previous
    sample's (just before it: the judge's motion model has both accelerations at a sample, docs/checker.md).
    Returns the largest |τ|/τ_max."""
    assert np.all(tr.q >= robot.q_lower - 1e-12) and np.all(tr.q <= robot.q_upper + 1e-12)
    assert np.all(np.abs(tr.dq) <= robot.dq_max * (1 + 1e-6))
    assert np.all(np.abs(tr.ddq) <= robot.ddq_max * (1 + 1e-9))
    worst = 0.0
    for k, (q, dq) in enumerate(zip(tr.q, tr.dq)):
        for ddq in (tr.ddq[k], tr.ddq[max(k - 1, 0)]):
            tau = robot.drivetrain_torques(q, dq, ddq)[0]
            assert np.all(np.abs(tau) <= robot.tau_max * (1 + 1e-9)), f"sample {k}: tau {tau} over {robot.tau_max}"
            worst = max(worst, float(np.max(np.abs(tau) / robot.tau_max)))
    return worst


@pytest.fixture(params=["compiled", "numpy"])
def geometry_paths(request, monkeypatch):
    """A test of the robot's geometry both ways: the compiled kernels (robodesign.model.geometry_kernel), and
    numpy's passes with every pair asked of coal (the kernels not ready, as before their first compilation)."""
    from robodesign.model import geometry_kernel
    if request.param == "numpy":
        monkeypatch.setattr(geometry_kernel, "ready", lambda: False)
    elif not (geometry_kernel.available() and geometry_kernel.warm_up()):
        pytest.skip("numba unavailable or ROBODESIGN_JIT=0")
    return request.param


@pytest.fixture(scope="session")
def ptp3_solved():
    """(task, module set, solution): PTP_3 solved with the known-good IMPROV arm 1,21,4,22,5,23,12, seed 0 (once
    per test process; the tests of the judge's motion model read it)."""
    from robodesign.design.solve import SolveSettings, solve
    from robodesign.formats.module_io import load_module_set
    from robodesign.formats.task_io import load_task
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    res = solve(task, ms, ["1", "21", "4", "22", "5", "23", "12"], settings=SolveSettings(seed=0))
    assert res.feasible, res.message
    return task, ms, res.solution
