"""Benchmark: the first command after an install (empty numba cache) against a warm cache and against the
pure-Python IK loop.

    flock /tmp/robodesign-bench.lock nice -n 5 .venv/bin/python experiments/bench_cold_start.py \
        [--rounds 3] [--run-config configs/default.yaml] [--no-run]

For ``robodesign solve`` of simple/PTP_3 with IMPROV (order 1,21,4,22,5,23,12) and for ``robodesign run``
(the built-in demo), each in a fresh process:

* cold: ``NUMBA_CACHE_DIR`` set to a new, empty folder (what a fresh install sees): the IK runs the Python
  loop while the kernels compile in a background process;
* warm: the same folder after that background compilation has finished: the compiled loop from the start;
* python: ``ROBODESIGN_JIT=0``, the pure-Python loop.

Times are wall clock of the whole process (imports included); for ``run`` also the time until the first
evaluation line. Rounds alternate the three modes; medians are printed with every round's value.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE.parent / "docs" / "results"  # the measured records behind docs/benchmarks.md
ROOT = HERE.parent
SHARED = ROOT.parent / "shared" / "cobra"
RD = [sys.executable, "-m", "robodesign.cli"]
SOLVE = RD + ["solve", str(SHARED / "tasks" / "simple" / "PTP_3.json"), "--modules", str(SHARED / "modules" / "IMPROV"),
              "--order", "1,21,4,22,5,23,12", "--json"]
PROBE = [sys.executable, "-c", "from robodesign.solvers import ik_kernel as k; print(k.compiled())"]


def timed(cmd, env, first_line=None):
    """(wall seconds, seconds to the first stdout line containing ``first_line``, stdout)."""
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    first, lines = None, []
    for line in p.stdout:
        lines.append(line)
        if first is None and first_line and first_line in line:
            first = time.perf_counter() - t0
    rc = p.wait()
    wall = time.perf_counter() - t0
    if rc not in (0, 1):
        raise RuntimeError(f"{cmd[3]} exited {rc}")
    return wall, first, "".join(lines)


def wait_compiled(env, limit=900.0) -> float:
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < limit:
        if subprocess.run(PROBE, env=env, capture_output=True, text=True).stdout.strip() == "True":
            return time.perf_counter() - t0
        time.sleep(1.0)
    raise RuntimeError("the background compilation did not finish")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--run-config", default=str(ROOT / "configs" / "default.yaml"))
    ap.add_argument("--no-run", action="store_true", help="measure only solve")
    ap.add_argument("--out", default=str(RESULTS / "cold_start.json"))
    a = ap.parse_args()
    base = {k: v for k, v in os.environ.items() if k not in ("ROBODESIGN_JIT", "NUMBA_CACHE_DIR")}
    base["PYTHONUNBUFFERED"] = "1"
    tmp = Path(tempfile.mkdtemp(prefix="rd-cold-"))
    res = {"solve": {"cold": [], "warm": [], "python": []}, "run": {"cold": [], "warm": [], "python": []},
           "compile_wait": []}
    cmds = {"solve": (SOLVE, None)}
    if not a.no_run:
        cmds["run"] = (RD + ["run", a.run_config, "--progress", "lines", "--no-report"], ": eval 1")
    try:
        for r in range(a.rounds):
            for what, (cmd, marker) in cmds.items():
                cache = tmp / f"cache-{what}-{r}"
                envs = {"cold": dict(base, NUMBA_CACHE_DIR=str(cache)), "warm": dict(base, NUMBA_CACHE_DIR=str(cache)),
                        "python": dict(base, ROBODESIGN_JIT="0", NUMBA_CACHE_DIR=str(tmp / "unused"))}
                order = ["python", "cold", "warm"] if r % 2 == 0 else ["cold", "warm", "python"]
                for mode in order:
                    c = list(cmd)
                    if what == "run":
                        c += ["--out", str(tmp / f"run-{mode}-{r}")]
                    if mode == "warm":
                        res["compile_wait"].append(wait_compiled(envs["warm"]))
                    wall, first, _ = timed(c, envs[mode], marker)
                    res[what][mode].append({"wall": wall, "first_evaluation": first})
                    print(f"round {r} {what:5s} {mode:6s} {wall:6.2f} s" +
                          (f"  (first evaluation at {first:.2f} s)" if first is not None else ""), flush=True)
        print()
        for what in cmds:
            med = {m: statistics.median(x["wall"] for x in res[what][m]) for m in ("cold", "warm", "python")}
            print(f"{what:5s} median wall: cold {med['cold']:.2f} s, warm {med['warm']:.2f} s, python {med['python']:.2f}"
                  f" s; cold/python {med['cold'] / med['python']:.2f}, warm/python {med['warm'] / med['python']:.2f}")
            if what == "run":
                f = {m: statistics.median(x["first_evaluation"] for x in res[what][m]) for m in ("cold", "warm", "python")}
                print(f"run   median time to the first evaluation: cold {f['cold']:.2f} s, warm {f['warm']:.2f} s, "
                      f"python {f['python']:.2f} s")
        print(f"background compilation finished {statistics.median(res['compile_wait']):.1f} s (median) after the "
              f"cold command ended")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(res, indent=1))
    print(f"written {a.out}")


if __name__ == "__main__":
    main()
