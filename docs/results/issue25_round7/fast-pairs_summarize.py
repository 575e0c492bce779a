"""Summarise the fast-pairs A/B records: python fast-pairs_summarize.py <good prefix> <ga prefix> <replay prefix or ->
(e.g. good ga replay, or good2 ga2 -): per round and checkout, the feasible PTP_3 stage medians (ms), the oven_hard
IK replay's CPU ms (median of its rounds) and hash, and the genetic search's CPU seconds per task and hashes."""
import json
import re
import statistics
import sys
from pathlib import Path

HERE = Path(__file__).parent


def good(path):
    """(ik, plan, timing, check, total CPU) medians of a profile_evaluator --only good record."""
    row = [r for r in path.read_text().splitlines() if r.startswith("| feasible")][0].split("|")
    num = [float(re.match(r"\s*([0-9.]+)", c).group(1)) for c in row[3:] if re.match(r"\s*[0-9.]", c)]
    return num[3], num[5], num[6], num[7], num[-1]


def replay(path):
    """(median CPU ms of the replay's rounds, hash)."""
    text = path.read_text()
    cpu = [float(x) for x in re.findall(r"cpu total ([0-9.]+) ms", text)]
    return statistics.median(cpu), re.search(r"result hash (\w+)", text).group(1)


def ga(path):
    """[(task, CPU s, hash)] of a bench_front_ga record."""
    rows = [json.loads(r) for r in path.read_text().splitlines() if r.startswith("{")]
    return [(r["task"][:24], r["cpu_seconds"], r["hash"]) for r in rows]


def main():
    gp, ap, rp = sys.argv[1:4]
    for f in sorted(HERE.glob(f"fast-pairs_{gp}_r*.txt")):
        ik, plan, timing, check, cpu = good(f)
        print(f"{f.stem}: ik {ik} plan {plan} timing {timing} check {check} total CPU {cpu}")
    if rp != "-":
        for f in sorted(HERE.glob(f"fast-pairs_{rp}_r*.txt")):
            print(f.stem, *replay(f))
    for f in sorted(HERE.glob(f"fast-pairs_{ap}_r*.txt")):
        print(f.stem, ga(f))


main()
