"""Ray executor against a real local Ray cluster (started with ``ray start --head`` on 127.0.0.1); a worker
is killed mid-run and nothing is lost: the results equal a serial run's."""
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from test_experiment import SMALL, rows, stored_count, write

pytestmark = pytest.mark.slow
BIN = Path(sys.executable).parent
RAY = shutil.which("ray", path=str(BIN)) or shutil.which("ray")
ENV = dict(os.environ, RAY_USAGE_STATS_ENABLED="0", RAY_AUTH_MODE="disabled", PYTHONUNBUFFERED="1")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def actor_pids():
    out = subprocess.run(["ps", "-ww", "-eo", "pid,args"], capture_output=True, text=True).stdout
    return [int(line.split()[0]) for line in out.splitlines() if "ray::EvaluatorActor" in line]


@pytest.mark.skipif(RAY is None, reason="the ray command line is not installed")
def test_ray_cluster_run_survives_a_killed_worker(tmp_path):
    cfg = write(tmp_path, SMALL.format(budget=10, executor="serial"))
    ref = tmp_path / "serial"
    subprocess.run([sys.executable, "-m", "robodesign.cli", "run", str(cfg), "--out", str(ref), "--progress", "none"],
                   check=True, env=ENV, capture_output=True, timeout=600)
    port = free_port()
    subprocess.run([RAY, "start", "--head", f"--port={port}", "--node-ip-address=127.0.0.1", "--num-cpus=2",
                    "--include-dashboard=false", "--disable-usage-stats"], check=True, env=ENV, capture_output=True,
                   timeout=180)
    try:
        out = tmp_path / "ray"
        p = subprocess.Popen([sys.executable, "-m", "robodesign.cli", "run", str(cfg), "--out", str(out),
                              "--executor", "ray", "--address", f"127.0.0.1:{port}", "--workers", "2",
                              "--progress", "lines"], env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             text=True)
        killed = None
        deadline = time.time() + 300
        while time.time() < deadline and p.poll() is None:
            n = stored_count(out)
            pids = actor_pids()
            if n >= 3 and pids:
                killed = pids[0]
                os.kill(killed, signal.SIGKILL)  # a worker dies in the middle of the run
                break
            time.sleep(0.05)
        log, _ = p.communicate(timeout=600)
        assert p.returncode == 0, log
        assert killed is not None, "no Ray worker was found to kill"
        assert rows(out / "evaluations.sqlite") == rows(ref / "evaluations.sqlite")  # nothing lost, nothing doubled
        assert len(rows(ref / "evaluations.sqlite")) == 20
    finally:
        subprocess.run([RAY, "stop", "--force"], env=ENV, capture_output=True, timeout=120)
