"""Per-suite (task family) summaries: how many tasks an optimizer solved, how good and how fast, and for
each unsolved task the stage that stopped every candidate.

One record per run (task × optimizer × seed), from the results database or from a benchmark's CSV:
``solved`` (a feasible design was found), ``best`` (its best cost), ``first_feasible_s`` (run wall time
when the first feasible design was stored) and, for an unsolved run, ``stopped_at``: the furthest stage
any of its candidates reached, which is the stage that stopped every candidate (the solve pipeline is
ordered: a candidate that failed at ``ik`` passed ``reach``). ``stage_counts`` says where each candidate
failed. One that stops at ``plan`` or ``check`` with many candidates past IK points at a weak optimizer or
too small a budget.

Every run also gets a ``verdict`` (robodesign.design.diagnosis, docs/diagnosis.md): ``solved``,
``out_of_reach`` (*provably* out of reach for the module set: its reach bound, against the goals and the
base region the task allows; ``reach_bound`` holds the bound), ``torque`` (no tried design could hold the
goals' poses; the best shortfall in Nm) or ``not_found`` (the budget ran out; the best stage reached). The
summary counts them per suite: solved, provably out of reach, not found (torque or budget), and the solved
share of the tasks that are not proven out of reach.
"""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

import numpy as np

from robodesign.core.errors import RobodesignError
from robodesign.design.diagnosis import diagnose
from robodesign.design.problem import Problem
from robodesign.design.reach import SetReach, set_reach

SUITE_COLUMNS = ("suite", "optimizer", "tasks", "runs", "solved", "solved_pct", "out_of_reach", "not_found",
                 "solved_pct_reachable", "best_cost_median", "best_cost_min", "best_cost_max",
                 "first_feasible_s_median", "first_feasible_s_max", "unsolved_stopped_at")
UNSOLVED_COLUMNS = ("suite", "task", "optimizer", "seed", "evaluations", "stopped_at", "stage_counts", "verdict",
                    "diagnosis", "message")
TASK_COLUMNS = ("suite", "task", "optimizer", "seed", "result", "best_cost", "reach_bound", "diagnosis")
#: the result column's words for the verdicts (torque and budget are both "not found")
RESULT = {"solved": "solved", "out_of_reach": "provably out of reach", "torque": "not found", "not_found": "not found"}


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
    verdict: str = ""                    # solved | out_of_reach | torque | not_found ("" = not diagnosed)
    diagnosis: str = ""                  # the diagnosis' one line (its figure)
    reach_bound: Optional[float] = None  # m: the module set's reach bound (diagnosed unsolved runs)

    @property
    def result(self) -> str:
        """solved, provably out of reach or not found."""
        return RESULT.get(self.verdict or ("solved" if self.solved else "not_found"), "not found")


def record_of_run(suite: str, task: str, optimizer: str, seed: int, rows: Sequence[dict]) -> SuiteRecord:
    """A run's record from its evaluations (dicts with feasible, cost, stage, stage_index, wall, message)."""
    feas = [r for r in rows if r["feasible"] and r["cost"] is not None]
    rec = SuiteRecord(suite, task, optimizer, int(seed), bool(feas), evaluations=len(rows))
    if feas:
        rec.verdict = "solved"
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


def problems_of(meta: dict) -> Dict[str, dict]:
    """problem name → its entry in a results folder's meta.json (task and module-set references, cost, rules)."""
    return {p["name"]: p for p in meta.get("problems", []) if p.get("name")}


class Diagnoser:
    """Diagnoses unsolved runs (:func:`robodesign.design.diagnosis.diagnose`) from meta.json problem entries,
    building each problem once and each module set's reach bound once per (module set, rules)."""

    def __init__(self, problems: Dict[str, dict]):
        self.problems = problems
        self._built: Dict[str, Optional[Problem]] = {}
        self._reach: Dict[Tuple[str, str], SetReach] = {}

    def problem(self, name: str) -> Optional[Problem]:
        if name not in self._built:
            p = self.problems.get(name)
            try:
                self._built[name] = None if not p or not p.get("task") or not p.get("modules") else Problem.build(
                    p["task"], p["modules"], p.get("cost") or "cyc", rules=p.get("rules"))
            except (RobodesignError, OSError, KeyError, ValueError):  # a moved task file costs the diagnosis only
                self._built[name] = None
        return self._built[name]

    def __call__(self, rec: SuiteRecord, rows: Sequence[dict]) -> SuiteRecord:
        prob = None if rec.solved else self.problem(rec.task)
        if prob is None:
            return rec
        key = (str(self.problems[rec.task].get("modules")), repr(sorted(prob.rules().items())))
        if key not in self._reach:
            self._reach[key] = set_reach(prob.space)
        d = diagnose(prob, rows, reach=self._reach[key])
        rec.verdict, rec.diagnosis, rec.reach_bound = d.verdict, d.message, d.reach_bound
        return rec


def records_from_db(db, suite_of: Dict[str, str], problems: Optional[Dict[str, dict]] = None) -> List[SuiteRecord]:
    """The records of every run of a suite task in an ExperimentDB (runs not started yet are left out). With
    ``problems`` (:func:`problems_of` of the meta data) every unsolved run is diagnosed."""
    out = []
    diagnoser = Diagnoser(problems) if problems else None
    for run in db.runs():
        if run["task"] in suite_of:
            rows = db.evaluations(run["run_id"])
            if rows:
                rec = record_of_run(suite_of[run["task"]], run["task"], run["optimizer"], run["seed"], rows)
                out.append(diagnoser(rec, rows) if diagnoser else rec)
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
        bests = [r.best for r in solved if r.best is not None]  # (a solved run has its best)
        ff = [r.first_feasible_s for r in solved if r.first_feasible_s is not None]
        stops = Counter(r.stopped_at for r in recs if not r.solved)
        out_of_reach = sum(r.verdict == "out_of_reach" for r in recs)
        reachable = len(recs) - out_of_reach
        out.append({"suite": suite, "optimizer": opt, "tasks": len({r.task for r in recs}), "runs": len(recs),
                    "solved": len(solved), "solved_pct": 100.0 * len(solved) / len(recs) if recs else math.nan,
                    "out_of_reach": out_of_reach, "not_found": reachable - len(solved),
                    "solved_pct_reachable": 100.0 * len(solved) / reachable if reachable else math.nan,
                    "best_cost_median": _median(bests), "best_cost_min": min(bests) if bests else math.nan,
                    "best_cost_max": max(bests) if bests else math.nan,
                    "first_feasible_s_median": _median(ff), "first_feasible_s_max": max(ff) if ff else math.nan,
                    "unsolved_stopped_at": stage_counts_text(stops)})
    return out


def unsolved_rows(records: Iterable[SuiteRecord]) -> List[dict]:
    return [{"suite": r.suite, "task": r.task, "optimizer": r.optimizer, "seed": r.seed,
             "evaluations": r.evaluations, "stopped_at": r.stopped_at,
             "stage_counts": stage_counts_text(r.stage_counts), "verdict": r.result, "diagnosis": r.diagnosis,
             "message": r.message[:200]}
            for r in records if not r.solved]


def task_rows(records: Iterable[SuiteRecord]) -> List[dict]:
    """One row per run (columns :data:`TASK_COLUMNS`): solved (best cost), provably out of reach (the set's
    reach bound) or not found (why)."""
    return [{"suite": r.suite, "task": r.task, "optimizer": r.optimizer, "seed": r.seed, "result": r.result,
             "best_cost": r.best if r.best is not None else math.nan,
             "reach_bound": r.reach_bound if r.verdict == "out_of_reach" and r.reach_bound is not None else math.nan,
             "diagnosis": r.diagnosis} for r in records]


def cell(key: str, v) -> str:
    if isinstance(v, float):
        if not math.isfinite(v):
            return "–"
        if key in ("solved_pct", "solved_pct_reachable"):
            return f"{v:.1f} %"
        return f"{v:.4g}"
    return str(v)


def markdown(summary: List[dict], unsolved: List[dict], tasks: Optional[List[dict]] = None) -> str:
    lines = ["# Suites", "",
             "Per suite (task family) and optimizer: tasks, runs (task × seed), runs that found a feasible design, "
             "runs *provably* out of reach for the module set (its reach bound against the goals and the task's "
             "base region, docs/diagnosis.md) and runs not found; the solved share of the runs not proven out of "
             "reach; the best cost of the solved runs (median, min, max), the wall time to the first feasible "
             "design (median, max) and, for unsolved runs, the stage that stopped every candidate.", "",
             "| " + " | ".join(SUITE_COLUMNS) + " |", "|" + "---|" * len(SUITE_COLUMNS)]
    lines += ["| " + " | ".join(cell(c, s[c]) for c in SUITE_COLUMNS) + " |" for s in summary]
    if unsolved:
        lines += ["", "## Unsolved tasks", "",
                  "`stopped_at`: the furthest stage any candidate reached (so the stage that stopped every "
                  "candidate); `stage_counts`: where each candidate failed; `verdict`: provably out of reach or "
                  "not found, with the diagnosis' figure.", "",
                  "| " + " | ".join(UNSOLVED_COLUMNS) + " |", "|" + "---|" * len(UNSOLVED_COLUMNS)]
        lines += ["| " + " | ".join(str(u[c]).replace("|", "/") for c in UNSOLVED_COLUMNS) + " |" for u in unsolved]
    if tasks:
        lines += ["", "## Every task", "",
                  "| " + " | ".join(TASK_COLUMNS) + " |", "|" + "---|" * len(TASK_COLUMNS)]
        lines += ["| " + " | ".join(cell(c, t[c]).replace("|", "/") for c in TASK_COLUMNS) + " |" for t in tasks]
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
