"""Summaries of fast-ik3's A/B records (this folder): the feasible PTP_3 evaluation's medians (profile_evaluator),
the oven_hard IK replay's CPU per round (bench_ik_replay) and the genetic search's numbers (bench_front_ga).

    python fast-ik3_summarize.py good replay box_good box_ga box_replay
"""
import json
import re
import statistics
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def good(prefix):
    rows = {}
    for f in sorted(HERE.glob(f"fast-ik3_{prefix}_*_r*.txt")):
        m = re.match(rf"fast-ik3_{prefix}_(.+)_r(\d+)\.txt", f.name)
        line = next((ln for ln in f.read_text().splitlines() if ln.startswith("| feasible")), None)
        if m is None or line is None:
            continue
        c = [x.strip() for x in line.split("|")]
        val = {"ik": float(c[6].split()[0]), "plan": float(c[8].split()[0]), "total": float(c[12].split()[0]),
               "cpu": float(c[13].split()[0])}
        rows.setdefault(m.group(1), {})[int(m.group(2))] = val
    return rows


def replay(prefix):
    rows = {}
    for f in sorted(HERE.glob(f"fast-ik3_{prefix}_*_r*.txt")):
        m = re.match(rf"fast-ik3_{prefix}_(.+)_r(\d+)\.txt", f.name)
        cpu = [float(x) for x in re.findall(r"cpu total ([0-9.]+) ms", f.read_text())]
        h = re.findall(r"result hash (\w+)", f.read_text())
        if m and cpu:
            rows.setdefault(m.group(1), {})[int(m.group(2))] = {"cpu_median": statistics.median(cpu), "hash": h}
    return rows


def ga(prefix):
    rows = {}
    for f in sorted(HERE.glob(f"fast-ik3_{prefix}_*_r*.txt")):
        m = re.match(rf"fast-ik3_{prefix}_(.+)_r(\d+)\.txt", f.name)
        recs = [json.loads(ln) for ln in f.read_text().splitlines() if ln.startswith("{")]
        if m and recs:
            rows.setdefault(m.group(1), {})[int(m.group(2))] = {
                r["task"].replace(".json", ""): (r["evals_per_cpu_s"], r["stage_seconds"].get("ik"), r["hash"]) for r in recs}
    return rows


if __name__ == "__main__":
    for arg in sys.argv[1:]:
        data = {"good": lambda: good("good"), "box_good": lambda: good("box_good"), "replay": lambda: replay("replay"),
                "box_replay": lambda: replay("box_replay"), "box_ga": lambda: ga("box_ga")}[arg]()
        print(f"## {arg}")
        for src, rounds in data.items():
            for r, v in sorted(rounds.items()):
                print(src, r, v)
