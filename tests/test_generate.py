"""Task generators (robodesign generate; docs/generators.md): determinism, provenance, geometry of the
generated cells checked with coal (independently of the generators' own box arithmetic), loading, and a
solve → check round trip with the reference design of the built-in set robodesign_arm."""
import json
import math

import coal
import numpy as np
import pytest

from robodesign.judge.checker import check
from robodesign.cli.entry import main
from robodesign.generate import families, generate, regenerate
from robodesign.generate.common import REFERENCE_ORDER
from robodesign.formats.geometry import coal_shapes
from robodesign.formats.module_io import load_module_set
from robodesign.design.solve import SolveSettings, solve
from robodesign.formats.task_io import load_task
from robodesign.formats.task_spec import BasePlacement, Reach

from conftest import TASKS as COBRA_TASKS

COBRA_ASSETS = COBRA_TASKS / "assets"

EASY = {"variant": "easy"}  # the earlier robodesign variants (the published ones: tests/test_generator_stats.py)
WHITMAN_SETS = [({"goals": 3, "obstacles": 3, "base": "fixed", **EASY}, 3),
                ({"goals": 5, "obstacles": 5, "base": "xyz_any_rot", **EASY}, 3)]


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
    generate("whitman2020", a, 3, seed=7, options={"goals": 3, "obstacles": 3, **EASY})
    assert _bytes(a) == _bytes(whitman[(3, "fixed")])
    b = tmp_path / "b"
    generate("whitman2020", b, 3, seed=8, options={"goals": 3, "obstacles": 3, **EASY})
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
        assert "tau" in parts["joint"].parts
        assert {"collisionFree", "selfCollisionFree", "allGoalsFulfilled"} <= set(parts)


def test_whitman_header_regenerates_the_file(whitman, tmp_path):
    f = _files(whitman[(5, "xyz_any_rot")])[2]
    tags = json.loads(f.read_text())["header"]["tags"]
    for t in ("robodesign-generate:generator=whitman2020", "robodesign-generate:version=4",
              "robodesign-generate:seed=7", "robodesign-generate:index=2", "robodesign-generate:goals=5",
              "robodesign-generate:obstacles=5", "robodesign-generate:base=xyz_any_rot",
              "robodesign-generate:variant=easy"):
        assert t in tags
    assert not any("verify=" in t for t in tags)  # --verify not given: the easy variant's default (solve)
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
            res = solve(task, ms, list(REFERENCE_ORDER), settings=SolveSettings(seed=0, plan_time=10.0))
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
    assert main(["generate", "whitman2020", "--out", str(tmp_path), "--verify", "ik"]) == 2  # only --variant easy
    assert "--verify" in capsys.readouterr().err
    assert main(["generate", "--from", str(tmp_path / "missing.json"), "--out", str(tmp_path)]) == 2
    assert list(tmp_path.glob("*.json")) == []


def test_cli_writes_folder(tmp_path, capsys):
    assert main(["generate", "whitman2020", "--out", str(tmp_path), "--count", "2", "--seed", "3",
                 "--goals", "2", "--obstacles", "1"]) == 0
    files = _files(tmp_path)
    assert [f.name for f in files] == ["whitman2020_g2o1_fixed_s3_0000.json", "whitman2020_g2o1_fixed_s3_0001.json"]
    assert len(load_task(files[0]).goals) == 2


# ---------------------------------------------------------------------------------------------------------
# liu2020 (machine tending)
QUASER = COBRA_ASSETS / "QUASER_MV205_v3_compressed.stl"


@pytest.fixture(scope="module")
def liu(tmp_path_factory):
    out = {}
    for key, machine in (("default", None), ("quaser", QUASER)):
        d = tmp_path_factory.mktemp(f"liu_{key}")
        generate("liu2020", d, 3, seed=5, options={"machine": str(machine), **EASY} if machine else EASY)
        out[key] = d
    return out


def test_default_machine_stl_and_its_work_area(tmp_path):
    from robodesign.generate.machine import analyse, default_machine_stl
    data = default_machine_stl()
    assert data == default_machine_stl() and len(data) == 84 + 50 * 120  # 10 boxes, 12 triangles each
    f = tmp_path / "m.stl"
    f.write_bytes(data)
    import trimesh
    m = trimesh.load(str(f))
    assert np.allclose(m.bounds, [[0, -0.9, 0], [1.6, 0.9, 2.1]], atol=1e-6)
    fr = analyse(str(f), 1.0)
    assert fr.yaw == 0.0
    P = np.array(fr.points)
    # the boxes in machine._BOXES: seen through the door (|y| <= 0.45, z 0.85-1.55), above the table (0.85) and
    # under the roof, in front of the back wall (x = 1.5, less the 5 cm margin)
    assert len(P) > 100
    assert np.all(np.abs(P[:, 1]) <= 0.45 + 1e-9) and np.all((P[:, 2] > 0.85) & (P[:, 2] < 1.55))
    assert P[:, 0].min() == pytest.approx(0.05) and P[:, 0].max() <= 1.45 + 1e-9
    # nothing inside the vise (x 0.55-0.75, |y| < 0.12, z < 0.95) or behind the spindle head (x > 1.05, |y| < 0.3,
    # z > 1.4)
    assert not np.any((P[:, 0] > 0.55) & (P[:, 0] < 0.75) & (np.abs(P[:, 1]) < 0.12) & (P[:, 2] < 0.95))
    assert not np.any((P[:, 0] > 1.05) & (np.abs(P[:, 1]) < 0.3) & (P[:, 2] > 1.4))
    assert np.any(np.all(np.isclose(P, [1.35, -0.05, 1.2]), axis=1))  # deep inside, free
    # the same machine turned by 90°: the analysis turns its door back to the robot and finds the same points,
    # up to grid points that lie exactly on a boundary (the door jambs at |y| = 0.45, x = 1.45 = back wall less
    # the margin; float32 STL coordinates round differently after the turn)
    R = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])
    f2 = tmp_path / "m90.stl"
    trimesh.Trimesh(m.vertices @ R.T, m.faces).export(str(f2))
    fr2 = analyse(str(f2), 1.0)
    assert fr2.yaw == pytest.approx(3 * math.pi / 2)
    P2 = np.array(fr2.points)
    inner = lambda Q: {tuple(np.round(q, 3)) for q in Q if abs(q[1]) < 0.44 and q[0] < 1.4}  # noqa: E731
    assert len(inner(P)) > 600 and inner(P2) == inner(P)


def _segment_hits(task, p, dz):
    """Whether the vertical segment from p to p + (0, 0, dz) touches the machine mesh (coal, a 2 mm prism)."""
    seg = coal.CollisionObject(coal.Box(0.002, 0.002, abs(dz)),
                               coal.Transform3s(np.eye(3), np.asarray(p, float) + [0, 0, dz / 2]))
    g = task.obstacles[0].collision[0]
    for shape in coal_shapes(g):
        obj = coal.CollisionObject(shape, coal.Transform3s(g.pose[:3, :3], g.pose[:3, 3]))
        res = coal.CollisionResult()
        if coal.collide(seg, obj, coal.CollisionRequest(), res):
            return True
    return False


def test_liu_cells(liu):
    for key, folder in liu.items():
        files = _files(folder)
        assert len(files) == 3
        assets = sorted(p.name for p in (folder / "assets").iterdir())
        assert assets == ["QUASER_MV205_v3_compressed.stl" if key == "quaser" else "robodesign_cnc_box.stl"]
        if key == "quaser":
            assert (folder / "assets" / assets[0]).read_bytes() == QUASER.read_bytes()
        for f in files:
            raw = json.loads(f.read_text())
            (mesh,) = raw["obstacles"][0]["collision"]
            assert mesh["parameters"]["file"] == f"assets/{assets[0]}"
            assert mesh["parameters"]["scale"] == (0.001 if key == "quaser" else 1)
            task = load_task(f)
            assert [g.id for g in task.goals] == ["pick", "load", "unload", "place"]
            g = task.obstacles[0].collision[0]
            assert g.file == (folder / "assets" / assets[0]).resolve()
            import trimesh
            V = trimesh.load(str(g.file)).vertices * g.scale[0]
            W = V @ g.pose[:3, :3].T + g.pose[:3, 3]
            assert W[:, 2].min() == pytest.approx(0.0, abs=1e-6)  # standing on the floor
            for goal in task.goals:
                p = goal.pose.nominal[:3, 3]
                assert _point_distance(task, p) >= 0.049
                if goal.id in ("load", "unload"):
                    # inside the machine: its mesh above (within 1.5 m) and below (within 1 m), and in line of
                    # sight from the robot's side (x decreasing) for at least 10 cm
                    assert _segment_hits(task, p, 1.55) and _segment_hits(task, p, -1.05)
                    assert 0.4 <= p[0] <= 0.6 + 0.6 + 0.1 and 0.6 - 0.05 <= p[2] <= 1.3 + 0.05
                    assert np.allclose(goal.pose.nominal[:3, 2], [1, 0, 0])  # tool points into the machine
                else:
                    assert np.allclose(goal.pose.nominal[:3, 2], [0, 0, -1])  # tool down over a tray
            bp = task.constraint(BasePlacement).pose
            ok = np.eye(4)
            ok[:3, :3] = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])  # any yaw
            ok[:3, 3] = [0.29, -0.29, 0.59]
            assert bp.valid(ok)
            ok[2, 3] = 0.62
            assert not bp.valid(ok)


def test_liu_deterministic_and_regenerates(liu, tmp_path):
    again = tmp_path / "again"
    generate("liu2020", again, 3, seed=5, options={"machine": str(QUASER), **EASY})
    assert _bytes(again) == _bytes(liu["quaser"])
    other = tmp_path / "other"
    generate("liu2020", other, 1, seed=6, options={"machine": str(QUASER), **EASY})
    assert _files(other)[0].read_bytes() != _files(liu["quaser"])[0].read_bytes()
    f = _files(liu["quaser"])[1]
    assert "robodesign-generate:machine=QUASER_MV205_v3_compressed.stl" in json.loads(f.read_text())["header"]["tags"]
    out = regenerate(f, tmp_path / "re")  # finds the machine in assets/ beside the task
    assert out.read_bytes() == f.read_bytes()


@pytest.mark.slow
def test_liu_solve_check_round_trip(liu, ms):
    for folder in liu.values():
        for f in _files(folder)[:2]:
            task = load_task(f)
            results = [solve(task, ms, list(REFERENCE_ORDER), settings=SolveSettings(seed=s, plan_time=10.0))
                       for s in range(3)]
            good = [r for r in results if r.feasible]
            assert good, (f.name, [(r.stage, r.message) for r in results])
            v = check(task, good[0].solution, ms)
            assert v.valid and v.goals == {"pick": True, "load": True, "unload": True, "place": True}


def test_liu_bad_machine_input(tmp_path, capsys):
    assert main(["generate", "liu2020", "--out", str(tmp_path), "--machine", str(tmp_path / "none.stl")]) == 2
    assert "none.stl" in capsys.readouterr().err
    assert main(["generate", "liu2020", "--out", str(tmp_path), "--machine", str(QUASER),
                 "--machine-scale", "-1"]) == 2
    fake = tmp_path / "src" / "QUASER_MV205_v3_compressed.stl"  # same name, other content
    fake.parent.mkdir()
    fake.write_bytes(QUASER.read_bytes()[:-50] + b"\0" * 50)
    d = tmp_path / "out"
    assert main(["generate", "liu2020", "--out", str(d), "--machine", str(QUASER)]) == 0
    assert main(["generate", "liu2020", "--out", str(d), "--machine", str(fake)]) == 2
    assert "other content" in capsys.readouterr().err


def test_verify_ik_skips_the_solve_but_keeps_the_goal_tests(tmp_path):
    generate("whitman2020", tmp_path, 1, seed=7, options={"verify": "ik", **EASY})
    raw = json.loads(_files(tmp_path)[0].read_text())
    assert "robodesign-generate:verify=ik" in raw["header"]["tags"]
    task = load_task(_files(tmp_path)[0])
    for g in task.goals:
        assert _point_distance(task, g.pose.nominal[:3, 3]) >= 0.06 - 1e-6


# ---------------------------------------------------------------------------------------------------------
# bpo2024 (edge cases)
def test_bpo_structures_and_spots_by_hand():
    from robodesign.generate.bpo2024 import STRUCTURES, spots
    rng = np.random.default_rng(0)
    sizes = {name: len(f(rng, "hard")) for name, f in STRUCTURES.items() if name != "random"}
    # X: 5 + 5 - 1 (shared crossing); cross: 9 + plinth; house: 3 layers of a 4 x 5 ring (14) less a 2-cube door,
    # a 4 x 5 roof and a 4-cube ridge; oven: 3 x 4 x 4 less the 2 x 2 x 2 cavity, plus 4 pillar cubes
    assert sizes == {"x": 9, "cross": 10, "house": 3 * 14 - 2 + 20 + 4, "oven": 48 - 8 + 4}
    x = frozenset(STRUCTURES["x"](rng, "hard"))
    top = [c for score, c in spots(x, "hard") if score == 3.0]
    # the four notches next to the crossing (0, 0, 2): each has three cubes as face neighbours
    assert sorted(top) == [(0, -1, 2), (0, 0, 1), (0, 0, 3), (0, 1, 2)]
    assert min(score for score, _ in spots(x, "hard")) >= 2.0
    assert min(score for score, _ in spots(x, "easy")) == 1.0
    oven = frozenset(STRUCTURES["oven"](rng, "hard"))
    best = spots(oven, "hard")[0]
    # the back cells of the 2 x 2 x 2 cavity: e.g. (1, -1, 3) has the back wall, the side wall and the oven floor
    # as face neighbours (3) and 9 of its 12 edge neighbours filled (all but the three through the cavity)
    assert best == (3 + 0.5 * 9, (1, -1, 3))
    field = STRUCTURES["random"](np.random.default_rng(1), "hard")
    assert len(field) == 14 and all(c[2] == 0 or (c[0], c[1], c[2] - 1) in field for c in field)  # stacked


@pytest.fixture(scope="module")
def bpo(tmp_path_factory):
    d = tmp_path_factory.mktemp("bpo")
    generate("bpo2024", d, 3, seed=2, options=EASY)  # mixed: x, cross, house (easy)
    h = tmp_path_factory.mktemp("bpo_hard")
    generate("bpo2024", h, 2, seed=2, options={"structure": "oven", "difficulty": "hard", **EASY})
    return d, h


@pytest.mark.slow
def test_bpo_cells(bpo):
    d, h = bpo
    assert [f.name for f in _files(d)] == ["bpo2024easy_cross_easy_s2_0001.json",
                                           "bpo2024easy_house_easy_s2_0002.json", "bpo2024easy_x_easy_s2_0000.json"]
    for folder, clearance, near in ((d, 0.08, 1), (h, 0.04, 2)):
        for f in _files(folder):
            task = load_task(f)
            assert len(task.goals) == 3
            for o in task.obstacles:
                assert o.collision[0].size == (0.25, 0.25, 0.25)
            for g in task.goals:
                p = g.pose.nominal[:3, 3]
                assert _point_distance(task, p) >= clearance - 1e-6
                # in a spot of the structure: cubes within one cube edge (hard: at least two, a pocket)
                close = [o for o in task.obstacles if _point_distance_one(o, p) <= 0.25 + 1e-6]
                assert len(close) >= near
            bp = task.constraint(BasePlacement).pose
            far = np.eye(4)
            far[:3, :3] = np.array([[-1, 0, 0], [0, 1, 0], [0, 0, -1.0]])  # upside down
            far[:3, 3] = [-0.99, 0.99, -0.99]
            assert bp.valid(far)
            far[1, 3] = 1.01
            assert not bp.valid(far)


def _point_distance_one(obstacle, p):
    class _One:
        obstacles = [obstacle]
    return _point_distance(_One, p)


@pytest.mark.slow
def test_bpo_deterministic_regenerates_and_round_trip(bpo, tmp_path, ms):
    d, h = bpo
    again = tmp_path / "again"
    generate("bpo2024", again, 2, seed=2, options={"structure": "oven", "difficulty": "hard", **EASY})
    assert _bytes(again) == _bytes(h)
    f = _files(d)[1]
    assert regenerate(f, tmp_path / "re").read_bytes() == f.read_bytes()
    for f in _files(d) + _files(h):
        task = load_task(f)
        res = solve(task, ms, list(REFERENCE_ORDER), settings=SolveSettings(seed=0, plan_time=10.0))
        assert res.feasible, (f.name, res.stage, res.message)
        assert check(task, res.solution, ms).valid


def test_regenerate_refuses_tampered_provenance(liu, tmp_path, capsys):
    f = _files(liu["quaser"])[0]
    raw = json.loads(f.read_text())
    tags = raw["header"]["tags"]
    secret = tmp_path / "secret.stl"  # a file outside the task's folder must never be read through the tags
    secret.write_bytes(QUASER.read_bytes())
    cases = {
        "escape.json": [t.replace("machine=QUASER_MV205_v3_compressed.stl", f"machine=../../{secret.name}")
                        for t in tags],
        "negative.json": [t.replace("seed=5", "seed=-1") for t in tags],
        "unknown.json": tags + ["robodesign-generate:goals=3"],  # an option liu2020 does not have
        "noversion.json": [t for t in tags if "version=" not in t],
    }
    for name, new in cases.items():
        bad = liu["quaser"] / name
        bad.write_text(json.dumps({**raw, "header": {**raw["header"], "tags": new}}))
        try:
            assert main(["generate", "--from", str(bad), "--out", str(tmp_path / "o")]) == 2, name
        finally:
            bad.unlink()
        err = capsys.readouterr().err
        assert name in err and "header" in err, err
    bad = tmp_path / "list.json"
    bad.write_text(json.dumps({"header": ["x"], "obstacles": []}))
    assert main(["generate", "--from", str(bad), "--out", str(tmp_path / "o")]) == 2
    assert not (tmp_path / "o").exists()
