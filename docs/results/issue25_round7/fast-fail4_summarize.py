"""fast-fail4's A/B summary: per round and checkout, the 'failed at ik' rows of profile_evaluator (stage medians,
total and CPU medians) and bench_front_ga's evaluations per CPU second and hashes; then medians over rounds and the
per-round ratios (branch ÷ base)."""
import json
import re
import statistics
from pathlib import Path

HERE = Path(__file__).resolve().parent
COLS = ["assembly", "base", "reach", "ik", "total", "cpu"]


def profile_rows(path):
    """{family: {column: ms}} of the 'failed at ik' rows."""
    out, fam = {}, None
    for line in path.read_text().splitlines():
        m = re.match(r"### (\S+),", line)
        if m:
            fam = m.group(1)
        if line.startswith("| failed at ik"):
            cells = [c.strip() for c in line.strip("|").split("|")]
            out[fam] = {"assembly": num(cells[2]), "base": num(cells[3]), "reach": num(cells[4]), "ik": num(cells[5]),
                        "total": num(cells[11]), "cpu": num(cells[12])}
    return out


def num(cell):
    """The number at the start of a table cell (NaN for '–')."""
    return float(cell.split()[0]) if cell not in ("–", "") else float("nan")


def ga_rows(path):
    """{task file: bench_front_ga's JSON line}."""
    return {json.loads(line)["task"]: json.loads(line) for line in path.read_text().splitlines()
            if line.startswith("{")}


def main():
    rounds = sorted({int(p.stem.rsplit("_r", 1)[1]) for p in HERE.glob("fast-fail4_profile_*_r*.txt")})
    prof = {(t, r): profile_rows(HERE / f"fast-fail4_profile_{t}_r{r}.txt") for t in ("base", "ff4") for r in rounds
            if (HERE / f"fast-fail4_profile_{t}_r{r}.txt").exists()}
    ga = {(t, r): ga_rows(HERE / f"fast-fail4_ga_{t}_r{r}.txt") for t in ("base", "ff4") for r in rounds
          if (HERE / f"fast-fail4_ga_{t}_r{r}.txt").exists()}
    done = [r for r in rounds if ("base", r) in ga and ("ff4", r) in ga]
    print("rounds", done)
    for fam in ("whitman2020_g5o5", "bpo2024"):
        print(f"\n{fam}, failed at ik (ms; medians over rounds of the per-round medians)")
        for t in ("base", "ff4"):
            vals = {c: statistics.median(prof[t, r][fam][c] for r in done) for c in COLS}
            print(t, "  ".join(f"{c} {v:.2f}" for c, v in vals.items()),
                  "| per round cpu:", [prof[t, r][fam]["cpu"] for r in done])
        ratios = [prof["ff4", r][fam]["cpu"] / prof["base", r][fam]["cpu"] for r in done]
        print("cpu ratio per round", [round(x, 2) for x in ratios], "median", round(statistics.median(ratios), 2))
    print("\nGA evaluations per CPU second")
    for task in ga["base", done[0]]:
        b = [ga["base", r][task]["evals_per_cpu_s"] for r in done]
        f = [ga["ff4", r][task]["evals_per_cpu_s"] for r in done]
        hashes = {ga[t, r][task]["hash"] for t in ("base", "ff4") for r in done}
        print(task, "base", b, "ff4", f, "ratio per round", [round(y / x, 2) for x, y in zip(b, f)],
              "ratio of medians", round(statistics.median(f) / statistics.median(b), 2), "hashes", hashes)


if __name__ == "__main__":
    main()
