"""Per-suite (task family) summaries: how many tasks an optimizer solved, how good and how fast, and for
each unsolved task the stage that stopped every candidate.

One record per run (task × optimizer × seed), from the results database or from a benchmark's CSV:
``solved`` (a feasible design was found), ``best`` (its best cost), ``first_feasible_s`` (run wall time
when the first feasible design was stored) and, for an unsolved run, ``stopped_at``: the furthest stage
any of its candidates reached, which is the stage that stopped every candidate (the solve pipeline is
ordered: a candidate that failed at ``ik`` passed ``reach``). ``stage_counts`` says where each candidate
failed. A task whose every candidate stops at ``reach`` is beyond the module set's reach (infeasible for
it); one that stops at ``plan`` or ``check`` with many candidates past IK points at a weak optimizer or
too small a budget.
"""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
from typing import Dict, Iterable, List, Optional, Sequence

import numpy as np

SUITE_COLUMNS = ("suite", "optimizer", "tasks", "runs", "solved", "solved_pct", "best_cost_median",
                 "best_cost_min", "best_cost_max", "first_feasible_s_median", "first_feasible_s_max",
                 "unsolved_stopped_at")
UNSOLVED_COLUMNS = ("suite", "task", "optimizer", "seed", "evaluations", "stopped_at", "stage_counts", "message")


@dataclass
class SuiteRecord:
    suite: str
    task: str
    optimizer: str
    seed: int
    solved: bool
    best: Optional[float] = None
    first_feasible_s: Optional[float] = None
    evaluations: int = 0
    stopped_at: str = ""                 # unsolved runs: the furthest stage any candidate reached
    stage_counts: Dict[str, int] = field(default_factory=dict)  # failing stage → candidates
    message: str = ""                    # why the furthest candidate failed


def record_of_run(suite: str, task: str, optimizer: str, seed: int, rows: Sequence[dict]) -> SuiteRecord:
    """A run's record from its evaluations (dicts with feasible, cost, stage, stage_index, wall, message)."""
    feas = [r for r in rows if r["feasible"] and r["cost"] is not None]
    rec = SuiteRecord(suite, task, optimizer, int(seed), bool(feas), evaluations=len(rows))
    if feas:
        rec.best = min(float(r["cost"]) for r in feas)
        rec.first_feasible_s = float(feas[0]["wall"])
        return rec
    rec.stage_counts = dict(Counter(r["stage"] for r in rows))
    if rows:
        far = max(rows, key=lambda r: r["stage_index"])  # the first one on ties: ask order
        rec.stopped_at, rec.message = far["stage"], far.get("message") or ""
    else:
        rec.stopped_at = "no evaluation"
    return rec


def suite_of_problems(meta: dict) -> Dict[str, str]:
    """problem name → suite, from a results folder's meta.json (problems outside suites left out)."""
    return {p["name"]: p["suite"] for p in meta.get("problems", []) if p.get("suite")}


def records_from_db(db, suite_of: Dict[str, str]) -> List[SuiteRecord]:
    """The records of every run of a suite task in an ExperimentDB (runs not started yet are left out)."""
    out = []
    for run in db.runs():
        if run["task"] in suite_of:
            rows = db.evaluations(run["run_id"])
            if rows:
                out.append(record_of_run(suite_of[run["task"]], run["task"], run["optimizer"], run["seed"], rows))
    return out


def stage_counts_text(counts: Dict[str, int]) -> str:
    return ", ".join(f"{k} {v}" for k, v in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0])))


def _median(v: List[float]) -> float:
    return float(np.median(v)) if v else math.nan


def summarize_suites(records: Iterable[SuiteRecord]) -> List[dict]:
    """One row per (suite, optimizer), in first-seen order (columns :data:`SUITE_COLUMNS`)."""
    groups: Dict[tuple, List[SuiteRecord]] = {}
    for r in records:
        groups.setdefault((r.suite, r.optimizer), []).append(r)
    out = []
    for (suite, opt), recs in groups.items():
        solved = [r for r in recs if r.solved]
        bests = [r.best for r in solved]
        ff = [r.first_feasible_s for r in solved if r.first_feasible_s is not None]
        stops = Counter(r.stopped_at for r in recs if not r.solved)
        out.append({"suite": suite, "optimizer": opt, "tasks": len({r.task for r in recs}), "runs": len(recs),
                    "solved": len(solved), "solved_pct": 100.0 * len(solved) / len(recs) if recs else math.nan,
                    "best_cost_median": _median(bests), "best_cost_min": min(bests) if bests else math.nan,
                    "best_cost_max": max(bests) if bests else math.nan,
                    "first_feasible_s_median": _median(ff), "first_feasible_s_max": max(ff) if ff else math.nan,
                    "unsolved_stopped_at": stage_counts_text(stops)})
    return out


def unsolved_rows(records: Iterable[SuiteRecord]) -> List[dict]:
    return [{"suite": r.suite, "task": r.task, "optimizer": r.optimizer, "seed": r.seed,
             "evaluations": r.evaluations, "stopped_at": r.stopped_at,
             "stage_counts": stage_counts_text(r.stage_counts), "message": r.message[:200]}
            for r in records if not r.solved]


def cell(key: str, v) -> str:
    if isinstance(v, float):
        if not math.isfinite(v):
            return "–"
        if key == "solved_pct":
            return f"{v:.1f} %"
        return f"{v:.4g}"
    return str(v)


def markdown(summary: List[dict], unsolved: List[dict]) -> str:
    lines = ["# Suites", "",
             "Per suite (task family) and optimizer: tasks, runs (task × seed), runs that found a feasible design, "
             "the best cost of the solved runs (median, min, max), the wall time to the first feasible design "
             "(median, max) and, for unsolved runs, the stage that stopped every candidate.", "",
             "| " + " | ".join(SUITE_COLUMNS) + " |", "|" + "---|" * len(SUITE_COLUMNS)]
    lines += ["| " + " | ".join(cell(c, s[c]) for c in SUITE_COLUMNS) + " |" for s in summary]
    if unsolved:
        lines += ["", "## Unsolved tasks", "",
                  "`stopped_at`: the furthest stage any candidate reached (so the stage that stopped every "
                  "candidate); `stage_counts`: where each candidate failed.", "",
                  "| " + " | ".join(UNSOLVED_COLUMNS) + " |", "|" + "---|" * len(UNSOLVED_COLUMNS)]
        lines += ["| " + " | ".join(str(u[c]).replace("|", "/") for c in UNSOLVED_COLUMNS) + " |" for u in unsolved]
    return "\n".join(lines) + "\n"


def html_tables(summary: List[dict], unsolved: List[dict]) -> str:
    import html
    e = html.escape
    parts = ["<h2>Suites</h2><table><tr>" + "".join(f"<th>{e(c)}</th>" for c in SUITE_COLUMNS) + "</tr>"]
    for s in summary:
        parts.append("<tr>" + "".join(f"<td>{e(cell(c, s[c]))}</td>" for c in SUITE_COLUMNS) + "</tr>")
    parts.append("</table>")
    if unsolved:
        parts.append("<h3>Unsolved tasks: the stage that stopped every candidate</h3><table><tr>"
                     + "".join(f"<th>{e(c)}</th>" for c in UNSOLVED_COLUMNS) + "</tr>")
        for u in unsolved:
            parts.append("<tr>" + "".join(f"<td>{e(str(u[c]))}</td>" for c in UNSOLVED_COLUMNS) + "</tr>")
        parts.append("</table>")
    return "\n".join(parts)
