"""Re-diagnose the unsolved tasks of a stored family run with the current proofs (they do not depend on the
search): the reach proof (design/reach.py) and the blocked-goal and fixed-part proofs (design/blocked.py).

    .venv/bin/python experiments/prove_unsolved.py docs/results/families_published_v3 --tasks results/tasks

reads ``runs.jsonl`` of the run folder, finds each unsolved task's file under ``--tasks`` (the generated tasks
of bench_families.py), and writes ``proofs.json`` beside it: per unsolved task, the proof's message or null. It
prints per family: tasks, solved, proven (stored or now), solved / not proven.
"""
from __future__ import annotations

import argparse
import json
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from robodesign.design.blocked import blocked_goal_proof  # noqa: E402
from robodesign.design.diagnosis import allowed_end_effectors  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.reach import reach_proof  # noqa: E402

SETS = {"heavy": "robodesign_heavy", "builtin": "robodesign_arm"}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", help="a bench_families.py output folder (holds runs.jsonl)")
    ap.add_argument("--tasks", default=str(ROOT / "results" / "tasks"), help="the generated task files")
    args = ap.parse_args()
    run = Path(args.run)
    try:
        rows = [json.loads(line) for line in (run / "runs.jsonl").read_text().splitlines() if line.strip()]
    except (OSError, ValueError) as e:
        print(f"{run / 'runs.jsonl'}: cannot read the run's records ({e})", file=sys.stderr)
        return 2
    files = {p.stem: p for p in Path(args.tasks).rglob("*.json")}
    proofs = {}
    fam = defaultdict(lambda: {"tasks": 0, "solved": 0, "proven": 0})
    for r in rows:
        f = fam[r["variant"]]
        f["tasks"] += 1
        if r["verdict"] == "solved":
            f["solved"] += 1
            continue
        if r["task"] not in files:
            print(f"{r['task']}: task file not found under {args.tasks}", file=sys.stderr)
            return 2
        problem = Problem.build(files[r["task"]], SETS.get(r["set"], r["set"]), "cyc")
        proof = reach_proof(problem.task, problem.space) or blocked_goal_proof(
            problem.task, allowed_end_effectors(problem.space), problem.space)
        proofs[r["task"]] = {"variant": r["variant"], "stored_verdict": r["verdict"],
                             "proof": None if proof is None else proof.to_json()}
        if proof is not None:
            f["proven"] += 1
        if (proof is not None) != (r["verdict"] == "out_of_reach"):
            print(f"{r['task']}: stored verdict {r['verdict']}, now {'proven' if proof else 'not proven'}")
    (run / "proofs.json").write_text(json.dumps(proofs, indent=1) + "\n")
    print(f"{'family':26s} tasks solved proven  solved / not proven")
    for v, f in fam.items():
        rest = f["tasks"] - f["proven"]
        print(f"{v:26s} {f['tasks']:5d} {f['solved']:6d} {f['proven']:6d}  {f['solved']}/{rest} = "
              f"{100.0 * f['solved'] / rest if rest else float('nan'):.1f} %")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:  # nothing is written before the end: stopping loses only this re-diagnosis
        print("interrupted", file=sys.stderr)
        sys.exit(130)
