"""Experiments: config validation, the results folder, resume after kill -9, identical executors."""
import csv
import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from robodesign.cli.entry import main
from robodesign.experiment.config import load_experiment

ROOT = Path(__file__).resolve().parents[1]
RD = [sys.executable, "-m", "robodesign.cli"]

SMALL = """
name: small
modules: robodesign_arm
tasks: [robodesign/pick_and_place]
cost: cyc
optimizers: [random]
budget: {budget}evals
seeds: [0, 1]
batch_size: 2
executor: {executor}
"""


def write(tmp_path, text, name="cfg.yaml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def rows(db):
    with sqlite3.connect(db) as c:
        return c.execute("SELECT r.task, r.optimizer, r.seed, e.idx, e.candidate_key, e.feasible, e.stage, e.cost "
                         "FROM evaluations e JOIN runs r USING (run_id) ORDER BY r.task, r.optimizer, r.seed, e.idx"
                         ).fetchall()


def stored_count(out: Path) -> int:
    """Evaluations committed so far in a (running) results folder; 0 while the database is not there yet."""
    try:
        return len(rows(out / "evaluations.sqlite"))
    except sqlite3.Error:
        return 0


@pytest.mark.parametrize("text,msg", [
    ("name: x\ntasks: [robodesign/pick_and_place]\noptimizers: [random]\nbudget: 5x\n",
     "cfg.yaml: budget: budget '5x'"),
    ("name: x\ntasks: [robodesign/pick_and_place]\noptimizers:\n  - random\n  - name: genetic\n    budget: 5x\n",
     "cfg.yaml: optimizers[1].budget"),
    ("name: x\ntasks: [robodesign/pick_and_place]\noptimizers: [nosuchopt]\n", "nosuchopt"),
    ("name: x\ntasks: [no/such_task]\noptimizers: [random]\n", "cfg.yaml: tasks[0]"),
    ("name: x\ntasks: [robodesign/pick_and_place]\noptimizers: [random]\nbudgte: 5evals\n",
     "cfg.yaml: budgte: unknown field 'budgte'"),
    ("name: x\ntasks: [robodesign/pick_and_place\noptimizers: [random]\n", "cfg.yaml: line"),
    ("name: x\ntasks: [robodesign/pick_and_place]\noptimizers: [random]\nexecutor: {kind: process, chunk_size: 0}\n",
     "cfg.yaml: executor.chunk_size"),
])
def test_malformed_configs_name_the_field(tmp_path, capsys, text, msg):
    cfg = write(tmp_path, text)
    code = main(["run", str(cfg), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and msg in err and "Traceback" not in err, err


def test_bundled_configs_are_valid():
    from robodesign.experiment.config import load_config
    for c in sorted((ROOT / "configs").glob("*.yaml")):
        cfg, _ = load_config(c)
        if cfg.suites:  # shape, generator family and options checked; resolving would generate 50 tasks each
            assert all(s.generate and sum(g.count for g in s.generate) >= 50 for s in cfg.suites), c
            continue
        exp, _ = load_experiment(c)
        assert list(exp.runs()), c


def test_small_run_writes_every_result_file(tmp_path, capsys):
    out = tmp_path / "res"
    code = main(["run", str(write(tmp_path, SMALL.format(budget=6, executor="serial"))), "--out", str(out),
                 "--progress", "none"])
    printed = capsys.readouterr().out
    assert code == 0 and str(out) in printed and "best robot for robodesign/pick_and_place" in printed
    for f in ("config.yaml", "meta.json", "evaluations.sqlite", "evaluations.csv", "summary.csv", "summary.md",
              "anytime_evals.csv", "anytime_time.csv", "index.html"):
        assert (out / f).is_file(), f
    meta = json.loads((out / "meta.json").read_text())
    assert meta["seeds"] == [0, 1] and "pin" in json.dumps(meta) and "cpu" in json.dumps(meta).lower()
    db = rows(out / "evaluations.sqlite")
    assert len(db) == 12 and sorted({(r[2]) for r in db}) == [0, 1]
    with open(out / "evaluations.csv") as f:
        csv_rows = list(csv.DictReader(f))
    assert len(csv_rows) == len(db)
    assert sorted(r["candidate"] for r in csv_rows) == sorted(r[4] for r in db)
    feasible_costs = sorted(float(r["cost"]) for r in csv_rows if r["feasible"] == "1")
    assert feasible_costs == sorted(r[7] for r in db if r[5])
    import matplotlib.image as mpimg
    pngs = list((out / "plots").glob("*.png"))
    assert pngs and all(mpimg.imread(p).shape[0] > 200 for p in pngs)
    # best solutions are CoBRA files that the checker accepts (re-checked here, independently of the runner)
    from robodesign.judge.checker import check
    from robodesign.formats.solution import load_solution
    from robodesign.formats.task_io import load_task
    best = sorted((out / "best").rglob("*-seed*.json"))
    best = [b for b in best if not b.name.endswith(".verdict.json")]
    if any(r[5] for r in db):
        assert best
    for b in best:
        v = check(load_task("robodesign/pick_and_place"), load_solution(b), "robodesign_arm")
        assert v.valid and v.cost == pytest.approx(min(r[7] for r in db if r[5] and f"seed{r[2]}" in b.name))


def test_resume_after_kill_equals_uninterrupted_run(tmp_path):
    cfg = write(tmp_path, SMALL.format(budget=14, executor="serial"))
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    ref = tmp_path / "ref"
    subprocess.run(RD + ["run", str(cfg), "--out", str(ref), "--progress", "none"], check=True, env=env,
                   capture_output=True, timeout=600)
    killed = tmp_path / "killed"
    p = subprocess.Popen(RD + ["run", str(cfg), "--out", str(killed), "--progress", "none"], env=env,
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 300
    n = 0
    while time.time() < deadline:
        try:
            n = len(rows(killed / "evaluations.sqlite"))
        except sqlite3.Error:
            n = 0
        if n >= 9:  # in the middle of the second run (seed 1)
            break
        time.sleep(0.05)
    p.send_signal(signal.SIGKILL)
    p.wait()
    partial = rows(killed / "evaluations.sqlite")
    assert 9 <= len(partial) < 28
    r = subprocess.run(RD + ["run", "--resume", str(killed), "--progress", "none"], env=env, capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    final, expected = rows(killed / "evaluations.sqlite"), rows(ref / "evaluations.sqlite")
    assert len(expected) == 28 and final == expected  # no loss, no duplicates, identical results
    assert len({(x[0], x[1], x[2], x[3]) for x in final}) == len(final)


def test_serial_and_process_executors_give_identical_results(tmp_path):
    outs = {}
    for name, ex in (("serial", "serial"), ("process", "process"), ("chunks", "{kind: process, chunk_size: 3}")):
        out = tmp_path / name
        code = main(["run", str(write(tmp_path, SMALL.format(budget=6, executor=ex), f"{name}.yaml")), "--out",
                     str(out), "--progress", "none", "--workers", "2"])
        assert code == 0
        outs[name] = rows(out / "evaluations.sqlite")
    assert outs["serial"] == outs["process"] == outs["chunks"] and len(outs["serial"]) == 12
    meta = json.loads((tmp_path / "chunks" / "meta.json").read_text())
    assert meta["sessions"][0]["executor"]["chunk_size"] == 3


def _pool_workers(parent: int):
    """PIDs of the process-pool workers (spawn children) of ``parent``, from /proc."""
    out = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            ppid = int((d / "stat").read_text().rsplit(")", 1)[1].split()[1])
            cmd = (d / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except (OSError, IndexError, ValueError):
            continue
        if ppid == parent and "spawn_main" in cmd:
            out.append(int(d.name))
    return sorted(out)


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(")")[-1].split()[0] != "Z"
    except OSError:
        return False


def test_process_executor_survives_a_killed_worker_and_a_killed_driver(tmp_path):
    """A pool worker killed mid-run is replaced (its candidate re-run); the driver killed later leaves no
    orphan workers behind; the resumed experiment equals a serial run."""
    cfg = write(tmp_path, SMALL.format(budget=14, executor="process"))
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    ref = tmp_path / "ref"
    subprocess.run(RD + ["run", str(cfg), "--out", str(ref), "--executor", "serial", "--progress", "none"],
                   check=True, env=env, capture_output=True, timeout=600)
    out = tmp_path / "proc"
    log = open(tmp_path / "proc.log", "w")
    p = subprocess.Popen(RD + ["run", str(cfg), "--out", str(out), "--workers", "2", "--progress", "lines"], env=env,
                         stdout=log, stderr=subprocess.STDOUT)
    try:
        killed_worker, workers = None, []
        deadline = time.time() + 300
        while time.time() < deadline and p.poll() is None:
            n = stored_count(out)
            if killed_worker is None and n >= 3:
                ws = _pool_workers(p.pid)
                if ws:
                    killed_worker = ws[0]
                    os.kill(killed_worker, signal.SIGKILL)
            elif killed_worker is not None and n >= 12:
                workers = _pool_workers(p.pid)
                p.send_signal(signal.SIGKILL)
                break
            time.sleep(0.05)
        p.wait(timeout=60)
        assert killed_worker is not None and workers, (tmp_path / "proc.log").read_text()[-3000:]
        assert killed_worker not in workers  # the pool was restarted with new workers
        t0 = time.time()
        while any(_alive(w) for w in workers) and time.time() - t0 < 120:  # a hang guard (watch: every 0.5 s)
            time.sleep(0.1)
        assert not any(_alive(w) for w in workers), "pool workers outlived the killed driver"
    finally:
        if p.poll() is None:
            p.kill()
    r = subprocess.run(RD + ["run", "--resume", str(out), "--workers", "2", "--progress", "none"], env=env,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    assert rows(out / "evaluations.sqlite") == rows(ref / "evaluations.sqlite")
    meta = json.loads((out / "meta.json").read_text())
    assert meta["sessions"][0]["executor"]["kind"] == "process" and len(meta["sessions"]) == 2
