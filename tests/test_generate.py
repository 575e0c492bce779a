"""Task generators (robodesign generate; docs/generators.md): determinism, provenance, geometry of the
generated cells checked with coal (independently of the generators' own box arithmetic), loading, and a
solve → check round trip with the reference design of the built-in set robodesign_arm."""
import json
import math

import coal
import numpy as np
import pytest

from robodesign.checker import check
from robodesign.cli import main
from robodesign.generate import families, generate, regenerate
from robodesign.generate.common import REFERENCE_ORDER
from robodesign.geometry import coal_shapes
from robodesign.module_io import load_module_set
from robodesign.solve import SolveSettings, solve
from robodesign.task_io import load_task
from robodesign.task_spec import BasePlacement, Reach

WHITMAN_SETS = [({"goals": 3, "obstacles": 3, "base": "fixed"}, 3),
                ({"goals": 5, "obstacles": 5, "base": "xyz_any_rot"}, 3)]


@pytest.fixture(scope="module")
def ms():
    return load_module_set("robodesign_arm")


def _files(folder):
    return sorted(p for p in folder.glob("*.json"))


def _bytes(folder):
    out = {}
    for p in sorted(folder.rglob("*")):
        if p.is_file():
            out[p.relative_to(folder).as_posix()] = p.read_bytes()
    return out


def _point_distance(task, p) -> float:
    """Distance of point p to the task's obstacles, computed by coal (a 0.1 mm sphere at p)."""
    probe = coal.CollisionObject(coal.Sphere(1e-4), coal.Transform3s(np.eye(3), np.asarray(p, float)))
    best = math.inf
    for o in task.obstacles:
        for g in o.collision:
            for shape in coal_shapes(g):
                obj = coal.CollisionObject(shape, coal.Transform3s(g.pose[:3, :3], g.pose[:3, 3]))
                res = coal.DistanceResult()
                coal.distance(probe, obj, coal.DistanceRequest(), res)
                best = min(best, res.min_distance + 1e-4)
    return best


@pytest.fixture(scope="module")
def whitman(tmp_path_factory):
    out = {}
    for opts, n in WHITMAN_SETS:
        d = tmp_path_factory.mktemp(f"w{opts['goals']}")
        generate("whitman2020", d, n, seed=7, options=opts)
        out[(opts["goals"], opts["base"])] = d
    return out


def test_list_names_every_family(capsys):
    assert main(["generate", "--list"]) == 0
    text = capsys.readouterr().out
    for name in families():
        assert name in text
    assert "--obstacles" in text


def test_whitman_same_seed_same_bytes_other_seed_differs(tmp_path, whitman):
    a = tmp_path / "a"
    generate("whitman2020", a, 3, seed=7, options={"goals": 3, "obstacles": 3})
    assert _bytes(a) == _bytes(whitman[(3, "fixed")])
    b = tmp_path / "b"
    generate("whitman2020", b, 3, seed=8, options={"goals": 3, "obstacles": 3})
    ta = [json.loads(p.read_text()) for p in _files(a)]
    tb = [json.loads(p.read_text()) for p in _files(b)]
    for x, y in zip(ta, tb):
        assert x["goals"] != y["goals"] and x["obstacles"] != y["obstacles"]
    # the tasks of one folder differ from each other too
    assert len({json.dumps(t["goals"]) for t in ta}) == 3


@pytest.mark.parametrize("opts,n", WHITMAN_SETS)
def test_whitman_cells(whitman, opts, n):
    files = _files(whitman[(opts["goals"], opts["base"])])
    assert len(files) == n
    for f in files:
        task = load_task(f)
        assert not task.warnings
        goals = [g for g in task.goals if isinstance(g, Reach)]
        assert len(goals) == opts["goals"]
        assert len(task.obstacles) == opts["obstacles"]
        for o in task.obstacles:
            (g,) = o.collision
            assert g.kind == "box" and g.size == (0.25, 0.25, 0.25)
            assert np.array_equal(g.pose[:3, :3], np.eye(3))  # axis-aligned
            assert np.hypot(*g.pose[:2, 3]) <= 1.0 + 1e-9 and 0.125 - 1e-9 <= g.pose[2, 3] <= 1.0 + 1e-9
        for g in goals:
            p = g.pose.nominal[:3, 3]
            assert _point_distance(task, p) >= 0.06 - 1e-6  # collision-free goal, with clearance
            assert 0.3 - 1e-9 <= np.hypot(*p[:2]) <= 0.9 + 1e-9 and 0.05 - 1e-9 <= p[2] <= 1.0 + 1e-9
            # position ± 5 mm, orientation free
            T = g.pose.nominal.copy()
            T[:3, :3] = np.array([[0, 0, 1], [0, -1, 0], [1, 0, 0]], float)  # any rotation
            T[:3, 3] += [0.0049, -0.0049, 0.0049]
            assert g.pose.valid(T)
            T[0, 3] += 0.0002
            assert not g.pose.valid(T)
        bp = task.constraint(BasePlacement).pose
        R = np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0]], float)
        far = np.eye(4)
        far[:3, :3], far[:3, 3] = R, [0.99, -0.99, 0.99]
        assert bp.valid(np.eye(4))
        assert bp.valid(far) == (opts["base"] == "xyz_any_rot")
        far[0, 3] = 1.02
        assert not bp.valid(far)
        parts = {c.type: c for c in task.constraints}
        assert "tau" in parts["joint"].parts and {"collisionFree", "selfCollisionFree", "allGoalsFulfilled"} <= set(parts)


def test_whitman_header_regenerates_the_file(whitman, tmp_path):
    f = _files(whitman[(5, "xyz_any_rot")])[2]
    tags = json.loads(f.read_text())["header"]["tags"]
    for t in ("robodesign-generate:generator=whitman2020", "robodesign-generate:version=1",
              "robodesign-generate:seed=7", "robodesign-generate:index=2", "robodesign-generate:goals=5",
              "robodesign-generate:obstacles=5", "robodesign-generate:base=xyz_any_rot"):
        assert t in tags
    out = regenerate(f, tmp_path)
    assert out.name == f.name and out.read_bytes() == f.read_bytes()
    # and through the CLI
    assert main(["generate", "--from", str(f), "--out", str(tmp_path / "cli")]) == 0
    assert (tmp_path / "cli" / f.name).read_bytes() == f.read_bytes()


def test_whitman_solve_check_round_trip(whitman, ms):
    """The reference design solves every generated whitman task and the checker accepts the solution."""
    for key, folder in whitman.items():
        for f in _files(folder):
            task = load_task(f)
            res = solve(task, ms, list(REFERENCE_ORDER), settings=SolveSettings(seed=0))
            assert res.feasible, (f.name, res.stage, res.message)
            v = check(task, res.solution, ms)
            assert v.valid and v.costs["cyc"] == pytest.approx(res.solution.trajectory.t[-1])
            assert res.goals_reached == len(task.goals)


def test_cli_bad_input_exit_2(tmp_path, capsys):
    assert main(["generate", "whitman2020", "--out", str(tmp_path), "--goals", "x"]) == 2
    assert "--goals" in capsys.readouterr().err
    assert main(["generate", "whitman2020", "--out", str(tmp_path), "--base", "floating"]) == 2
    assert main(["generate", "nosuchfamily", "--out", str(tmp_path)]) == 2
    assert main(["generate", "whitman2020"]) == 2  # no --out
    assert main(["generate", "whitman2020", "--out", str(tmp_path), "--count", "0"]) == 2
    assert main(["generate", "--from", str(tmp_path / "missing.json"), "--out", str(tmp_path)]) == 2
    assert list(tmp_path.glob("*.json")) == []


def test_cli_writes_folder(tmp_path, capsys):
    assert main(["generate", "whitman2020", "--out", str(tmp_path), "--count", "2", "--seed", "3",
                 "--goals", "2", "--obstacles", "1"]) == 0
    files = _files(tmp_path)
    assert [f.name for f in files] == ["whitman2020_g2o1_fixed_s3_0000.json", "whitman2020_g2o1_fixed_s3_0001.json"]
    assert len(load_task(files[0]).goals) == 2
