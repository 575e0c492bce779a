"""Statistics of the faithful task generators next to the published figures (issue 21; docs/generators.md).

    nice .venv/bin/python experiments/generator_stats.py --count 40 [--out /tmp/genstats]
        [--reference-python /tmp/timor/bin/python]

Generates N tasks per benchmark family (Whitman2020 3/3 fixed, 3/3 free, 5/5 free; Liu2020 case 2b with the
QUASER MV205 mesh of the CoBRA data; BPO24 edge cases) and prints, per family, the published figures next to the
measured ones (robodesign.generate.stats, plain JSON arithmetic).

``--reference-python PY`` also loads every generated file with the reference implementation (Timor Python,
installed into a separate venv whose interpreter is PY: ``pip install timor-python==1.1.1``) and prints how many
load. Offline, Timor cannot download its JSON schemata or the CoBRA module sets: the loader then stubs the
schema files (so schema validation is skipped; Timor's own parsing and its bound checks, e.g. ``Theta_R`` ≤ π,
still run) and skips the module-set download.
"""
from __future__ import annotations

import argparse
import subprocess
import tempfile
import time
from pathlib import Path

from robodesign.generate import generate
from robodesign.generate.stats import PUBLISHED, folder_stats, table

ROOT = Path(__file__).resolve().parents[1]
QUASER = ROOT.parent / "shared" / "cobra" / "tasks" / "assets" / "QUASER_MV205_v3_compressed.stl"

SUITES = {  # name → (family, options)
    "whitman2020 3/3 fixed": ("whitman2020", {"goals": 3, "obstacles": 3, "base": "fixed"}),
    "whitman2020 3/3 free": ("whitman2020", {"goals": 3, "obstacles": 3, "base": "xyz_any_rot"}),
    "whitman2020 5/5 free": ("whitman2020", {"goals": 5, "obstacles": 5, "base": "xyz_any_rot"}),
    "liu2020 case 2b": ("liu2020", {"machine": str(QUASER)}),
    "bpo2024 edge cases": ("bpo2024", {}),
}


LOADER = r"""
import importlib, json, logging, site, sys
from pathlib import Path
logging.disable(logging.WARNING)
cache = Path(site.getsitepackages()[0]) / "cache" / "schemata"  # Timor's default schema folder
cache.mkdir(parents=True, exist_ok=True)
for s in ("PoseSchema", "TaskSchema", "ModuleSchema", "SolutionSchema"):
    f = cache / (s + ".json")
    if not f.exists():  # offline stub: no validation, parsing still runs
        f.write_text(json.dumps({"$schema": "http://json-schema.org/draft-07/schema#",
                                 "$id": "https://cobra.cps.cit.tum.de/api/schemas/" + s + ".json"}))
robot = importlib.import_module("cobra.robot.robot")
def offline():
    raise TimeoutError("offline")
robot.get_available_module_dbs = offline
from timor.task.Task import Task
for folder in sys.argv[1:]:
    ok, bad = 0, []
    for f in sorted(Path(folder).glob("*.json")):
        try:
            Task.from_json_file(f, Path(folder))
            ok += 1
        except Exception as e:
            bad.append(f"{f.name}: {type(e).__name__}: {e}")
    print(f"{Path(folder).name}: {ok} of {ok + len(bad)} load in the reference", *bad[:3], sep="\n  ")
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=40)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", help="keep the generated folders here (default: a temporary folder)")
    ap.add_argument("--reference-python", help="interpreter of a venv with timor-python: load every file with it")
    args = ap.parse_args()
    base = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="genstats_"))
    folders = []
    for name, (family, opts) in SUITES.items():
        folder = base / name.replace(" ", "_").replace("/", "")
        folders.append(folder)
        t0 = time.perf_counter()
        files = generate(family, folder, args.count, args.seed, opts)
        wall = time.perf_counter() - t0
        s = folder_stats(files)
        cols = {f"published {family}": PUBLISHED[family],
                f"generated ({args.count} tasks, seed {args.seed})": {r: s.row(r) for r in PUBLISHED[family]}}
        print(f"\n### {name}  ({wall:.1f} s to generate)\n")
        print(table(cols))
    if args.reference_python:
        print("\n### Loaded by the reference implementation\n")
        subprocess.run([args.reference_python, "-c", LOADER, *map(str, folders)], check=True, cwd=tempfile.gettempdir())


if __name__ == "__main__":
    main()
