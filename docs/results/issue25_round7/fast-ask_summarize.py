"""Summarize the fast-ask A/B records of this folder: per task and checkout the median over rounds of evaluations
per CPU second and ask seconds (bench_front_ga), of the replayed asks' CPU seconds (bench_ask_replay), and the
per-round ratios.   python fast-ask_summarize.py [folder]"""
import json
import statistics
import sys
from collections import defaultdict
from pathlib import Path

D = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).parent)


def rows(pattern):
    out = defaultdict(dict)   # (task) -> {(round, checkout): record}
    for f in sorted(D.glob(pattern)):
        parts = f.stem.split("_")   # fast-ask_ga_r1_base_s7
        r, ck = parts[2], "_".join(parts[3:])
        for line in f.read_text().splitlines():
            if line.startswith("{"):
                d = json.loads(line)
                out[d["task"][:-5]][(r, ck)] = d
    return out


def med(xs):
    return statistics.median(xs) if xs else float("nan")


def table(out, key, cks, ratio_of):
    for task, recs in out.items():
        rounds = sorted({r for r, _ in recs})
        cells = []
        for ck in cks:
            xs = [recs[(r, ck)][key] for r in rounds if (r, ck) in recs]
            cells.append(f"{ck} {med(xs):.3g} ({', '.join(f'{x:.3g}' for x in xs)})")
        for a, b in ratio_of:
            rs = [recs[(r, a)][key] / recs[(r, b)][key] for r in rounds if (r, a) in recs and (r, b) in recs]
            cells.append(f"{a}/{b} per round {', '.join(f'{x:.2f}' for x in rs)}: median {med(rs):.2f}")
        print(f"{task}: " + " | ".join(cells))


ga = rows("fast-ask_ga_r*.txt")
for task, recs in rows("fast-ask_gabpo_r*.txt").items():
    ga[task].update(recs)
print("## bench_front_ga evals_per_cpu_s")
table(ga, "evals_per_cpu_s", ["base_9d", "base_s7", "fast-ask"], [("fast-ask", "base_s7"), ("fast-ask", "base_9d"),
                                                                 ("base_s7", "base_9d")])
print("## bench_front_ga ask_seconds (wall)")
table(ga, "ask_seconds", ["base_s7", "fast-ask"], [("fast-ask", "base_s7")])
print("## bench_front_ga cpu_seconds")
table(ga, "cpu_seconds", ["base_9d", "base_s7", "fast-ask"], [("fast-ask", "base_s7")])
print("## bench_ask_replay: median CPU seconds of the replayed asks")
table(rows("fast-ask_askreplay_r*.txt"), "median", ["base_s7", "fast-ask"], [("fast-ask", "base_s7")])
