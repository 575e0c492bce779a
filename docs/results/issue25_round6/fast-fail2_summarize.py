"""Medians of fast-fail2's alternating A/B runs (fast-fail2_ab.sh): per side, the "failed at ik" rows of
profile_evaluator (stage medians, total, CPU) and bench_front_ga's evaluations per CPU second, per round and over
the rounds; ratios per round (new ÷ base for times, new ÷ base for evaluations per CPU second).

    python fast-fail2_summarize.py PREFIX        (reads PREFIX_profile.txt and PREFIX_ga.txt)
"""
import json
import re
import statistics
import sys
from collections import defaultdict

prefix = sys.argv[1]
STAGES = ("assembly", "base", "reach", "ik")


def sides(path):
    """(round, side) → the lines of that run."""
    out, key = defaultdict(list), None
    for line in open(path):
        m = re.match(r"## round (\d+) src (\S+)", line)
        if m:
            key = (int(m.group(1)), "base" if "base_s6" in m.group(2) else "new")
            continue
        if key:
            out[key].append(line)
    return out


prof = defaultdict(dict)   # (round, side) → family → (stages..., total, cpu)
for key, lines in sides(prefix + "_profile.txt").items():
    fam = None
    for line in lines:
        if line.startswith("### "):
            fam = line.split()[1].rstrip(",")
        if line.startswith("| failed at ik") and fam:
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            st = [float(c.split()[0]) if c not in ("–", "") else 0.0 for c in cells[2:2 + len(STAGES)]]
            total, cpu = float(cells[-2].split()[0]), float(cells[-1].split()[0])
            prof[key][fam] = st + [total, cpu]
ga = defaultdict(dict)   # (round, side) → task → (evals per CPU s, hash, ik stage s)
for key, lines in sides(prefix + "_ga.txt").items():
    for line in lines:
        if line.startswith("{"):
            d = json.loads(line)
            ga[key][d["task"][:-5]] = (d["evals_per_cpu_s"], d["hash"], d["stage_seconds"].get("ik", 0.0))
rounds = sorted({r for r, _ in prof} | {r for r, _ in ga})
fams = sorted({f for v in prof.values() for f in v})
print("## profile_evaluator, failed at ik: medians per round (ms): " + ", ".join(STAGES) + ", total, CPU")
for fam in fams:
    print(f"\n### {fam}")
    for side in ("base", "new"):
        rows = [prof[(r, side)][fam] for r in rounds if fam in prof.get((r, side), {})]
        print(f"{side}: " + "; ".join(" ".join(f"{x:.2f}" for x in row) for row in rows))
        if rows:
            med = [statistics.median(col) for col in zip(*rows)]
            print(f"{side} median of rounds: " + " ".join(f"{x:.2f}" for x in med))
    ratios = [prof[(r, "new")][fam][-1] / prof[(r, "base")][fam][-1] for r in rounds
              if fam in prof.get((r, "new"), {}) and fam in prof.get((r, "base"), {})]
    tot = [prof[(r, "new")][fam][-2] / prof[(r, "base")][fam][-2] for r in rounds
           if fam in prof.get((r, "new"), {}) and fam in prof.get((r, "base"), {})]
    pairs = [(prof[(r, "base")][fam], prof[(r, "new")][fam]) for r in rounds
             if fam in prof.get((r, "new"), {}) and fam in prof.get((r, "base"), {})]
    control = [(n[0] + n[1]) / (b[0] + b[1]) for b, n in pairs]   # assembly + base: code not changed
    changed = [(n[2] + n[3]) / (b[2] + b[3]) for b, n in pairs]   # reach + ik
    print("new/base assembly+base (unchanged code: the machine's speed) per round: " +
          ", ".join(f"{x:.2f}" for x in control))
    print("new/base reach+ik per round: " + ", ".join(f"{x:.2f}" for x in changed) +
          (f" (median {statistics.median(changed):.2f})" if changed else ""))
    print("new/base CPU per round: " + ", ".join(f"{x:.2f}" for x in ratios) +
          (f" (median {statistics.median(ratios):.2f})" if ratios else ""))
    print("new/base total per round: " + ", ".join(f"{x:.2f}" for x in tot) +
          (f" (median {statistics.median(tot):.2f})" if tot else ""))
print("\n## bench_front_ga: evaluations per CPU second per round; hashes")
tasks = sorted({t for v in ga.values() for t in v})
for t in tasks:
    print(f"\n### {t}")
    for side in ("base", "new"):
        vals = [ga[(r, side)][t] for r in rounds if t in ga.get((r, side), {})]
        print(f"{side}: " + ", ".join(f"{v[0]:.1f}" for v in vals) +
              (f" (median {statistics.median(v[0] for v in vals):.1f}); hashes {sorted({v[1] for v in vals})}" if vals else ""))
    ratios = [ga[(r, "new")][t][0] / ga[(r, "base")][t][0] for r in rounds
              if t in ga.get((r, "new"), {}) and t in ga.get((r, "base"), {})]
    print("new/base per round: " + ", ".join(f"{x:.2f}" for x in ratios) +
          (f" (median {statistics.median(ratios):.2f})" if ratios else ""))
