"""Benchmark: how long the test suite (or a group of test files) takes, per file, serially and with pytest-xdist.

    nice -n 10 .venv/bin/python experiments/bench_test_suite.py [--workers 2] [--junit OUT.xml] [FILES...]

Runs ``python -m pytest -q -p no:cacheprovider --junitxml=...`` (with ``-n N`` when ``--workers`` is given; README's
test command is ``-n 2``) on FILES (default: the whole suite), then prints the wall time, the CPU seconds of
pytest and of every process it waited for (its workers, the CLI subprocesses and process pools of the tests),
the load average before and after, and per file the sum of its tests' durations (setup, call and teardown, as
pytest's junit XML records them). With ``-n 2`` the per-file sums are the time each file held a worker; wall
time is what the suite takes. ``--compare A.xml B.xml`` prints two earlier runs' per-file sums side by side.
docs/benchmarks.md, "Test suite duration".
"""
from __future__ import annotations

import argparse
import collections
import os
import resource
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def per_file(junit: Path) -> tuple[dict[str, float], collections.Counter]:
    """Sum of test durations per test file, and the count of passed / failed / skipped tests."""
    root = ET.parse(junit).getroot()
    files: dict[str, float] = collections.defaultdict(float)
    outcome: collections.Counter = collections.Counter()
    for case in root.iter("testcase"):
        name = (case.get("classname") or "?").split(".")
        module = next((p for p in name if p.startswith("test_")), name[-1])
        files[f"{module}.py"] += float(case.get("time") or 0)
        kind = "failed" if case.find("failure") is not None or case.find("error") is not None else \
            "skipped" if case.find("skipped") is not None else "passed"
        outcome[kind] += 1
    return dict(files), outcome


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="*", help="test files (default: the whole suite)")
    ap.add_argument("--workers", type=int, default=0, help="pytest-xdist workers (-n); 0: one process")
    ap.add_argument("--junit", type=Path, help="keep the junit XML here (default: a temporary file)")
    ap.add_argument("--compare", nargs=2, type=Path, metavar=("A.xml", "B.xml"),
                    help="print the per-file sums of two earlier runs side by side and exit")
    args = ap.parse_args(argv)
    if args.compare:
        (a, _), (b, _) = (per_file(x) for x in args.compare)
        print(f"{'file':34s} {args.compare[0].name:>12s} {args.compare[1].name:>12s}")
        for f in sorted(set(a) | set(b), key=lambda f: -max(a.get(f, 0), b.get(f, 0))):
            print(f"{f:34s} {a.get(f, 0):12.1f} {b.get(f, 0):12.1f}")
        print(f"{'sum':34s} {sum(a.values()):12.1f} {sum(b.values()):12.1f}")
        return 0
    junit = args.junit or Path(tempfile.mkdtemp()) / "junit.xml"
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", f"--junitxml={junit}",
           *(["-n", str(args.workers)] if args.workers else []), *args.files]
    load_before = os.getloadavg()
    t0 = time.perf_counter()
    r = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    load_after = os.getloadavg()
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    print(r.stdout.strip().splitlines()[-1] if r.stdout.strip() else r.stderr[-2000:])
    files, outcome = per_file(junit)
    print(f"command   {' '.join(cmd[1:])}")
    print(f"wall      {wall:.0f} s ({wall / 60:.1f} min); CPU {ru.ru_utime + ru.ru_stime:.0f} s "
          f"(pytest, its workers and every process they waited for)")
    print(f"load      before {' '.join(f'{x:.2f}' for x in load_before)}, after "
          f"{' '.join(f'{x:.2f}' for x in load_after)} (1, 5, 15 min; {os.cpu_count()} cores)")
    print(f"tests     {dict(outcome)}")
    for f, s in sorted(files.items(), key=lambda kv: -kv[1]):
        print(f"  {f:34s} {s:8.1f} s")
    return r.returncode


if __name__ == "__main__":
    sys.exit(main())
