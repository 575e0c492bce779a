"""No cold-start stall: with an empty numba cache the first command runs the Python IK loop while the
kernels compile in a background process (and gets the pure-Python path's solution); once compiled, later
processes use the compiled loop at once and get the same solution. How long the cold command takes
against the pure-Python one is a benchmark, not a test (a busy machine would fail it):
experiments/bench_cold_start.py, docs/benchmarks.md "Cold start"."""
import json
import os
import subprocess
import sys
import time

import pytest

from conftest import IMPROV, TASKS

PTP3 = TASKS / "simple" / "PTP_3.json"
SOLVE = [sys.executable, "-m", "robodesign.cli", "solve", str(PTP3), "--modules", str(IMPROV),
         "--order", "1,21,4,22,5,23,12", "--json"]
PROBE = [sys.executable, "-c", "import time; t = time.perf_counter(); from robodesign.solvers import ik_kernel as k; "
         "r = k.ready(); print(r, k.compiled(), round(time.perf_counter() - t, 3))"]


def _solve(env):
    r = subprocess.run(SOLVE, env=env, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


@pytest.mark.slow
def test_cold_cache_solve_runs_the_python_loop_then_the_compiled_one(tmp_path):
    base = {k: v for k, v in os.environ.items() if k != "ROBODESIGN_JIT"}
    python = dict(base, ROBODESIGN_JIT="0", NUMBA_CACHE_DIR=str(tmp_path / "unused"))
    py = _solve(python)
    # the background compiler at the tests' priority: niced, it could starve for an hour on a loaded machine
    cold = dict(base, NUMBA_CACHE_DIR=str(tmp_path / "cold"), ROBODESIGN_COMPILE_NICE="0")
    # at the first use, an empty cache: the Python loop (no compiled kernel yet), a compiler started
    probe = subprocess.run(PROBE, env=cold, capture_output=True, text=True, timeout=120).stdout.split()
    assert probe[:2] == ["False", "False"], probe
    first = _solve(cold)
    assert first["feasible"] and first["cost"] == pytest.approx(py["cost"], abs=1e-9)

    # the background compiler fills the cache by itself; a later process then uses the kernels at once
    deadline = time.time() + 1200  # a guard against a hang, not a timing claim (about a minute on an idle machine)
    probe = None
    while time.time() < deadline:
        probe = subprocess.run(PROBE, env=cold, capture_output=True, text=True, timeout=120).stdout.split()
        if probe[1] == "True":
            break
        time.sleep(2)
    assert probe[:2] == ["True", "True"], probe
    warm = _solve(cold)
    assert warm["feasible"] and warm["cost"] == pytest.approx(py["cost"], abs=1e-9)


def test_ready_waits_for_nothing_when_the_kernel_is_off(monkeypatch):
    from robodesign.solvers import ik_kernel
    monkeypatch.setenv("ROBODESIGN_JIT", "0")
    monkeypatch.setattr(ik_kernel, "_STATE", None)
    monkeypatch.setattr(ik_kernel, "_start_compiler", lambda: pytest.fail("no compiler with ROBODESIGN_JIT=0"))
    assert not ik_kernel.ready() and ik_kernel._STATE is None
