"""Medians of the fifth round's alternating runs (profile_r*_*.md, ga_r*_*.txt in this folder): per checkout, the
feasible PTP_3 evaluation's stages, the failing candidates' totals and stages, and the genetic search's evaluations
per CPU second and ask seconds, with the per-round ratios of main to the other checkouts.

    python docs/results/issue25_round5/summarize_round5.py [FOLDER NAMES]

FOLDER and NAMES (comma-separated checkouts, the first the issue's baseline, the second the round's start, the
last main) read another round's records, e.g. ``docs/results/issue25_round6 base_9d,base_s6,main``.
"""
import json
import re
import statistics
import sys
from pathlib import Path

HERE = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent
NAMES = tuple(sys.argv[2].split(",")) if len(sys.argv) > 2 else ("base_9d", "base_s5", "main")
START = NAMES[1]
ROUNDS = sorted({int(m.group(1)) for p in HERE.glob("profile_r*_main.md") if (m := re.match(r"profile_r(\d+)_", p.name))})


def tables(text):
    """{section title: {group: (cells by column name)}}"""
    out, title, cols = {}, None, None
    for line in text.splitlines():
        if line.startswith("### "):
            title = line[4:].split(",")[0]
            out[title] = {}
        elif line.startswith("| group"):
            cols = [c.strip() for c in line.strip("|").split("|")]
        elif line.startswith("| ") and title and cols and not line.startswith("|---") and not line.startswith("| ("):
            cells = [c.strip() for c in line.strip("|").split("|")]
            out[title][cells[0]] = dict(zip(cols, cells))
    return out


def num(cell):
    m = re.match(r"([0-9.]+)", cell or "")
    return float(m.group(1)) if m else 0.0


def med(xs):
    return statistics.median(xs) if xs else float("nan")


prof = {n: {r: tables((HERE / f"profile_r{r}_{n}.md").read_text()) for r in ROUNDS} for n in NAMES}
ga = {n: {r: [json.loads(line) for line in (HERE / f"ga_r{r}_{n}.txt").read_text().splitlines()
              if line.startswith("{")] for r in ROUNDS} for n in NAMES}

print("## feasible PTP_3 (ms, median over rounds of each round's median)")
for n in NAMES:
    rows = [prof[n][r]["PTP_3"]["feasible"] for r in ROUNDS]
    st = {k: med([num(x[k]) for x in rows]) for k in ("ik", "plan", "timing", "check", "total (median)")}
    print(n, {k: round(v, 1) for k, v in st.items()}, "per round", [num(x["total (median)"]) for x in rows])
for fam in ("whitman2020_g5o5", "bpo2024"):
    print(f"## {fam}: failing at IK (ms)")
    for n in NAMES:
        rows = [prof[n][r][fam]["failed at ik"] for r in ROUNDS]
        st = {k: med([num(x.get(k, "0")) for x in rows]) for k in ("assembly", "base", "reach", "ik", "total (median)")}
        print(n, {k: round(v, 2) for k, v in st.items()}, "per round", [num(x["total (median)"]) for x in rows])
    ratio = [num(prof["main"][r][fam]["failed at ik"]["total (median)"]) /
             num(prof[START][r][fam]["failed at ik"]["total (median)"]) for r in ROUNDS]
    print(f"main / {START} per round", [round(x, 2) for x in ratio], "median", round(med(ratio), 2))
print("## genetic search: evaluations per CPU second (median of rounds), ask seconds")
tasks = [d["task"] for d in ga["main"][ROUNDS[0]]]
for i, t in enumerate(tasks):
    row = {n: med([ga[n][r][i]["evals_per_cpu_s"] for r in ROUNDS]) for n in NAMES}
    asks = {n: med([ga[n][r][i].get("ask_seconds", float("nan")) for r in ROUNDS]) for n in NAMES}
    per_round = [ga["main"][r][i]["evals_per_cpu_s"] / ga["base_9d"][r][i]["evals_per_cpu_s"] for r in ROUNDS]
    hashes = {n: sorted({ga[n][r][i]["hash"] for r in ROUNDS}) for n in NAMES}
    print(t, {n: round(v, 1) for n, v in row.items()}, f"main/9d {row['main'] / row['base_9d']:.2f}x",
          "per round", [round(x, 2) for x in per_round], "ask", {n: round(v, 2) for n, v in asks.items()}, hashes)
