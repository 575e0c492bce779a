"""Loading published files: task / module-set load times (fresh processes) and robodesign's STL reader vs trimesh.

Since issue 12/13 every collision mesh is read (and checked) when a task or module set is loaded, so a broken
mesh is an error instead of a vanished obstacle. STL files are read with numpy (binary and ASCII), which gives
the same vertices as trimesh's unprocessed read without importing trimesh.

    python experiments/bench_task_load.py [--repeat 5]
"""
from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

COBRA = Path(__file__).resolve().parents[2] / "shared" / "cobra"
LOAD = r'''
import sys, time
t0 = time.perf_counter()
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
kind, ref = sys.argv[1], sys.argv[2]
t1 = time.perf_counter()
(load_task if kind == "task" else load_module_set)(ref)
print((time.perf_counter() - t1) * 1e3)
'''


def fresh_load_ms(kind: str, ref: Path, repeat: int) -> float:
    runs = [float(subprocess.run([sys.executable, "-c", LOAD, kind, str(ref)], capture_output=True, text=True,
                                 check=True).stdout) for _ in range(repeat)]
    return statistics.median(runs)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args()
    print("load in a fresh process (median of", a.repeat, "runs):")
    for kind, ref in (("task", COBRA / "tasks" / "simple" / "PTP_2.json"),
                      ("task", COBRA / "tasks" / "simple" / "PTP_3.json"),
                      ("modules", COBRA / "modules" / "IMPROV")):
        print(f"  {ref.relative_to(COBRA)}: {fresh_load_ms(kind, ref, a.repeat):.0f} ms")
    from robodesign.formats.geometry import read_stl  # the reader itself is what is measured
    t = time.perf_counter()
    import trimesh
    print(f"import trimesh: {(time.perf_counter() - t) * 1e3:.0f} ms (not needed for STL any more)")
    for f in sorted((COBRA / "tasks" / "assets").glob("*.stl")):
        t = time.perf_counter()
        v, tri = read_stl(f)
        ours = time.perf_counter() - t
        t = time.perf_counter()
        m = trimesh.load(str(f), force="mesh", process=False)
        theirs = time.perf_counter() - t
        same = np.array_equal(np.asarray(m.vertices)[np.asarray(m.faces)], v[tri])
        print(f"  {f.name}: {len(tri)} triangles, numpy {ours * 1e3:.1f} ms, trimesh {theirs * 1e3:.1f} ms "
              f"(×{theirs / ours:.1f}), identical vertices: {same}")


if __name__ == "__main__":
    main()
