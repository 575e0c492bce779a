"""Experiment results survive damage: a truncated, garbled, missing or empty results database, or one that
lost its WAL, is a clear exit 2 on ``--resume`` (never a traceback, never a silent start over); ``--restart``
starts over with the old files moved aside; the WAL is checkpointed so the .sqlite file alone keeps the data."""
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
from robodesign.design.evaluator import Evaluation
from robodesign.experiment.storage import DamagedDatabase, ExperimentDB
from robodesign.design.search_space import Candidate
from test_experiment import SMALL as SMALL_CONFIG

RD = [sys.executable, "-m", "robodesign.cli"]
SMALL = SMALL_CONFIG.replace("{executor}", "serial")


def rows(db):
    con = sqlite3.connect(db)
    try:
        return con.execute("SELECT r.seed, e.idx, e.candidate_key, e.feasible, e.stage, e.cost FROM evaluations e "
                           "JOIN runs r USING (run_id) ORDER BY r.seed, e.idx").fetchall()
    finally:
        con.close()


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """A finished 2-run experiment (2 × 10 evaluations, each run with a feasible best design) and its rows."""
    d = tmp_path_factory.mktemp("finished")
    (d / "cfg.yaml").write_text(SMALL.format(budget=10))
    out = d / "res"
    assert main(["run", str(d / "cfg.yaml"), "--out", str(out), "--progress", "none", "--no-report"]) == 0
    return out, rows(out / "evaluations.sqlite")


def _garble_pages(f: Path):
    """Overwrite the first 64 bytes of every page but the first two (b-tree page headers) with garbage."""
    data = bytearray(f.read_bytes())
    for off in range(2 * 4096, len(data), 4096):
        data[off:off + 64] = b"\xde\xad\xbe\xef" * 16
    f.write_bytes(bytes(data))


DAMAGE = {
    "truncated": (lambda f: os.truncate(f, f.stat().st_size // 2), "is damaged"),
    "garbled pages": (_garble_pages, "is damaged"),
    "garbled header": (lambda f: f.write_bytes(b"this is no SQLite file" * 10 + f.read_bytes()[220:]),
                       "is damaged (file is not a database)"),
    "missing": (lambda f: f.unlink(), "is missing, but meta.json records 20 stored evaluations"),
    "empty": (lambda f: f.write_bytes(b""), "is an empty file, but meta.json records 20 stored evaluations"),
}


@pytest.mark.parametrize("case", list(DAMAGE))
def test_damaged_database_refuses_resume_and_restart_starts_over(finished, tmp_path, capsys, case):
    src, expected = finished
    out = tmp_path / "res"
    shutil.copytree(src, out)
    db = out / "evaluations.sqlite"
    damage, msg = DAMAGE[case]
    damage(db)
    damaged_bytes = db.read_bytes() if db.exists() else None

    code = main(["run", "--resume", str(out), "--progress", "none", "--no-report"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert f"{db}: the results database {msg}" in err and f"--resume {out} --restart" in err, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    # refused means untouched: the damaged file is still there, byte for byte
    assert (db.read_bytes() if db.exists() else None) == damaged_bytes

    code = main(["run", "--resume", str(out), "--restart", "--progress", "none", "--no-report"])
    assert code == 0, capsys.readouterr().err
    assert rows(db) == expected and len(expected) == 20  # started over: the same 20 evaluations again
    meta = json.loads((out / "meta.json").read_text())
    assert meta["stored_evaluations"] == 20
    restart = meta["restarts"][-1]
    assert restart["stored_evaluations"] == 20
    aside = out / restart["moved_to"]
    assert "best" in restart["moved"] and (aside / "best").is_dir()
    if damaged_bytes is not None:  # the damaged file is kept aside, never deleted
        assert (aside / "evaluations.sqlite").read_bytes() == damaged_bytes


def test_database_with_fewer_evaluations_than_meta_records_is_refused_every_time(finished, tmp_path, capsys):
    """An older copy of the database (here: the last 9 evaluations of seed 1 gone) is refused, and the refusal
    leaves meta.json's record alone, so asking again is refused again."""
    src, expected = finished
    out = tmp_path / "res"
    shutil.copytree(src, out)
    con = sqlite3.connect(out / "evaluations.sqlite")
    with con:
        con.execute("DELETE FROM evaluations WHERE idx >= 1 AND run_id = (SELECT run_id FROM runs WHERE seed = 1)")
    con.close()
    for _ in range(2):
        assert main(["run", "--resume", str(out), "--progress", "none", "--no-report"]) == 2
        err = capsys.readouterr().err
        assert "the results database holds only 11 evaluations, but meta.json records 20 stored evaluations" in err
        assert json.loads((out / "meta.json").read_text())["stored_evaluations"] == 20
    assert len(rows(out / "evaluations.sqlite")) == 11


def test_restart_needs_resume(tmp_path, capsys):
    (tmp_path / "cfg.yaml").write_text(SMALL.format(budget=2))
    code = main(["run", str(tmp_path / "cfg.yaml"), "--restart", "--out", str(tmp_path / "r")])
    err = capsys.readouterr().err
    assert code == 2 and "--restart needs --resume DIR" in err and not (tmp_path / "r").exists()


def _evaluation(k: int) -> Evaluation:
    return Evaluation(candidate=Candidate(("1", str(20 + k), "12"), ()), feasible=False, cost=None, score=1e9 + k,
                      stage="ik", stage_index=0, goals_reached=0, seconds=0.01, seed=k)


@pytest.mark.parametrize("period,copied", [(0.0, 7), (1e9, 0)])
def test_checkpoints_keep_the_sqlite_file_complete_while_the_writer_runs(tmp_path, period, copied):
    """With checkpoints the .sqlite copied alone (no -wal) while the writer is still open holds every
    evaluation; without them (period 1e9) it holds none: everything sits in the -wal file."""
    seen = []
    db = ExperimentDB(tmp_path / "e.sqlite", checkpoint_seconds=period, on_checkpoint=seen.append)
    db.ensure_run("r", "t", "random", "random", 0, 0, "7evals", 1)
    storage = db.storage("r")
    for k in range(7):
        storage.append(k, _evaluation(k))
    shutil.copy(tmp_path / "e.sqlite", tmp_path / "copy.sqlite")
    assert (tmp_path / "e.sqlite-wal").exists()
    try:
        assert len(sqlite3.connect(tmp_path / "copy.sqlite").execute("SELECT idx FROM evaluations").fetchall()) \
            == copied
    except sqlite3.OperationalError:  # no table at all in the main file: the schema is in the WAL, too
        assert copied == 0
    assert seen == ([1, 2, 3, 4, 5, 6, 7] if period == 0 else [])
    db.close()  # the final checkpoint
    assert seen[-1] == 7
    shutil.copy(tmp_path / "e.sqlite", tmp_path / "copy2.sqlite")
    assert len(sqlite3.connect(tmp_path / "copy2.sqlite").execute("SELECT idx FROM evaluations").fetchall()) == 7


def test_damaged_database_error_from_the_storage_layer(tmp_path):
    f = tmp_path / "e.sqlite"
    f.write_bytes(b"\x00garbage" * 1000)
    with pytest.raises(DamagedDatabase) as e:
        ExperimentDB(f)
    assert str(e.value).startswith(f"{f}: the results database is damaged (file is not a database)")


@pytest.mark.slow
def test_killed_run_copied_without_its_wal_resumes_exactly_and_an_older_copy_is_refused(tmp_path, capsys):
    """kill -9 mid-run, then copy the folder without the -wal file: the .sqlite alone holds at least what
    meta.json records (checkpoints), and resuming the copy gives exactly the uninterrupted run. Putting that
    older copy back into the finished folder (meta.json records all 80) is refused, naming the lost -wal."""
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text(SMALL.format(budget=40))
    ref = tmp_path / "ref"
    assert main(["run", str(cfg), "--out", str(ref), "--progress", "none", "--no-report"]) == 0
    expected = rows(ref / "evaluations.sqlite")
    assert len(expected) == 80

    killed = tmp_path / "killed"
    p = subprocess.Popen(RD + ["run", str(cfg), "--out", str(killed), "--progress", "none", "--no-report"],
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    claimed = 0
    deadline = time.time() + 300
    try:
        while time.time() < deadline and claimed < 9:
            try:
                claimed = json.loads((killed / "meta.json").read_text()).get("stored_evaluations", 0)
            except (OSError, ValueError):
                pass
            time.sleep(0.05)
    finally:
        p.send_signal(signal.SIGKILL)
        p.wait()
    assert claimed >= 9
    copy = tmp_path / "copy"
    copy.mkdir()
    for f in ("config.yaml", "meta.json", "evaluations.sqlite"):
        shutil.copy(killed / f, copy / f)
    meta_claims = json.loads((copy / "meta.json").read_text())["stored_evaluations"]
    alone = rows(copy / "evaluations.sqlite")
    assert meta_claims >= 9 and meta_claims <= len(alone) < 80
    assert alone == expected[:len(alone)]  # the same evaluations as the uninterrupted run, so far

    assert main(["run", "--resume", str(copy), "--progress", "none", "--no-report"]) == 0
    assert rows(copy / "evaluations.sqlite") == expected

    # the older copy put back in place of the finished database: meta.json says 80
    older = tmp_path / "older"
    shutil.copytree(copy, older)
    assert not (older / "evaluations.sqlite-wal").exists()  # a clean close checkpointed and removed it
    shutil.copy(killed / "evaluations.sqlite", older / "evaluations.sqlite")
    capsys.readouterr()
    assert main(["run", "--resume", str(older), "--progress", "none", "--no-report"]) == 2
    err = capsys.readouterr().err
    assert (f"holds only {len(alone)} evaluations, but meta.json records 80 stored evaluations (its -wal file is "
            "gone") in err, err


def test_a_run_made_under_other_evaluation_rules_is_refused(finished, tmp_path, capsys):
    """Results of an older robodesign (no rules recorded: rules 1) with a run left unfinished: --resume stops with
    exit 2, names the database and the rules, prints no traceback and leaves the database as it was."""
    src, expected = finished
    out = tmp_path / "res"
    shutil.copytree(src, out)
    db = out / "evaluations.sqlite"
    con = sqlite3.connect(db)
    with con:
        con.execute("DELETE FROM info WHERE key LIKE 'rules:%'")
        con.execute("UPDATE runs SET status='running' WHERE seed = 1")
    con.close()
    before = rows(db)
    code = main(["run", "--resume", str(out), "--progress", "none", "--no-report"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert str(db) in err and "made under evaluation rules 1, this robodesign evaluates under rules" in err, err
    assert "Traceback" not in err
    assert rows(db) == before == expected
