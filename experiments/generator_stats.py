"""Statistics of the faithful task generators next to the published figures (issue 21; docs/generators.md).

    nice .venv/bin/python experiments/generator_stats.py --count 40 [--out /tmp/genstats]

Generates N tasks per benchmark family (Whitman2020 3/3 fixed, 3/3 free, 5/5 free; Liu2020 case 2b with the
QUASER MV205 mesh of the CoBRA data; BPO24 edge cases) and prints, per family, the published figures next to the
measured ones (robodesign.generate.stats, plain JSON arithmetic).
"""
from __future__ import annotations

import argparse
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=40)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", help="keep the generated folders here (default: a temporary folder)")
    args = ap.parse_args()
    base = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="genstats_"))
    for name, (family, opts) in SUITES.items():
        folder = base / name.replace(" ", "_").replace("/", "")
        t0 = time.perf_counter()
        files = generate(family, folder, args.count, args.seed, opts)
        wall = time.perf_counter() - t0
        s = folder_stats(files)
        cols = {f"published {family}": PUBLISHED[family],
                f"generated ({args.count} tasks, seed {args.seed})": {r: s.row(r) for r in PUBLISHED[family]}}
        print(f"\n### {name}  ({wall:.1f} s to generate)\n")
        print(table(cols))


if __name__ == "__main__":
    main()
