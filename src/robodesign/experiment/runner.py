"""Run an experiment: every (task, optimizer, seed) run, stored evaluation by evaluation; resumable.

Results folder (docs/experiments.md)::

    config.yaml            the config exactly as given (resume reads it back)
    meta.json              seeds, runs, package versions, machine, one entry per session
    evaluations.sqlite     every evaluation (WAL, one commit per evaluation)
    best/<task>/<optimizer>-seed<k>.json          best solution of each run (CoBRA solution file)
    best/<task>/<optimizer>-seed<k>.verdict.json  the checker's verdict on that file
    evaluations.csv, anytime_*.csv, plots/*.png, summary.csv, summary.md, index.html   (report.py)

Resume: ``run_experiment(..., resume=True)`` on the folder re-reads ``config.yaml``; finished runs are
skipped, a run that was cut off is replayed from the database (see storage.py) and continued; the
result is exactly the evaluations of an uninterrupted run for evaluation budgets.

Damage: meta.json's ``stored_evaluations`` is the number of evaluations the database held at its last
checkpoint. A resume refuses (InputError, exit 2) when the database is missing, unreadable, or holds
fewer evaluations than that; ``restart=True`` then moves the old database and best files aside into
``damaged-<timestamp>/`` and starts the experiment over in the same folder.
"""
from __future__ import annotations

import datetime as _dt
import json
import math
import os
import platform
import socket
import sys
import time
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

from robodesign.core.errors import InputError
from robodesign.design.optimize import Budget, Study, create_optimizer
from robodesign.experiment.config import ResolvedExperiment, RunSpec, load_experiment
from robodesign.experiment.storage import DB_FILE, ExperimentDB

PACKAGES = ("robodesign", "robodesign-optimizers", "numpy", "pin", "coal", "ompl", "casadi", "ruckig", "toppra",
            "optuna", "deap", "ray", "scipy", "matplotlib", "pydantic", "PyYAML", "rich", "jsonschema", "trimesh")


# ------------------------------------------------------------------------------------------------
# meta
# ------------------------------------------------------------------------------------------------
def package_versions() -> Dict[str, Optional[str]]:
    out: Dict[str, Optional[str]] = {}
    for p in PACKAGES:
        try:
            out[p] = metadata.version(p)
        except metadata.PackageNotFoundError:
            out[p] = None
    return out


def machine_info() -> dict:
    cpu = platform.processor() or ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = None
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal:"):
                mem = int(line.split()[1]) * 1024
                break
    except OSError:
        try:
            mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
        except (ValueError, OSError, AttributeError):
            pass
    usable: Optional[int]
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:
        usable = os.cpu_count()
    return {"hostname": socket.gethostname(), "platform": platform.platform(), "machine": platform.machine(),
            "cpu": cpu, "cores": os.cpu_count(), "usable_cores": usable,
            "memory_gib": round(mem / 2 ** 30, 2) if mem else None,
            "python": sys.version.split()[0], "python_implementation": platform.python_implementation(),
            "python_executable": sys.executable}


def _write_json(path: Path, data) -> None:
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(data, indent=2, default=str))
    tmp.replace(path)


def _now() -> str:
    return _dt.datetime.now().astimezone().isoformat(timespec="seconds")


# ------------------------------------------------------------------------------------------------
# folder
# ------------------------------------------------------------------------------------------------
class FolderLock:
    """An exclusive ``flock`` on ``<dir>/.lock``: two processes never write the same results folder. The
    lock dies with its process (``kill -9`` included)."""

    def __init__(self, folder: Path):
        self.path = Path(folder) / ".lock"
        self.fd = None

    def acquire(self):
        import fcntl
        self.fd = open(self.path, "a+")
        try:
            fcntl.flock(self.fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            self.fd.close()
            self.fd = None
            raise InputError("another robodesign process is writing this results folder", file=str(self.path.parent))
        self.fd.seek(0)
        self.fd.truncate()
        self.fd.write(str(os.getpid()))
        self.fd.flush()
        return self

    def release(self):
        if self.fd is not None:
            import fcntl
            fcntl.flock(self.fd, fcntl.LOCK_UN)
            self.fd.close()
            self.fd = None


def default_out_dir(name: str, root: Path = Path("results")) -> Path:
    stamp = _dt.datetime.now().strftime("%Y%m%d-%H%M%S")
    p = root / f"{name}-{stamp}"
    k = 2
    while p.exists():
        p = root / f"{name}-{stamp}-{k}"
        k += 1
    return p


def best_paths(out: Path, problem: str, optimizer: str, seed: int):
    d = out / "best" / problem
    return d / f"{optimizer}-seed{seed}.json", d / f"{optimizer}-seed{seed}.verdict.json"


# ------------------------------------------------------------------------------------------------
# progress
# ------------------------------------------------------------------------------------------------
def _fmt_cost(v) -> str:
    return "-" if v is None or (isinstance(v, float) and not math.isfinite(v)) else f"{v:.6g}"


class LineProgress:
    """One plain line per evaluation (when stdout is not a terminal)."""

    def __init__(self, stream=None):
        self.stream = stream or sys.stdout

    def _p(self, s):
        print(s, file=self.stream, flush=True)

    def start_run(self, run: RunSpec, k: int, n: int, total: Optional[int], stored: int):
        self.tag = f"[{k}/{n}] {run.problem.name} {run.optimizer.label} seed {run.seed}"
        self.total = total
        self.best = None
        self._p(f"{self.tag}: start (budget {run.optimizer.budget_text}"
                + (f", replaying {stored} stored evaluations" if stored else "") + ")")

    def evaluation(self, index: int, ev, best, replayed: bool):
        if replayed:
            return
        b = best.cost if best is not None and best.feasible else None
        tot = f"/{self.total}" if self.total else ""
        what = f"feasible cost {_fmt_cost(ev.cost)}" if ev.feasible else f"failed at {ev.stage}"
        self._p(f"{self.tag}: eval {index + 1}{tot} {ev.candidate.key()} {what} ({ev.seconds:.2f} s), "
                f"best {_fmt_cost(b)}")

    def end_run(self, run, result, new: int):
        b = result.best_feasible
        self._p(f"{self.tag}: done ({len(result.history)} evaluations, {new} new, {result.stopped}); "
                f"best {_fmt_cost(b.cost) if b else 'none feasible'}")

    def skip_run(self, run, k, n):
        self._p(f"[{k}/{n}] {run.problem.name} {run.optimizer.label} seed {run.seed}: already finished, skipped")

    def message(self, s: str):
        self._p(s)

    def close(self):
        pass


class SummaryProgress(LineProgress):
    """Off a terminal by default: the start and end of each run, and in between a summary line at most
    every ``every`` seconds (not one per evaluation)."""

    def __init__(self, stream=None, every: float = 5.0):
        super().__init__(stream)
        self.every = float(every)

    def start_run(self, run, k, n, total, stored):
        super().start_run(run, k, n, total, stored)
        self.last = time.perf_counter()
        self.t_run = self.last
        self.count = self.feasible = 0

    def evaluation(self, index: int, ev, best, replayed: bool):
        self.count = index + 1
        self.feasible += bool(ev.feasible)
        now = time.perf_counter()
        if replayed or now - self.last < self.every:
            return
        self.last = now
        b = best.cost if best is not None and best.feasible else None
        tot = f"/{self.total}" if self.total else ""
        self._p(f"{self.tag}: {self.count}{tot} evaluations in {now - self.t_run:.0f} s, {self.feasible} feasible "
                f"(this session), best {_fmt_cost(b)}")


class RichProgress:
    """A rich progress bar per run (terminal)."""

    def __init__(self):
        from rich.console import Console
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, SpinnerColumn, TextColumn, TimeElapsedColumn
        self.console = Console()
        self.progress = Progress(SpinnerColumn(), TextColumn("{task.description}"), BarColumn(),
                                 MofNCompleteColumn(), TextColumn("best {task.fields[best]}"), TimeElapsedColumn(),
                                 console=self.console, transient=False)
        self.progress.start()
        self.task = None

    def start_run(self, run, k, n, total, stored):
        desc = f"[{k}/{n}] {run.problem.name} · {run.optimizer.label} · seed {run.seed}"
        self.task = self.progress.add_task(desc, total=total, best="-")

    def evaluation(self, index, ev, best, replayed):
        b = best.cost if best is not None and best.feasible else None
        self.progress.update(self.task, completed=index + 1, best=_fmt_cost(b))

    def end_run(self, run, result, new):
        self.progress.update(self.task, total=len(result.history), completed=len(result.history))

    def skip_run(self, run, k, n):
        self.progress.console.print(f"[{k}/{n}] {run.problem.name} · {run.optimizer.label} · seed {run.seed}: "
                                    "already finished")

    def message(self, s):
        self.progress.console.print(s)

    def close(self):
        self.progress.stop()


class NoProgress:
    def start_run(self, *a):
        pass

    def evaluation(self, *a):
        pass

    def end_run(self, *a):
        pass

    def skip_run(self, *a):
        pass

    def message(self, s):
        pass

    def close(self):
        pass


def make_progress(mode: str = "auto"):
    """``bar`` (rich), ``lines`` (one per evaluation), ``summary`` (one every 5 s at most), ``none``;
    ``auto``: a bar on a terminal, else the summary."""
    if mode == "none":
        return NoProgress()
    if mode == "bar" or (mode == "auto" and sys.stdout.isatty()):
        try:
            return RichProgress()
        except ImportError:
            pass
    return LineProgress() if mode == "lines" else SummaryProgress()


# ------------------------------------------------------------------------------------------------
# best solutions
# ------------------------------------------------------------------------------------------------
def write_best(out: Path, db: ExperimentDB, run: RunSpec) -> Optional[dict]:
    """Write the run's best feasible solution as a CoBRA solution file and store the checker's verdict on
    that very file beside it. Returns the verdict JSON (None when the run found nothing feasible)."""
    from robodesign.formats.solution import load_solution
    from robodesign.judge.checker import check
    best = db.best(run.run_id)
    sol_path, verdict_path = best_paths(out, run.problem.name, run.optimizer.label, run.seed)
    if best is None or not best.get("solution"):
        return None
    sol_path.parent.mkdir(parents=True, exist_ok=True)
    tmp = sol_path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(json.loads(best["solution"]), indent=1))
    tmp.replace(sol_path)
    t0 = time.perf_counter()
    problem = run.problem.problem
    try:
        verdict = check(problem.task, load_solution(sol_path), problem.module_set)
        v = verdict.to_json()
    except Exception as e:  # noqa: BLE001 - record, never crash the experiment on the re-check
        # an error is not a verdict: "valid" stays None (neither VALID nor INVALID), the error is named
        kind = "bad input" if isinstance(e, InputError) else "internal error"
        v = {"valid": None, "error": f"{kind}: {type(e).__name__}: {e}", "cost": None}
    stored = best["cost"]
    v = {"file": sol_path.name, "run": run.run_id, "evaluation": best["idx"], "candidate": best["candidate_key"],
         "cost_stored": stored, "check_seconds": round(time.perf_counter() - t0, 4), "checked_at": _now(),
         "agrees": bool(v.get("valid")) and v.get("cost") is not None and stored is not None
         and abs(v["cost"] - stored) <= 1e-6 * max(1.0, abs(stored)), **v}
    _write_json(verdict_path, v)
    return v


# ------------------------------------------------------------------------------------------------
# running
# ------------------------------------------------------------------------------------------------
@dataclass
class ExperimentOutcome:
    out_dir: Path
    report: Optional[Path]
    evaluations: int
    new_evaluations: int
    runs: int
    skipped_runs: int
    best: Dict[str, Optional[dict]] = field(default_factory=dict)  # problem → best feasible row (+ run info)
    executor: dict = field(default_factory=dict)
    seconds: float = 0.0
    problems_verdicts: Dict[str, dict] = field(default_factory=dict)


def prepare_new(exp: ResolvedExperiment, config_text: str, config_path: Optional[Path], out: Path) -> None:
    if (out / DB_FILE).exists() or (out / "meta.json").exists():
        raise InputError(f"already holds an experiment; continue it with --resume {out}", file=str(out))
    out.mkdir(parents=True, exist_ok=True)
    (out / "config.yaml").write_text(config_text, encoding="utf-8")
    meta = {
        "name": exp.name, "created": _now(),
        "config_file": str(Path(config_path).resolve()) if config_path else None,
        "config_dir": str(exp.base_dir.resolve()),
        "seeds": exp.seeds, "eval_seed": exp.config.eval_seed,
        "problems": [p.to_json() for p in exp.problems],
        "optimizers": [{"label": o.label, "name": o.name, "options": o.options, "budget": o.budget_text,
                        "batch_size": o.batch_size} for o in exp.optimizers],
        "runs": [{"run_id": r.run_id, "task": r.problem.name, "optimizer": r.optimizer.label, "seed": r.seed}
                 for r in exp.runs()],
        "solve": exp.config.solve.model_dump(),
        "versions": package_versions(), "machine": machine_info(), "sessions": [], "stored_evaluations": 0,
        "note": "results are exact and resumable for evaluation budgets; time budgets depend on the machine",
    }
    _write_json(out / "meta.json", meta)


def load_resume(folder: Path):
    """(experiment, config text, meta) of an existing results folder."""
    folder = Path(folder)
    meta_p, cfg_p = folder / "meta.json", folder / "config.yaml"
    if not meta_p.is_file() or not cfg_p.is_file():
        raise InputError("not a results folder (no meta.json / config.yaml)", file=str(folder))
    try:
        meta = json.loads(meta_p.read_text())
    except ValueError as e:
        raise InputError(f"unreadable meta.json: {e}", file=str(folder)) from None
    exp, text = load_experiment(cfg_p, display=str(cfg_p), base_dir=Path(meta.get("config_dir") or folder),
                                default_name=meta.get("name"))
    if isinstance(meta.get("solve"), dict):
        # the solve settings the evaluations were made with, not today's defaults: a resume stays exact
        # even if robodesign's defaults changed in between
        import dataclasses

        from robodesign.design.solve import SolveSettings
        known = {f.name for f in dataclasses.fields(SolveSettings)}
        exp.solve = SolveSettings(**{k: v for k, v in meta["solve"].items() if k in known})
    return exp, text, meta


def claimed_evaluations(meta: dict) -> int:
    """How many evaluations meta.json says the database holds (folders written before ``stored_evaluations``
    existed: the sum of the finished sessions' new evaluations)."""
    if "stored_evaluations" in meta:
        return int(meta["stored_evaluations"] or 0)
    return sum(int(s.get("new_evaluations") or 0) for s in meta.get("sessions", []))


def open_for_resume(out: Path, meta: dict) -> ExperimentDB:
    """The results database of a folder being resumed, after checking that it holds at least what meta.json
    says was stored; otherwise an InputError saying what is missing and what to do."""
    path = out / DB_FILE
    claimed = claimed_evaluations(meta)
    todo = (f"restore {DB_FILE} (with its {DB_FILE}-wal file, if any) from a copy, or start the experiment over "
            f"in this folder with `robodesign run --resume {out} --restart` (the old files are moved aside)")
    if not path.is_file():
        if claimed:
            raise InputError(f"the results database is missing, but meta.json records {claimed} stored "
                             f"evaluations: {todo}", file=str(path))
        return _open_db(path, out)
    if path.stat().st_size == 0 and claimed:
        raise InputError(f"the results database is an empty file, but meta.json records {claimed} stored "
                         f"evaluations: {todo}", file=str(path))
    wal_lost = not Path(f"{path}-wal").exists()
    db = _open_db(path, out)
    held = db.count()
    if held < claimed:
        db.on_checkpoint = None  # closing must not overwrite meta.json's record with the smaller count
        db.close()
        what = "holds no evaluations" if held == 0 else f"holds only {held} evaluations"
        why = " (its -wal file is gone: was the .sqlite copied or restored without it?)" if wal_lost else ""
        raise InputError(f"the results database {what}, but meta.json records {claimed} stored evaluations{why}: "
                         f"{todo}", file=str(path))
    return db


def restart_folder(out: Path, meta: dict) -> dict:
    """Move the database (and its -wal/-shm) and the best files aside into ``damaged-<timestamp>/``; the
    experiment then starts over in the folder. Nothing is deleted."""
    aside = out / f"damaged-{_dt.datetime.now().strftime('%Y%m%d-%H%M%S')}"
    k = 2
    while aside.exists():
        aside = out / f"damaged-{_dt.datetime.now().strftime('%Y%m%d-%H%M%S')}-{k}"
        k += 1
    moved = []
    for name in (DB_FILE, f"{DB_FILE}-wal", f"{DB_FILE}-shm", "best"):
        if (out / name).exists():
            aside.mkdir(exist_ok=True)
            (out / name).replace(aside / name)
            moved.append(name)
    meta.setdefault("restarts", []).append({"at": _now(), "stored_evaluations": claimed_evaluations(meta),
                                            "moved_to": aside.name if moved else None, "moved": moved})
    meta["stored_evaluations"] = 0
    return meta


def _open_db(path: Path, out: Path) -> ExperimentDB:
    def record(count: int) -> None:
        meta = json.loads((out / "meta.json").read_text())
        meta["stored_evaluations"] = count
        _write_json(out / "meta.json", meta)
    return ExperimentDB(path, on_checkpoint=record)


def run_experiment(exp: ResolvedExperiment, out: Path, *, config_text: str = "", config_path=None,
                   resume: bool = False, restart: bool = False, executor: Optional[str] = None,
                   workers: Optional[int] = None, address: Optional[str] = None,
                   chunk_size: Optional[int] = None, progress=None, report: bool = True) -> ExperimentOutcome:
    """Run (or resume) an experiment into ``out``. The executor settings of the config can be overridden.
    ``restart`` (with ``resume``): start the experiment over in its folder, the old results moved aside."""
    out = Path(out)
    t_start = time.perf_counter()
    progress = progress or NoProgress()
    lock, db = _open_folder(exp, out, config_text, config_path, resume, restart, progress)
    pool = None
    session: Dict[str, Any] = {"started": _now(), "resume": resume, "argv": sys.argv, "pid": os.getpid()}
    meta = json.loads((out / "meta.json").read_text())
    meta.setdefault("sessions", []).append(session)
    _write_json(out / "meta.json", meta)
    total_new = 0
    skipped = 0
    runs = list(exp.runs())
    try:
        pool = _start_pool(exp, out, db, runs, session, progress, executor, workers, address, chunk_size)
        for k, r in enumerate(runs, 1):
            if db.run_status(r.run_id) == "done":
                skipped += 1
                progress.skip_run(r, k, len(runs))
                continue
            total_new += _run_one(exp, r, k, len(runs), db, pool, progress)
            write_best(out, db, r)
        session["finished"] = _now()
        session["status"] = "complete"
    except BaseException as e:
        session["finished"] = _now()
        session["status"] = f"interrupted: {type(e).__name__}"
        raise
    finally:
        session["new_evaluations"] = total_new
        if pool is not None:
            session["executor"] = pool.info()
            # after Ctrl-C / SIGTERM the workers are stopped at once (what they had in flight was not stored)
            pool.close(now=session.get("status") != "complete")
        meta = json.loads((out / "meta.json").read_text())
        meta["sessions"][-1] = session
        _write_json(out / "meta.json", meta)
        lock.release()
    # best files of runs finished in an earlier session whose files are missing (e.g. killed in between)
    for r in runs:
        sp, vp = best_paths(out, r.problem.name, r.optimizer.label, r.seed)
        if not vp.exists() and db.best(r.run_id) is not None:
            write_best(out, db, r)
    report_path = None
    if report:
        from robodesign.experiment.report import write_report
        report_path = write_report(out, db=db)
    outcome = ExperimentOutcome(out_dir=out, report=report_path, evaluations=db.count(), new_evaluations=total_new,
                                runs=len(runs), skipped_runs=skipped, executor=session.get("executor", {}),
                                seconds=time.perf_counter() - t_start)
    for p in exp.problems:
        outcome.best[p.name] = best_of_problem(db, p.name)
    db.close()
    return outcome


def _open_folder(exp: ResolvedExperiment, out: Path, config_text: str, config_path, resume: bool, restart: bool,
                 progress) -> Tuple[FolderLock, ExperimentDB]:
    """Prepare a new results folder (or take the one resumed, restarted if asked), lock it and open its
    database. → (the lock, held, and the database)."""
    if restart and not resume:
        raise InputError("--restart needs --resume DIR (it starts the experiment in that folder over)")
    if not resume:
        prepare_new(exp, config_text, config_path, out)
    lock = FolderLock(out).acquire()
    try:
        meta = json.loads((out / "meta.json").read_text())
        if restart:
            _write_json(out / "meta.json", restart_folder(out, meta))
            progress.message(f"restart: the old results are in {meta['restarts'][-1]['moved_to'] or '(nothing)'}")
        db = open_for_resume(out, meta) if resume else _open_db(out / DB_FILE, out)
    except BaseException:
        lock.release()
        raise
    return lock, db


def _start_pool(exp: ResolvedExperiment, out: Path, db: ExperimentDB, runs: List[RunSpec], session: Dict[str, Any],
                progress, executor: Optional[str], workers: Optional[int], address: Optional[str],
                chunk_size: Optional[int]):
    """Record every run in the database and, when some are not done, start the executor's pool (recorded in
    meta.json at once). → the pool, or None when there is nothing to run."""
    from robodesign.experiment.executors import make_pool
    for k, r in enumerate(runs):
        db.ensure_run(r.run_id, r.problem.name, r.optimizer.label, r.optimizer.name, r.seed, k,
                      r.optimizer.budget_text, r.optimizer.batch_size)
    kind = executor or exp.executor.kind
    todo = [r for r in runs if db.run_status(r.run_id) != "done"]
    if not todo:
        return None
    pool = make_pool(kind, exp.evaluator_specs(), workers or exp.executor.workers,
                     address or exp.executor.address, chunk_size or exp.executor.chunk_size)
    session["executor"] = pool.info()
    meta = json.loads((out / "meta.json").read_text())
    meta["sessions"][-1] = session  # recorded now: a killed session keeps its executor in meta.json
    _write_json(out / "meta.json", meta)
    progress.message(f"executor: {pool.kind}, {pool.workers} worker(s), ready in {pool.startup_seconds:.1f} s")
    return pool


def best_of_problem(db: ExperimentDB, problem: str) -> Optional[dict]:
    row = db.con.execute(
        "SELECT e.*, r.optimizer AS optimizer, r.seed AS run_seed FROM evaluations e JOIN runs r USING (run_id) "
        "WHERE r.task=? AND e.feasible=1 AND e.cost IS NOT NULL ORDER BY e.cost, r.ordinal, e.idx LIMIT 1",
        (problem,)).fetchone()
    return dict(row) if row else None


def _run_one(exp: ResolvedExperiment, r: RunSpec, k: int, n: int, db: ExperimentDB, pool, progress) -> int:
    opt = create_optimizer(r.optimizer.name, r.problem.problem, seed=r.seed, options=r.optimizer.options)
    storage = db.storage(r.run_id, r.problem.problem)
    budget = r.optimizer.budget
    if budget.seconds is not None:
        # the time budget is the run's total wall time: a resumed run gets what is left of it
        used = db.con.execute("SELECT MAX(wall) FROM evaluations WHERE run_id=?", (r.run_id,)).fetchone()[0] or 0.0
        budget = Budget(budget.evaluations, max(budget.seconds - used, 1e-9))
    stored = db.count(r.run_id)
    db.start_run(r.run_id)
    progress.start_run(r, k, n, budget.evaluations, stored)

    def on_evaluation(index, ev, best):
        progress.evaluation(index, ev, best, index < storage.n_stored)

    study = Study(opt, pool.bind(exp.spec_id(r.problem, r.seed)), budget, batch_size=r.optimizer.batch_size,
                  storage=storage, on_evaluation=on_evaluation)
    result = study.run()
    db.finish_run(r.run_id, result.stopped)
    new = len(result.history) - storage.n_stored
    progress.end_run(r, result, new)
    return new
