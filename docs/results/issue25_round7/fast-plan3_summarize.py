"""Summary of fast-plan3_ab.sh's records (argv[1]: their prefix): per round, base → branch, the feasible PTP_3
evaluation's plan stage and CPU (ms, medians over 20 seeds), and per genetic-search task the plan stage's seconds,
the CPU seconds and the evaluations per CPU second; then the medians over the rounds and their ratio."""
import json
import re
import statistics
import sys
from collections import defaultdict

prefix = sys.argv[1]


def rounds(path, parse):
    """{(round, which): [parsed records]} of one record file (which: 'base' or 'branch')."""
    out, key = defaultdict(list), None
    for line in open(path):
        m = re.match(r"## round (\d+) src (\S+)", line)
        if m:
            key = (int(m.group(1)), "base" if "base_s7" in m.group(2) else "branch")
        elif line.strip():
            out[key].append(parse(line))
    return out


def feasible(line):
    cells = [c.strip() for c in line.strip().strip("|").split("|")]
    return {"plan": float(cells[7].split()[0]), "cpu": float(cells[-1].split()[0])}


def show(label, table):
    """table: {round: (base, branch)}; nothing when the base has no such time (a stage never reached)."""
    if not all(b for b, _ in table.values()):
        return
    base, branch = [b for b, _ in table.values()], [x for _, x in table.values()]
    per = ", ".join("%.2f→%.2f (%.2f)" % (b, x, x / b) for b, x in table.values())
    print("%-44s %8.2f %8.2f  ratio of medians %.2f | %s" % (label, statistics.median(base), statistics.median(branch),
                                                          statistics.median(branch) / statistics.median(base), per))


prof = rounds(prefix + "_profile.txt", feasible)
R = sorted({r for r, _ in prof})
for field in ("plan", "cpu"):
    show("PTP_3 feasible, %s ms" % field, {r: (prof[r, "base"][0][field], prof[r, "branch"][0][field]) for r in R
                                          if prof.get((r, "base")) and prof.get((r, "branch"))})
ga = rounds(prefix + "_ga.txt", json.loads)
tasks = [d["task"] for d in ga[R[0], "base"]]
for t, task in enumerate(tasks):
    for field, label in (("plan", "plan s"), ("cpu_seconds", "CPU s"), ("evals_per_cpu_s", "evals/CPU s")):
        def val(d):
            return d["stage_seconds"].get("plan", 0.0) if field == "plan" else d[field]
        show("%s %s" % (task[:40], label), {r: (val(ga[r, "base"][t]), val(ga[r, "branch"][t])) for r in R
                                            if len(ga.get((r, "branch"), [])) > t})
    print("  hashes:", sorted({d["hash"] for k, v in ga.items() for d in v if d["task"] == task}))
