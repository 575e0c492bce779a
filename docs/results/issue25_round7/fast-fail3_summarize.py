"""Medians of fast-fail3's alternating A/B runs in this folder (fast-fail3_profile_<side>_r<k>.txt and
fast-fail3_ga_<side>_r<k>.txt, side ``base`` = the session start 1b535a2, ``ff3`` = the branch): per round and side,
the failing candidates' median total, CPU and stages (profile_evaluator), the feasible PTP_3 evaluation's total, and
the genetic search's evaluations per CPU second and ask seconds per task (bench_front_ga), with the branch ÷ base
ratio per round and the median over the rounds.

    python docs/results/issue25_round7/fast-fail3_summarize.py
"""
import json
import re
import statistics
from pathlib import Path

HERE = Path(__file__).parent
SIDES = ("base", "ff3")
ROUNDS = sorted({int(m.group(1)) for p in HERE.glob("fast-fail3_ga_ff3_r*.txt")
                 if (m := re.search(r"_r(\d+)\.txt$", p.name))})


def profile_rows(path: Path) -> dict:
    """{(section, group): {column: cell}} of a profile_evaluator output."""
    out, title, cols = {}, None, None
    for line in path.read_text().splitlines():
        if line.startswith("### "):
            title = line[4:].split(",")[0]
        elif line.startswith("| group"):
            cols = [c.strip() for c in line.strip("|").split("|")]
        elif line.startswith("| ") and title and cols and not line.startswith(("|---", "| (")):
            cells = [c.strip() for c in line.strip("|").split("|")]
            out[(title, cells[0])] = dict(zip(cols, cells))
    return out


def num(cell: str) -> float:
    m = re.match(r"([0-9.]+)", cell or "")
    return float(m.group(1)) if m else 0.0


def ga_rows(path: Path) -> dict:
    """{task: record} of a bench_front_ga output."""
    return {d["task"]: d for d in (json.loads(line) for line in path.read_text().splitlines() if line.startswith("{"))}


def main() -> None:
    prof = {(s, r): profile_rows(HERE / f"fast-fail3_profile_{s}_r{r}.txt") for s in SIDES for r in ROUNDS}
    ga = {(s, r): ga_rows(HERE / f"fast-fail3_ga_{s}_r{r}.txt") for s in SIDES for r in ROUNDS}
    keys = [("whitman2020_g5o5", "failed at ik"), ("bpo2024", "failed at ik"), ("PTP_3", "feasible")]
    for title, group in keys:
        print(f"\n## {title} — {group} (ms; per round: base / ff3)")
        for col in ("total (median)", "CPU (median)", "assembly", "base", "reach", "ik"):
            vals = {s: [num(prof[(s, r)].get((t, group), {}).get(col, "")) for r in ROUNDS
                        for t in [next((k[0] for k in prof[(s, r)] if k[0].startswith(title) and k[1] == group), "")]]
                    for s in SIDES}
            ratios = [b and f / b for b, f in zip(vals["base"], vals["ff3"])]
            print(f"{col:16s} base {vals['base']} median {statistics.median(vals['base']):.2f} | ff3 {vals['ff3']} "
                  f"median {statistics.median(vals['ff3']):.2f} | ff3/base per round "
                  f"{[round(x, 2) for x in ratios]} median {statistics.median(ratios):.2f}")
    print("\n## genetic search: evaluations per CPU second, ask seconds, hashes")
    for task in ga[("base", ROUNDS[0])]:
        e = {s: [ga[(s, r)][task]["evals_per_cpu_s"] for r in ROUNDS] for s in SIDES}
        a = {s: [ga[(s, r)][task]["ask_seconds"] for r in ROUNDS] for s in SIDES}
        h = {ga[(s, r)][task]["hash"] for s in SIDES for r in ROUNDS}
        ratios = [f / b for b, f in zip(e["base"], e["ff3"])]
        print(f"{task}: evals/CPU s base {e['base']} (median {statistics.median(e['base']):.1f}) ff3 {e['ff3']} "
              f"(median {statistics.median(e['ff3']):.1f}); ff3/base per round {[round(x, 2) for x in ratios]} "
              f"median {statistics.median(ratios):.2f}; ask s base {a['base']} ff3 {a['ff3']}; hashes {sorted(h)}")


if __name__ == "__main__":
    main()
