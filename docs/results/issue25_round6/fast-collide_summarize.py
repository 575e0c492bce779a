"""Medians of fast-collide's alternating A/B runs (issue 25, round 6).

    python fast-collide_summarize.py PREFIX   (fast-collide_d3aa647_, fast-collide_final_ or fast-collide_final3_)

Per checkout (the ``### round r src S`` headers): the genetic search's CPU seconds, IK stage seconds and evaluations
per CPU second per task; the IK replay's CPU ms per round (3 per run); profile_evaluator's feasible PTP_3 total and
CPU medians and the median IK stage of candidates failing at IK. Prints every round's value, their median and the
per-round ratio (A/B, same round)."""
import json
import re
import statistics
import sys
from collections import defaultdict
from pathlib import Path

HERE = Path(__file__).parent
prefix = sys.argv[1] if len(sys.argv) > 1 else "fast-collide_"


def runs(name):
    """(round, src, text) of every run in a file."""
    text = (HERE / f"{prefix}{name}.txt").read_text()
    parts = re.split(r"^### round (\d+) src (\S+).*$", text, flags=re.M)
    return [(int(parts[i]), parts[i + 1], parts[i + 2]) for i in range(1, len(parts), 3)]


def table(values):
    """values[src][key] = {round: value}: per key, each src's rounds and median; ratio of the first src to each other."""
    srcs = list(values)
    keys = list(dict.fromkeys(k for s in srcs for k in values[s]))
    for k in keys:
        print(f"  {k}")
        for s in srcs:
            v = values[s].get(k, {})
            xs = [v[r] for r in sorted(v)]
            print(f"    {Path(s).name:12s} {' '.join(f'{x:8.2f}' for x in xs)}   median {statistics.median(xs):8.2f}"
                  if xs else f"    {s}: -")
        a = values[srcs[0]].get(k, {})
        for s in srcs[1:]:
            b = values[s].get(k, {})
            rs = [a[r] / b[r] for r in sorted(set(a) & set(b)) if b[r]]
            if rs:
                print(f"    {Path(srcs[0]).name}/{Path(s).name} per round {' '.join(f'{x:.2f}' for x in rs)}"
                      f"   median {statistics.median(rs):.2f}")


hashes = defaultdict(set)


def genetic(name):
    """The genetic search's runs in ``{prefix}{name}.txt``: per task CPU seconds, IK stage seconds, evals/CPU s."""
    ga = defaultdict(lambda: defaultdict(dict))
    for r, s, text in runs(name):
        for line in text.splitlines():
            if line.startswith("{"):
                d = json.loads(line)
                t = d["task"].replace(".json", "")
                ga[s][f"{t} cpu_s"][r] = d["cpu_seconds"]
                ga[s][f"{t} ik_s"][r] = d["stage_seconds"].get("ik", 0.0)
                ga[s][f"{t} evals/cpu_s"][r] = d["evals_per_cpu_s"]
                hashes[s].add(d["hash"])
    return ga


for name in ("front_ga", "bpo_front_ga"):
    if (HERE / f"{prefix}{name}.txt").exists():
        print(f"## genetic search ({name}: bench_front_ga --budget 200evals --tasks 2"
              + (" --only bpo2024)" if name.startswith("bpo") else ")"))
        table(genetic(name))
print("  hashes:", {Path(s).name: sorted(h) for s, h in hashes.items()})

def present(name):
    return (HERE / f"{prefix}{name}.txt").exists()


rep = defaultdict(lambda: defaultdict(dict))
for r, s, text in runs("ik_replay") if present("ik_replay") else []:
    cpu = [float(x) for x in re.findall(r"cpu total ([0-9.]+) ms", text)]
    for i, x in enumerate(cpu):
        rep[s]["oven_hard IK replay cpu ms"][3 * r + i] = x
    for h in re.findall(r"result hash (\w+)", text):
        hashes["replay " + Path(s).name].add(h)
if rep:
    print("## IK replay (bench_ik_replay --task oven_hard --rounds 3)")
    table(rep)
    print("  hashes:", {s: sorted(h) for s, h in hashes.items() if s.startswith("replay")})

pe = defaultdict(lambda: defaultdict(dict))
for r, s, text in runs("profile_evaluator") if present("profile_evaluator") else []:
    section = None
    for line in text.splitlines():
        if line.startswith("### "):
            section = line.split(",")[0][4:]
        cells = [c.strip() for c in line.split("|")]
        if len(cells) > 13 and cells[1] in ("feasible", "failed at ik"):
            pe[s][f"{section} {cells[1]}: ik ms"][r] = float(cells[6].split()[0])
            pe[s][f"{section} {cells[1]}: total ms"][r] = float(cells[12].split()[0])
            pe[s][f"{section} {cells[1]}: CPU ms"][r] = float(cells[13].split()[0])
            if cells[1] == "feasible":
                for i, st in ((8, "plan"), (9, "timing"), (11, "check")):
                    pe[s][f"{section} feasible: {st} ms"][r] = float(cells[i].split()[0])
if pe:
    print("## profile_evaluator (--only good,whitman2020_g5o5,bpo2024 --feasible 20 --failing 30 --tasks 1)")
    table(pe)

for name, what in (("collide_replay", "oven_hard: 62 robots, 4891 queries"),
                   ("whitman_collide_replay", "whitman2020 _0001: 56 robots, 12278 queries")):
    if not present(name):
        continue
    cr: dict = defaultdict(lambda: defaultdict(dict))
    for r, s, text in runs(name):
        cpu = [float(x) for x in re.findall(r"in_collision cpu ([0-9.]+) ms", text)]
        cr[s]["in_collision cpu ms (median of the run's 3)"][r] = statistics.median(cpu)
        for h in re.findall(r"verdict hash (\w+)", text):
            hashes[name + " " + Path(s).name].add(h)
    print(f"## the search's collision queries replayed (fast-collide_collide_replay.py, {what})")
    table(cr)
    print("  hashes:", {s: sorted(h) for s, h in hashes.items() if s.startswith(name)})
