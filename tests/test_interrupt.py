"""Ctrl-C (SIGINT to the whole process group, as a terminal sends it) and SIGTERM (to the driver) end
``robodesign optimize`` cleanly with 1 and 2 workers: exit 130, no traceback, the best design so far
written to --out (the judge accepts it) and the journal kept for --resume."""
import json
import os
import signal
import subprocess
import sys

import pytest
from conftest import IMPROV, TASKS

RD = [sys.executable, "-m", "robodesign.cli"]


def _sigint_default():
    """In the child: Ctrl-C as in a terminal, even when pytest itself runs with SIGINT ignored (a background
    job of a non-interactive shell), which the child would inherit."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
PTP3 = TASKS / "simple" / "PTP_3.json"


def optimize_until_feasible(tmp_path, workers: int, extra=()):
    """Start a long search, wait for its first feasible design (its --verbose line), return the process."""
    out = tmp_path / "best.json"
    cmd = RD + ["optimize", str(PTP3), "--modules", str(IMPROV), "--budget", "3000evals", "--workers", str(workers),
                "--out", str(out), "--verbose", *extra]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                         preexec_fn=_sigint_default, env=dict(os.environ, PYTHONUNBUFFERED="1"))
    seen = []
    for line in p.stderr:
        seen.append(line)
        if line.startswith("[") and "best —" not in line:  # "[  12]  3.1s ... best 2.83": a feasible best
            return p, out, seen
    p.wait()
    pytest.fail(f"the search ended before a feasible design: {''.join(seen)[-2000:]}")


@pytest.mark.slow
@pytest.mark.parametrize("workers, how", [(2, "SIGINT"), (1, "SIGTERM")])
def test_interrupted_optimize_keeps_its_best_checked_design(tmp_path, workers, how):
    p, out, seen = optimize_until_feasible(tmp_path, workers)
    if how == "SIGINT":
        os.killpg(p.pid, signal.SIGINT)  # what Ctrl-C in a terminal does: the driver and its workers get it
    else:
        p.send_signal(signal.SIGTERM)
    stdout, stderr = p.communicate(timeout=300)
    stderr = "".join(seen) + stderr
    assert p.returncode == 130, stderr[-3000:]
    assert "Traceback" not in stderr and "KeyboardInterrupt" not in stderr, stderr[-3000:]
    assert "interrupted" in stdout  # the summary block says how the search stopped
    assert "robodesign: interrupted after" in stderr and f"written to {out}" in stderr
    assert "resume with: robodesign optimize" in stderr and stderr.rstrip().endswith("--resume")
    assert (tmp_path / "best.journal.sqlite").is_file()
    assert not list(tmp_path.glob("*.tmp"))
    # the judge accepts the file, with the cost the search reported
    r = subprocess.run(RD + ["check", str(PTP3), str(out), "--modules", str(IMPROV), "--json"], capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    verdict = json.loads(r.stdout)
    best_line = [x for x in stdout.splitlines() if x.startswith("cost")][0]  # "cost         cyc = 3.01"
    assert verdict["valid"] and verdict["cost"] == pytest.approx(float(best_line.split("=")[1]), rel=1e-5)
    # a plain re-run refuses to overwrite the journal of the interrupted search (exit 2, one line)
    r = subprocess.run(RD + ["optimize", str(PTP3), "--modules", str(IMPROV), "--budget", "5evals", "--out", str(out)],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and "--resume" in r.stderr and "Traceback" not in r.stderr


RUN_CFG = """
name: interrupted
modules: ../shared/cobra/modules/IMPROV
tasks: [../shared/cobra/tasks/simple/PTP_3.json]
cost: cyc
optimizers: [random]
budget: 2000evals
seeds: [0]
batch_size: 8
executor: process
"""


@pytest.mark.slow
def test_interrupted_run_prints_its_resume_command(tmp_path):
    """Ctrl-C on `robodesign run` with 2 worker processes: exit 130, no traceback from the driver or a worker,
    the exact resume command, the session recorded as interrupted."""
    import sqlite3
    import time
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text(RUN_CFG.replace("../shared/cobra", str(IMPROV.parents[1])))
    out = tmp_path / "res"
    p = subprocess.Popen(RD + ["run", str(cfg), "--out", str(out), "--workers", "2", "--no-report"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                         preexec_fn=_sigint_default)

    def stored() -> int:
        try:
            with sqlite3.connect(out / "evaluations.sqlite") as c:
                return c.execute("SELECT COUNT(*) FROM evaluations").fetchone()[0]
        except sqlite3.Error:
            return 0
    deadline = time.time() + 600
    while p.poll() is None and stored() < 5 and time.time() < deadline:
        time.sleep(0.2)
    assert p.poll() is None, p.communicate()
    os.killpg(p.pid, signal.SIGINT)
    stdout, stderr = p.communicate(timeout=300)
    assert p.returncode == 130, stdout + stderr
    assert "Traceback" not in stdout + stderr and "KeyboardInterrupt" not in stdout + stderr, stdout + stderr
    assert f"continue with: robodesign run --resume {out}" in stderr
    meta = json.loads((out / "meta.json").read_text())
    assert meta["sessions"][-1]["status"] == "interrupted: KeyboardInterrupt"
    assert stored() >= 5  # kept for the resume (which tests/test_experiment.py checks to be exact)


@pytest.mark.slow
def test_interrupted_serve_shuts_down_quietly(tmp_path):
    """Ctrl-C on `robodesign serve` (its checker processes in the same process group): a clean shutdown,
    no traceback from the server or a checker process."""
    import socket
    import time
    import urllib.request
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    p = subprocess.Popen(RD + ["serve", "--port", str(port), "--data", str(tmp_path / "data"), "--workers", "1",
                               "--no-builtin"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                         start_new_session=True, preexec_fn=_sigint_default)
    deadline = time.time() + 300
    while time.time() < deadline and p.poll() is None:
        try:
            urllib.request.urlopen(f"http://127.0.0.1:{port}/api/queue", timeout=5).read()
            break
        except OSError:
            time.sleep(0.5)
    assert p.poll() is None, p.communicate()[0]
    os.killpg(p.pid, signal.SIGINT)
    out = p.communicate(timeout=120)[0]
    assert p.returncode == 0, out
    assert "Application shutdown complete" in out and "Traceback" not in out and "KeyboardInterrupt" not in out, out
