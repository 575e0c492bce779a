"""The faithful generators (issue 21): every generated file passes an independent reader of the reference's
tolerance bounds (plain json + the rules of FORMAT.md §2.5 / timor-python Tolerance: Theta_R in [0, π],
N_x, N_y, N_z in [−π, π], lo ≤ hi), writes exact π, and the statistics of 40 tasks per family match the
published figures (issue 21's table) within sample margins."""
import json
import math

import numpy as np
import pytest

from robodesign.generate import generate
from robodesign.generate.common import set_reach_bound
from robodesign.generate.stats import box_signed_distance, folder_stats

from conftest import TASKS as COBRA_TASKS

QUASER = COBRA_TASKS / "assets" / "QUASER_MV205_v3_compressed.stl"
# allowed ranges of each projection (FORMAT.md §2.5; the reference raises ValueError outside them)
ALLOWED = {"x": (-math.inf, math.inf), "y": (-math.inf, math.inf), "z": (-math.inf, math.inf),
           "r_cyl": (0.0, math.inf), "phi_cyl": (-math.pi, math.pi), "r_sph": (0.0, math.inf),
           "theta": (0.0, math.pi), "phi_sph": (-math.pi, math.pi), "N_x": (-math.pi, math.pi),
           "N_y": (-math.pi, math.pi), "N_z": (-math.pi, math.pi), "Theta_R": (0.0, math.pi)}
SUITES = {
    "w33fixed": ("whitman2020", {"goals": 3, "obstacles": 3, "base": "fixed"}),
    "w33free": ("whitman2020", {"goals": 3, "obstacles": 3, "base": "xyz_any_rot"}),
    "w55free": ("whitman2020", {"goals": 5, "obstacles": 5, "base": "xyz_any_rot"}),
    "liu": ("liu2020", {"machine": str(QUASER)}),
    "bpo": ("bpo2024", {}),
}


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    out = {}
    for key, (fam, opts) in SUITES.items():
        d = tmp_path_factory.mktemp(key)
        out[key] = generate(fam, d, 40, seed=0, options=opts)
    return out


def _poses(node):
    """Every tolerated pose (a dict with 'nominal') anywhere in a task's JSON."""
    if isinstance(node, dict):
        if "nominal" in node:
            yield node
        for v in node.values():
            yield from _poses(v)
    elif isinstance(node, list):
        for v in node:
            yield from _poses(v)


def test_every_bound_is_in_the_reference_range(folders):
    seen = set()
    for files in folders.values():
        for f in files:
            for pose in _poses(json.loads(f.read_text())):
                proj, tol = pose.get("toleranceProjection", []), pose.get("tolerance", [])
                assert len(proj) == len(tol)
                for p, (lo, hi) in zip(proj, tol):
                    a, b = ALLOWED[p]
                    assert a - 1e-12 <= lo <= hi <= b + 1e-12 and a <= lo and hi <= b, (f.name, p, lo, hi)
                    seen.add(p)
    assert {"x", "y", "z", "Theta_R"} <= seen


def test_goals_are_full_pose_with_the_reference_default_tolerance(folders):
    for files in folders.values():
        for f in files[:5]:
            text = f.read_text()
            for g in json.loads(text)["goals"]:
                gp = g["goalPose"]
                assert gp["toleranceProjection"] == ["x", "y", "z", "Theta_R"]
                assert gp["tolerance"] == [[-0.001, 0.001]] * 3 + [[0, math.pi / 360]]  # 0.5° exactly
                R = np.array(gp["nominal"])[:3, :3]
                assert np.allclose(R.T @ R, np.eye(3), atol=1e-9) and np.linalg.det(R) == pytest.approx(1.0)
            assert "0.008726646259971648" in text  # π/360 with all its digits, not rounded to 10 decimals


def test_the_easy_variant_writes_exact_pi(tmp_path):
    """The old writer rounded π to 3.1415926536 > π, which the reference rejects in Theta_R and N_z bounds."""
    from robodesign.generate.common import NEG_PI, PI, task_text
    text = task_text({"a": [0.0, PI], "b": [NEG_PI, PI], "c": math.pi})
    assert json.loads(text) == {"a": [0, math.pi], "b": [-math.pi, math.pi], "c": 3.1415926536}
    assert json.loads(text)["b"][1] <= math.pi


def test_constraints_and_bases_as_published(folders):
    def kinds(f):
        return [(c["type"], tuple(c.get("parts", ()))) for c in json.loads(f.read_text())["constraints"]]
    for key, files in folders.items():
        for f in files:
            k = kinds(f)
            base = [c for c in json.loads(f.read_text())["constraints"] if c["type"] == "basePlacement"][0]["pose"]
            assert ("selfCollisionFree", ()) not in k
            if key.startswith("w"):
                assert sorted(k) == sorted([("basePlacement", ()), ("joint", ("q", "tau")), ("collisionFree", ()),
                                            ("allGoalsFulfilled", ())])
            elif key == "bpo":
                assert ("joint", ("q", "dq", "tau")) in k and len(k) == 4
            else:
                assert ("joint", ("q", "tau")) in k and ("allGoalsFulfilledInOrder", ()) in k
            if key == "w33fixed":
                assert base["toleranceProjection"] == ["x", "y", "z", "Theta_R"]
                assert base["tolerance"] == [[-0.001, 0.001]] * 3 + [[0, math.pi / 360]]
            else:  # x, y, z ± 1 m, no rotation projection: any rotation
                assert base["toleranceProjection"] == ["x", "y", "z"] and base["tolerance"] == [[-1, 1]] * 3


def test_signed_box_distance_by_hand():
    box = {"type": "box", "parameters": {"x": 0.25, "y": 0.25, "z": 0.25},
           "pose": [[1, 0, 0, 1], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}
    assert box_signed_distance([1, 0, 0], box) == pytest.approx(-0.125)
    assert box_signed_distance([1.125 + 0.3, 0, 0], box) == pytest.approx(0.3)
    assert box_signed_distance([1.125 + 0.3, 0.125 + 0.4, 0], box) == pytest.approx(0.5)


def test_reach_bound_of_the_built_in_set_by_hand():
    # robodesign_arm (assets/modules/robodesign_arm/README.md): longest base 0.5 m (pedestal), longest joint
    # module 0.212 m (joint_L_pitch), longest link 0.5 m (link_L_500), longest end effector 0.15 m; at most 6
    # joints and one link before, between and after them
    assert set_reach_bound() == pytest.approx(0.5 + 6 * 0.212 + 7 * 0.5 + 0.15)


# published figures (issue 21) and the margins a sample of 40 tasks is held to
def test_statistics_match_the_published_figures(folders):
    s = {k: folder_stats(v) for k, v in folders.items()}
    for key in ("w33fixed", "w33free", "w55free"):
        d = s[key].distances
        assert d.min() < 0.3 and 0.85 <= np.median(d) <= 1.10 and 1.35 <= d.max() <= 1.75  # 0.09 / 0.97 / 1.54
        assert 0.40 <= s[key].below <= 0.67  # 51–67 %
        c = s[key].clearances
        assert 0.0 <= c.min() <= 0.1 and 0.4 <= np.median(c) <= 0.8  # 0.00 / 0.5–0.6
        assert s[key].obstacle_kinds == ["box 0.25 m"]
    assert set(s["w33free"].obstacle_counts) == {3} and set(s["w55free"].obstacle_counts) == {5}
    d = s["bpo"].distances
    assert 0.2 <= d.min() <= 0.6 and 1.1 <= np.median(d) <= 1.5 and 2.3 <= d.max() <= 3.2  # 0.35 / 1.30 / 2.72
    assert 0.40 <= s["bpo"].below <= 0.65  # 52 %
    assert s["bpo"].clearances.min() > 0 and 0.3 <= np.median(s["bpo"].clearances) <= 0.55  # −0.12 / 0.40
    assert 4 <= min(s["bpo"].obstacle_counts) and max(s["bpo"].obstacle_counts) <= 20
    d = s["liu"].distances
    assert 0.1 <= d.min() <= 0.35 and 0.5 <= np.median(d) <= 0.75 and 0.75 <= d.max() <= 1.0  # 0.15 / 0.66 / 0.90
    assert 0.10 <= s["liu"].below <= 0.35  # 21 %
    assert set(s["liu"].obstacle_counts) == {1} and s["liu"].obstacle_kinds == ["mesh"]


def test_easy_variant_cells_pass_the_reader_too():
    """The easy variants' constraint blocks hold π and −π bounds (Theta_R, N_z): written exactly as well."""
    from robodesign.generate import bpo2024, liu2020, whitman2020
    from robodesign.generate.common import Provenance, task_text
    prov = Provenance("x", 1, 0, 0, ())
    cells = [liu2020._cell("t", prov, "assets/m.stl", 1.0, np.eye(4), [], {}),
             bpo2024._cell("t", prov, {"structure": "x", "difficulty": "easy"}, [], 0.0, []),
             {"constraints": [whitman2020.base_constraint("xyz_any_rot", 1.0)]}]
    bounds = {}
    for cell in cells:
        for pose in _poses(json.loads(task_text(cell))):
            for p, (lo, hi) in zip(pose.get("toleranceProjection", []), pose.get("tolerance", [])):
                a, b = ALLOWED[p]
                assert a <= lo <= hi <= b, (p, lo, hi)
                bounds.setdefault(p, set()).add((lo, hi))
    assert (-math.pi, math.pi) in bounds["N_z"] and (0, math.pi) in bounds["Theta_R"]


def test_published_variants_are_deterministic_and_regenerate(folders, tmp_path):
    from robodesign.generate import regenerate
    for key in ("w55free", "bpo", "liu"):
        f = folders[key][7]
        tags = json.loads(f.read_text())["header"]["tags"]
        assert "robodesign-generate:variant=published" in tags and not any("verify=" in t for t in tags)
        out = regenerate(f, tmp_path / key)
        assert out.name == f.name and out.read_bytes() == f.read_bytes()
    # the BPO24 archetypes cycle with the task index; the level alternates, shifted by one every 10 tasks
    names = [f.name for f in folders["bpo"]]
    assert names[:2] == ["bpo2024_middle_oven_medium_s0_0000.json", "bpo2024_oven_hard_s0_0001.json"]
    assert names[10] == "bpo2024_middle_oven_hard_s0_0010.json" and names[12] == "bpo2024_cross_hard_s0_0012.json"
