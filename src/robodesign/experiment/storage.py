"""The results database ``evaluations.sqlite``: every evaluation of every run, committed one by one.

Durability: WAL journal, one transaction per evaluation (``synchronous=NORMAL``: a committed evaluation
survives the process being killed at any moment, ``kill -9`` included; only an OS crash or power loss
may lose the last commits, and those are re-evaluated on resume). The WAL is checkpointed into the main
file every ``checkpoint_seconds`` (default 1 s) and on close, so the ``.sqlite`` file alone (copied
without its ``-wal``) holds every evaluation but those of the last second of a killed run. After each
checkpoint ``on_checkpoint(count)`` reports the evaluations stored so far (the runner records the number
in meta.json, where a resume compares it with what the database holds).

Damage: opening an unreadable file (truncated, garbled, not SQLite; SQLite's ``quick_check``) raises
:class:`DamagedDatabase`, an :class:`~robodesign.core.errors.InputError` naming the file and what to do, never a
traceback.

Exact resume: :class:`RunStorage` is the ``storage`` of a :class:`robodesign.design.optimize.Study`. ``load()``
returns the stored evaluations of the run in ask order; the study replays them through the (seeded,
deterministic) optimizer and checks that it asks the same candidates again, then continues. Indices
are a primary key, so an evaluation can never be stored twice.

Tables: ``runs`` (one row per (task, optimizer, seed)), ``evaluations`` (one row per evaluation),
``info`` (key/value).
"""
from __future__ import annotations

import json
import math
import sqlite3
import time
from pathlib import Path
from typing import Callable, List, Optional

from robodesign.core.errors import InputError
from robodesign.design.evaluator import EVALUATION_RULES, Evaluation
from robodesign.design.search_space import Candidate

SCHEMA_VERSION = 1
DB_FILE = "evaluations.sqlite"

_SCHEMA = """
CREATE TABLE IF NOT EXISTS info (key TEXT PRIMARY KEY, value TEXT);
CREATE TABLE IF NOT EXISTS runs (
    run_id TEXT PRIMARY KEY,
    task TEXT NOT NULL,
    optimizer TEXT NOT NULL,
    optimizer_name TEXT NOT NULL,
    seed INTEGER NOT NULL,
    ordinal INTEGER NOT NULL,
    budget TEXT,
    batch_size INTEGER,
    status TEXT NOT NULL DEFAULT 'pending',   -- pending | running | done
    stopped TEXT,                              -- budget | exhausted
    sessions INTEGER NOT NULL DEFAULT 0,
    started_at REAL,
    finished_at REAL,
    wall_seconds REAL
);
CREATE TABLE IF NOT EXISTS evaluations (
    run_id TEXT NOT NULL REFERENCES runs(run_id),
    idx INTEGER NOT NULL,
    candidate_key TEXT NOT NULL,
    module_order TEXT NOT NULL,      -- JSON list of module IDs, base first
    base TEXT NOT NULL,              -- JSON list of base parameters (x, y, z, yaw offsets; free ones only)
    feasible INTEGER NOT NULL,
    stage TEXT NOT NULL,             -- first failed stage or 'done'
    stage_index INTEGER NOT NULL,
    goals_reached INTEGER NOT NULL,
    cost REAL,
    score REAL NOT NULL,
    timings TEXT NOT NULL,           -- JSON: [{name, passed, seconds, message}] per solve stage
    costs TEXT NOT NULL,             -- JSON: every built-in cost of the checked solution
    message TEXT NOT NULL,
    seed INTEGER NOT NULL,           -- the per-candidate seed of the evaluation
    eval_seconds REAL NOT NULL,      -- time the evaluation took (in its worker)
    wall REAL NOT NULL,              -- run wall-clock seconds when the result was committed
    created_at REAL NOT NULL,        -- unix time of the commit
    solution TEXT,                   -- CoBRA solution JSON (feasible evaluations)
    PRIMARY KEY (run_id, idx)
);
"""


def connect(path, readonly: bool = False) -> sqlite3.Connection:
    if readonly:
        con = sqlite3.connect(f"file:{Path(path)}?mode=ro", uri=True, timeout=30)
    else:
        con = sqlite3.connect(str(path), timeout=30, isolation_level=None)  # autocommit; explicit BEGIN
        con.execute("PRAGMA journal_mode=WAL")
        con.execute("PRAGMA synchronous=NORMAL")
    con.row_factory = sqlite3.Row
    return con


def _num(v: Optional[float]) -> Optional[float]:
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None


CHECKPOINT_SECONDS = 1.0


class DamagedDatabase(InputError):
    """The results database cannot be read (truncated, garbled, not an SQLite file)."""

    def __init__(self, path: Path, reason: str):
        folder = Path(path).parent
        reason = " ".join(str(reason).split())  # one line (an integrity check answers on several)
        super().__init__(
            f"the results database is damaged ({reason}). Keep a copy of the folder; to salvage what is readable "
            f"run `sqlite3 {path} .recover | sqlite3 recovered.sqlite`; to start the experiment over in this "
            f"folder run `robodesign run --resume {folder} --restart` (the damaged file is moved aside, not "
            f"deleted)", file=str(path))


class ExperimentDB:
    """The results database of one results folder (see the module doc).

    ``checkpoint_seconds``: copy the WAL into the main file at most this often (after a commit) and on
    close; ``on_checkpoint(count)`` is then called with the number of stored evaluations."""

    def __init__(self, path, checkpoint_seconds: float = CHECKPOINT_SECONDS,
                 on_checkpoint: Optional[Callable[[int], None]] = None):
        self.path = Path(path)
        self.checkpoint_seconds = float(checkpoint_seconds)
        self.on_checkpoint = on_checkpoint
        self._last_checkpoint = time.monotonic()
        self._stored: Optional[int] = None  # evaluations stored (counted once when opened, then +1 per insert)
        try:
            self.con = connect(self.path)
            if self.path.stat().st_size > 0:
                row = self.con.execute("PRAGMA quick_check(1)").fetchone()
                if row is None or row[0] != "ok":
                    raise DamagedDatabase(self.path, f"integrity check: {row[0] if row else 'no answer'}")
            self.con.executescript(_SCHEMA)
            self.con.execute("INSERT OR IGNORE INTO info(key, value) VALUES ('schema_version', ?)",
                             (str(SCHEMA_VERSION),))
            self._stored = self.count()
        except sqlite3.DatabaseError as e:
            self.close()
            raise DamagedDatabase(self.path, str(e)) from None
        except DamagedDatabase:
            self.close()
            raise

    def checkpoint(self) -> int:
        """Copy the WAL into the main database file now; returns the number of stored evaluations."""
        self.con.execute("PRAGMA wal_checkpoint(PASSIVE)").fetchone()
        self._last_checkpoint = time.monotonic()
        assert self._stored is not None  # (an ExperimentDB that did not open raised in __init__)
        if self.on_checkpoint is not None:
            self.on_checkpoint(self._stored)
        return self._stored

    def close(self) -> None:
        con = getattr(self, "con", None)
        if con is None:
            return
        try:
            if self._stored is not None:
                con.execute("PRAGMA wal_checkpoint(TRUNCATE)").fetchone()
                if self.on_checkpoint is not None:
                    self.on_checkpoint(self._stored)
        except sqlite3.Error:
            pass
        try:
            con.close()
        except sqlite3.Error:
            pass
        del self.con  # closed: ``getattr(db, "con", None)`` is None

    # -- runs -------------------------------------------------------------------------------------
    def ensure_run(self, run_id: str, task: str, optimizer: str, optimizer_name: str, seed: int, ordinal: int,
                   budget: str, batch_size: int) -> None:
        self.con.execute(
            "INSERT OR IGNORE INTO runs(run_id, task, optimizer, optimizer_name, seed, ordinal, budget, batch_size) "
            "VALUES (?,?,?,?,?,?,?,?)", (run_id, task, optimizer, optimizer_name, int(seed), ordinal, budget,
                                         int(batch_size)))

    def run_status(self, run_id: str) -> Optional[str]:
        row = self.con.execute("SELECT status FROM runs WHERE run_id=?", (run_id,)).fetchone()
        return row["status"] if row else None

    def start_run(self, run_id: str) -> None:
        self.con.execute("UPDATE runs SET status='running', sessions=sessions+1, "
                         "started_at=COALESCE(started_at, ?) WHERE run_id=?", (time.time(), run_id))

    def finish_run(self, run_id: str, stopped: str) -> None:
        wall = self.con.execute("SELECT MAX(wall) FROM evaluations WHERE run_id=?", (run_id,)).fetchone()[0]
        self.con.execute("UPDATE runs SET status='done', stopped=?, finished_at=?, wall_seconds=? WHERE run_id=?",
                         (stopped, time.time(), wall or 0.0, run_id))

    def runs(self) -> List[dict]:
        return [dict(r) for r in self.con.execute("SELECT * FROM runs ORDER BY ordinal")]

    def count(self, run_id: Optional[str] = None) -> int:
        if run_id is None:
            return self.con.execute("SELECT COUNT(*) FROM evaluations").fetchone()[0]
        return self.con.execute("SELECT COUNT(*) FROM evaluations WHERE run_id=?", (run_id,)).fetchone()[0]

    # -- evaluations --------------------------------------------------------------------------------
    def insert(self, run_id: str, index: int, ev: Evaluation, wall: float) -> None:
        c = ev.candidate
        row = (run_id, int(index), c.key(), json.dumps(list(c.order)), json.dumps([float(x) for x in c.base]),
               int(bool(ev.feasible)), ev.stage, int(ev.stage_index), int(ev.goals_reached), _num(ev.cost),
               float(ev.score), json.dumps(ev.stages), json.dumps({k: _num(v) for k, v in (ev.costs or {}).items()}),
               ev.message or "", int(ev.seed), float(ev.seconds), float(wall), time.time(),
               json.dumps(ev.solution) if ev.solution is not None else None)
        try:
            self.con.execute("BEGIN IMMEDIATE")
            self.con.execute("INSERT INTO evaluations VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?)", row)
            self.con.execute("COMMIT")
        except sqlite3.IntegrityError:
            self.con.execute("ROLLBACK")
            raise RuntimeError(f"evaluation {index} of run {run_id!r} is already stored (a second process writing "
                               f"to the same results folder?)") from None
        assert self._stored is not None
        self._stored += 1
        if time.monotonic() - self._last_checkpoint >= self.checkpoint_seconds:
            self.checkpoint()

    def evaluations(self, run_id: Optional[str] = None, with_solution: bool = False) -> List[dict]:
        cols = "*" if with_solution else ", ".join(
            c for c in ("run_id", "idx", "candidate_key", "module_order", "base", "feasible", "stage", "stage_index",
                        "goals_reached", "cost", "score", "timings", "costs", "message", "seed", "eval_seconds",
                        "wall", "created_at"))
        if run_id is None:
            q = f"SELECT {cols} FROM evaluations ORDER BY run_id, idx"
            rows = self.con.execute(q)
        else:
            rows = self.con.execute(f"SELECT {cols} FROM evaluations WHERE run_id=? ORDER BY idx", (run_id,))
        return [dict(r) for r in rows]

    def solution(self, run_id: str, index: int) -> Optional[dict]:
        row = self.con.execute("SELECT solution FROM evaluations WHERE run_id=? AND idx=?", (run_id, index)).fetchone()
        return json.loads(row[0]) if row and row[0] else None

    def best(self, run_id: str) -> Optional[dict]:
        """The best feasible evaluation of a run (lowest cost; the earliest on ties)."""
        row = self.con.execute("SELECT * FROM evaluations WHERE run_id=? AND feasible=1 AND cost IS NOT NULL "
                               "ORDER BY cost, idx LIMIT 1", (run_id,)).fetchone()
        return dict(row) if row else None

    def info(self, key: str) -> Optional[str]:
        row = self.con.execute("SELECT value FROM info WHERE key=?", (key,)).fetchone()
        return row[0] if row else None

    def set_info(self, key: str, value: str) -> None:
        self.con.execute("INSERT OR REPLACE INTO info (key, value) VALUES (?, ?)", (key, value))

    def storage(self, run_id: str, problem=None) -> "RunStorage":
        """The Study storage of run ``run_id``; with its :class:`~robodesign.design.problem.Problem`, the run's stored
        evaluations are tied to that problem (see :class:`RunStorage`)."""
        return RunStorage(self, run_id, problem)


def row_to_evaluation(r: dict) -> Evaluation:
    cand = Candidate(tuple(json.loads(r["module_order"])), tuple(float(x) for x in json.loads(r["base"])))
    return Evaluation(candidate=cand, feasible=bool(r["feasible"]), cost=r["cost"], score=float(r["score"]),
                      stage=r["stage"], stage_index=int(r["stage_index"]), goals_reached=int(r["goals_reached"]),
                      seconds=float(r["eval_seconds"]), seed=int(r["seed"]), stages=json.loads(r["timings"]),
                      message=r["message"], solution=json.loads(r["solution"]) if r.get("solution") else None,
                      costs={k: (v if v is not None else math.nan) for k, v in json.loads(r["costs"]).items()})


class RunStorage:
    """``Study`` storage of one run: ``load()`` (stored evaluations, ask order) and ``append(index, ev)``.

    ``wall`` of an evaluation is the run's wall-clock time when it was committed; a resumed session
    continues from the last stored value, so the anytime curves vs time exclude the time the run was dead.

    Given the run's ``problem``, the storage records its fingerprint (``info`` key ``problem:<run id>``)
    with the first evaluation, and ``load()`` refuses to resume the run when the problem's fingerprint
    changed since (the task file, the module set, the cost or the base bounds differ): stored evaluations
    would no longer be evaluations of this problem. Likewise it records the evaluation rules
    (:data:`~robodesign.design.evaluator.EVALUATION_RULES`, ``info`` key ``rules:<run id>``; a run stored
    without one was made under rules 1) and refuses a run made under other rules: this robodesign would
    evaluate its remaining candidates differently, and the resumed run would not be one run.
    """

    def __init__(self, db: ExperimentDB, run_id: str, problem=None):
        self.db = db
        self.run_id = run_id
        self.fingerprint = problem.fingerprint() if problem is not None else None
        self.n_stored = 0
        self.wall_offset = 0.0
        self._t0 = time.perf_counter()
        self.on_append = None

    def load(self) -> List[Evaluation]:
        rows = [dict(r) for r in self.db.con.execute(
            "SELECT * FROM evaluations WHERE run_id=? ORDER BY idx", (self.run_id,))]
        if self.fingerprint is not None and rows:
            stored = self.db.info(f"problem:{self.run_id}")
            if stored is not None and stored != self.fingerprint:
                raise InputError(f"cannot resume run {self.run_id!r}: its problem changed since its evaluations were "
                                 "stored (the task file, module set, cost or base bounds differ); start a new results "
                                 "folder", file=str(self.db.path))
            stored_rules = self.db.info(f"rules:{self.run_id}") or "1"
            rules = int(stored_rules) if stored_rules.isdigit() else stored_rules   # (a damaged record: not ours)
            if rules != EVALUATION_RULES:
                raise InputError(f"cannot resume run {self.run_id!r}: its evaluations were made under evaluation rules "
                                 f"{rules}, this robodesign evaluates under rules {EVALUATION_RULES} (it would evaluate "
                                 "the remaining candidates differently; docs/experiments.md, \"Stopping and resuming\"); "
                                 "start a new results folder, or finish the run with the robodesign that began it",
                                 file=str(self.db.path))
        for k, r in enumerate(rows):
            if r["idx"] != k:
                raise RuntimeError(f"run {self.run_id!r}: stored evaluations are not contiguous (index {r['idx']} "
                                   f"at position {k})")
        self.n_stored = len(rows)
        self.wall_offset = max((r["wall"] for r in rows), default=0.0)
        self._t0 = time.perf_counter()
        return [row_to_evaluation(r) for r in rows]

    def wall(self) -> float:
        return self.wall_offset + (time.perf_counter() - self._t0)

    def append(self, index: int, evaluation: Evaluation) -> None:
        if index == 0 and self.fingerprint is not None:
            self.db.set_info(f"problem:{self.run_id}", self.fingerprint)
            self.db.set_info(f"rules:{self.run_id}", str(EVALUATION_RULES))
        self.db.insert(self.run_id, index, evaluation, self.wall())
        if self.on_append is not None:
            self.on_append(index, evaluation)
