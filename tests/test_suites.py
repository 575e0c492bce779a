"""Task suites in experiment configs (issue 12): a folder of tasks (or a generated family) run as one
suite, summarized per suite, resumable after a kill without redoing finished tasks."""
import csv
import json
import os
import shutil
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from robodesign.cli.entry import main
from robodesign.core.paths import builtin_tasks_dir

from conftest import TASKS

RD = [sys.executable, "-m", "robodesign.cli"]
BUILTIN = ("pick_and_place", "timed_follow", "welding_seam")


def _folder_suite(tmp_path, budget):
    tasks = tmp_path / "tasks"
    tasks.mkdir()
    for n in BUILTIN:
        shutil.copy(builtin_tasks_dir() / "robodesign" / f"{n}.json", tasks / f"{n}.json")
    cfg = tmp_path / "suite.yaml"
    cfg.write_text(f"name: folder_suite\nmodules: robodesign_arm\nsuites:\n  - name: cells\n    folder: tasks\n"
                   f"optimizers: [random]\nbudget: {budget}evals\nseeds: [0]\n")
    return cfg


def _rows(db):
    with sqlite3.connect(db) as c:
        return c.execute("SELECT r.task, e.idx, e.candidate_key, e.feasible, e.stage, e.cost, e.created_at "
                         "FROM evaluations e JOIN runs r USING (run_id) ORDER BY r.ordinal, e.idx").fetchall()


def test_suite_resumes_after_kill_without_redoing_finished_tasks(tmp_path):
    cfg = _folder_suite(tmp_path, budget=5)
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    ref = tmp_path / "ref"
    subprocess.run(RD + ["run", str(cfg), "--out", str(ref), "--progress", "none"], check=True, env=env,
                   capture_output=True, timeout=600)
    expected = _rows(ref / "evaluations.sqlite")
    assert len(expected) == 15 and [r[0] for r in expected[::5]] == [f"cells/{n}" for n in BUILTIN]
    killed = tmp_path / "killed"
    p = subprocess.Popen(RD + ["run", str(cfg), "--out", str(killed), "--progress", "none"], env=env,
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline, n = time.time() + 300, 0
    while time.time() < deadline and n < 7:  # the first task done, the second one under way
        try:
            n = len(_rows(killed / "evaluations.sqlite"))
        except sqlite3.Error:
            n = 0
        time.sleep(0.02)
    p.send_signal(signal.SIGKILL)
    p.wait()
    before = _rows(killed / "evaluations.sqlite")
    assert 7 <= len(before) < 15
    r = subprocess.run(RD + ["run", "--resume", str(killed), "--progress", "lines"], env=env, capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert "cells/pick_and_place random seed 0: already finished, skipped" in r.stdout
    after = _rows(killed / "evaluations.sqlite")
    # nothing stored before the kill was evaluated again (same rows, same commit times) ...
    assert after[:len(before)] == before
    # ... and the suite ends exactly as an uninterrupted one
    assert [x[:6] for x in after] == [x[:6] for x in expected]
    meta = json.loads((killed / "meta.json").read_text())
    assert meta["sessions"][-1]["new_evaluations"] == 15 - len(before)
    assert (killed / "suites.csv").is_file() and "suite cells · random: solved" in r.stdout


def test_suite_folder_errors_name_the_field(tmp_path, capsys):
    cfg = tmp_path / "bad.yaml"
    cfg.write_text("name: x\nsuites:\n  - name: s\n    folder: nowhere\noptimizers: [random]\n")
    assert main(["run", str(cfg), "--out", str(tmp_path / "o")]) == 2
    assert "bad.yaml: suites[0].folder: no such folder 'nowhere'" in capsys.readouterr().err
    cfg.write_text("name: x\nsuites:\n  - name: s\noptimizers: [random]\n")
    assert main(["run", str(cfg), "--out", str(tmp_path / "o")]) == 2
    assert "suites[0]: give the suite a 'folder'" in capsys.readouterr().err
    cfg.write_text("name: x\nsuites:\n  - name: s\n    generate: {family: nosuch, count: 2}\noptimizers: [random]\n")
    assert main(["run", str(cfg), "--out", str(tmp_path / "o")]) == 2
    assert "suites[0].generate[0]: unknown generator family 'nosuch'" in capsys.readouterr().err


FAMILIES = {  # family → generator options of a small suite: the easy variants with verify ik (quick to generate,
    # and the 16-evaluation budget solves some of them, so the statistics below are not all empty; the built-in set
    # does not solve the published variants of issue 21 in a few random evaluations). 8 evaluations solved none of the
    # easy tasks either (on main too), so the budget is 16
    "whitman2020": {"goals": 3, "obstacles": 3, "base": "xyz_any_rot", "variant": "easy", "verify": "ik"},
    "liu2020": {"machine": str(TASKS / "assets" / "DMU_125P_compress.stl"), "variant": "easy", "verify": "ik"},
    "bpo2024": {"structure": "mixed", "difficulty": "mixed", "variant": "easy", "verify": "ik"},
}


def _hand_count(db_path, tasks):
    """Per task: solved?, best cost, wall time of the first feasible evaluation, and for an unsolved task the
    furthest stage reached, counted straight from the stored evaluations."""
    out = {}
    with sqlite3.connect(db_path) as c:
        for t in tasks:
            ev = c.execute("SELECT e.feasible, e.cost, e.wall, e.stage, e.stage_index FROM evaluations e JOIN runs r "
                           "USING (run_id) WHERE r.task=? ORDER BY e.idx", (t,)).fetchall()
            feas = [e for e in ev if e[0] == 1]
            out[t] = {"solved": bool(feas), "best": min((e[1] for e in feas), default=None),
                      "first": feas[0][2] if feas else None,
                      "stopped": None if feas else sorted(ev, key=lambda e: -e[4])[0][3]}
    return out


@pytest.mark.slow
def test_suite_summary_matches_a_hand_count(tmp_path, capsys):
    suites = "".join(
        f"  - name: {fam}\n    folder: gen/{fam}\n"
        f"    generate: {{family: {fam}, count: 3, seed: 1, options: {json.dumps(opts)}}}\n"
        for fam, opts in FAMILIES.items())
    cfg = tmp_path / "fam.yaml"
    cfg.write_text(f"name: fam\nmodules: robodesign_arm\nsuites:\n{suites}optimizers: [random]\nbudget: 16evals\n")
    out = tmp_path / "out"
    assert main(["run", str(cfg), "--out", str(out), "--progress", "none"]) == 0
    printed = capsys.readouterr().out
    with open(out / "suites.csv") as f:
        summary = {r["suite"]: r for r in csv.DictReader(f)}
    with open(out / "suites_unsolved.csv") as f:
        unsolved = list(csv.DictReader(f))
    assert set(summary) == set(FAMILIES)
    solved_somewhere = 0
    for fam in FAMILIES:
        files = sorted(p for p in (tmp_path / "gen" / fam).glob("*.json") if not p.name.startswith("."))
        assert len(files) == 3 and (tmp_path / "gen" / fam / ".suite.json").is_file()
        tasks = [f"{fam}/{p.stem}" for p in files]
        hand = _hand_count(out / "evaluations.sqlite", tasks)
        s = summary[fam]
        solved = [t for t in tasks if hand[t]["solved"]]
        solved_somewhere += len(solved)
        assert (int(s["tasks"]), int(s["runs"]), int(s["solved"])) == (3, 3, len(solved))
        assert float(s["solved_pct"]) == pytest.approx(100 * len(solved) / 3)
        bests = sorted(hand[t]["best"] for t in solved)
        if bests:
            assert float(s["best_cost_min"]) == pytest.approx(bests[0])
            assert float(s["best_cost_max"]) == pytest.approx(bests[-1])
            assert float(s["best_cost_median"]) == pytest.approx(
                bests[len(bests) // 2] if len(bests) % 2 else (bests[0] + bests[1]) / 2)
            firsts = sorted(hand[t]["first"] for t in solved)
            assert float(s["first_feasible_s_max"]) == pytest.approx(firsts[-1])
        else:
            assert s["best_cost_median"] == ""
        stopped = sorted((u["task"], u["stopped_at"]) for u in unsolved if u["suite"] == fam)
        assert stopped == sorted((t, hand[t]["stopped"]) for t in tasks if not hand[t]["solved"])
        assert f"suite {fam} · random: solved {len(solved)}/3 runs" in printed
    assert solved_somewhere >= 1  # the budget finds designs: the statistics above are not all empty
    # the generated folder is recorded; the same folder with other generator arguments is refused
    text = cfg.read_text()
    cfg.write_text(text.replace("seed: 1", "seed: 2", 1))
    assert main(["run", str(cfg), "--out", str(tmp_path / "out2")]) == 2
    assert "holds tasks generated with other arguments" in capsys.readouterr().err
    # ... and so is a folder written by another version of a generator (recorded in the manifest)
    from robodesign.generate import get_family
    cfg.write_text(text)
    manifest = tmp_path / "gen" / "bpo2024" / ".suite.json"
    m = json.loads(manifest.read_text())
    assert m["versions"] == {"bpo2024": get_family("bpo2024").version}
    m["versions"]["bpo2024"] -= 1
    manifest.write_text(json.dumps(m))
    assert main(["run", str(cfg), "--out", str(tmp_path / "out3")]) == 2
    v = get_family("bpo2024").version
    assert f"holds tasks of other generator versions (bpo2024 v{v - 1}, now v{v})" in capsys.readouterr().err


def test_optimize_json_says_where_the_candidates_stopped(capsys):
    from robodesign.design.solve import STAGES
    # the nominal base of base_placement is 1.25 m from the fixture: with the base held there, designs fail
    code = main(["optimize", "robodesign/base_placement", "--modules", "robodesign_arm", "--fixed-base",
                 "--optimizer", "random", "--budget", "6evals", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 1 and not out["feasible"] and out["first_feasible_seconds"] is None
    counts = out["stage_counts"]
    assert sum(counts.values()) == out["evaluations"] == 6
    assert out["stopped_at"] == max(counts, key=STAGES.index)  # the furthest stage any candidate reached
    assert out["best"]["stage"] == out["stopped_at"]
