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

from robodesign.cli import main
from robodesign.paths import builtin_tasks_dir

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
    assert "suites[0].generate: unknown generator family 'nosuch'" in capsys.readouterr().err
