"""Medians of the A/B raw outputs in this folder (issue 25 round 5, fast-ikfail): python summarize.py"""
import json
import re
import statistics as st
import sys
from collections import defaultdict
from pathlib import Path

HERE = Path(__file__).parent


def replay(name):
    cpu, wall, hashes = defaultdict(list), defaultdict(list), defaultdict(set)
    src = None
    for line in (HERE / name).read_text().splitlines():
        if line.startswith("## "):
            src = line.split()[-1]
        elif line.startswith("round"):
            m = re.search(r"wall total ([\d.]+) ms.*cpu total ([\d.]+) ms", line)
            wall[src].append(float(m.group(1)))
            cpu[src].append(float(m.group(2)))
        elif line.startswith("result hash"):
            hashes[src].add(line.split()[-1])
    for s in cpu:
        print(f"{name}: {s}: {len(cpu[s])} rounds, CPU median {st.median(cpu[s]):.0f} ms (min {min(cpu[s]):.0f}), "
              f"wall median {st.median(wall[s]):.0f} ms, hashes {sorted(hashes[s])}")


def ga(name):
    ik, cpu, hashes = defaultdict(list), defaultdict(list), defaultdict(set)
    src = None
    for line in (HERE / name).read_text().splitlines():
        if line.startswith("## "):
            src = line.split()[-1]
        elif line.startswith("{"):
            d = json.loads(line)
            key = (d["task"].replace(".json", ""), src)
            ik[key].append(d["stage_seconds"].get("ik", 0.0))
            cpu[key].append(d["cpu_seconds"])
            hashes[key].add(d["hash"])
    for k in sorted(ik):
        print(f"{name}: {k[0]} {k[1]}: {len(ik[k])} runs, ik stage median {st.median(ik[k]):.2f} s "
              f"(min {min(ik[k]):.2f}), CPU median {st.median(cpu[k]):.2f} s, hashes {sorted(hashes[k])}")


if __name__ == "__main__":
    for f in sys.argv[1:] or ["ik_replay_oven_hard.txt", "ik_replay_whitman_0001.txt"]:
        if (HERE / f).exists():
            replay(f)
    for f in ["front_ga.txt"]:
        if (HERE / f).exists():
            ga(f)
