"""The journal of ``robodesign optimize``: every evaluation is committed as it arrives (the experiments'
results database, :mod:`robodesign.experiment.storage`, one run), so an interrupted search continues with
``--resume`` where it stopped and ends with the result of an uninterrupted one (the same seed and
evaluation budget give the same best design: the stored evaluations are replayed through the seeded
optimizer, :class:`robodesign.design.optimize.Study`).

The journal is ``<out>.journal.sqlite`` beside ``--out`` (``best_solution.journal.sqlite`` by default). It
is kept when the search is interrupted (Ctrl-C, SIGTERM, a crash) and deleted when the search ends by its
budget or because the optimizer has nothing left to ask. A search refuses to start over an existing journal
without ``--resume`` (its evaluations would be lost), and ``--resume`` refuses a journal written with
other settings (the setting is named).
"""
from __future__ import annotations

import json
import shlex
from pathlib import Path
from typing import IO, List, Optional

from robodesign.core.errors import InputError
from robodesign.design.optimize import Budget
from robodesign.experiment.storage import ExperimentDB, RunStorage

RUN_ID = "optimize"
DEFAULT_OUT = "best_solution.json"
#: the settings a resumed search must share with the interrupted one (the budget may grow)
SETTINGS = ("task", "modules", "optimizer", "cost", "seed", "batch_size", "opt", "dof", "max_links", "fixed_base",
            "planner", "plan_time", "optimize_trajectory")


def journal_path(out: Optional[str]) -> Path:
    """``<out>.journal.sqlite`` beside the solution file ``out`` (default ``best_solution.json``)."""
    p = Path(out or DEFAULT_OUT)
    return p.with_name(p.stem + ".journal.sqlite")


def settings_of(args) -> dict:
    return {k: getattr(args, k, None) for k in SETTINGS}


def resume_command(argv: Optional[List[str]] = None) -> str:
    """The command line that continues this search: the same arguments (default: this process's) and
    ``--resume``."""
    import sys
    args = [a for a in (sys.argv[1:] if argv is None else argv) if a != "--resume"]
    return "robodesign " + shlex.join(args + ["--resume"])


class Journal:
    """The open journal of one ``optimize`` command (see the module doc): ``storage`` is the Study's
    storage, ``budget`` what is left of the budget (a time budget counts the time already spent)."""

    def __init__(self, args, problem, budget: Budget):
        self.path = journal_path(args.out)
        self.resumed = bool(getattr(args, "resume", False))
        self.lock: Optional[IO[str]] = None
        exists = self.path.exists() and self.path.stat().st_size > 0
        if exists and not self.resumed:
            raise InputError("holds the evaluations of an unfinished search (interrupted?): continue it with the "
                             "same command and --resume, or delete the file to start over", file=str(self.path))
        if self.resumed and not exists:
            raise InputError("no journal to resume (it is written beside --out while `optimize` runs and deleted "
                             "when the search ends; give the --out of the interrupted command)", file=str(self.path))
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)  # where --out goes (written at the end)
        except OSError as e:
            raise InputError(f"cannot create the folder of --out: {e.strerror}", file=str(self.path.parent)) from None
        self._lock()
        self.db = ExperimentDB(self.path, checkpoint_seconds=1.0)
        try:
            settings = settings_of(args)
            if self.resumed:
                stored = json.loads(self.db.info("optimize_settings") or "{}")
                for k in SETTINGS:
                    if k in stored and stored[k] != settings[k]:
                        raise InputError(f"--resume: the interrupted search used --{k.replace('_', '-')} "
                                         f"{stored[k]!r}, this command gives {settings[k]!r}; resume it with the "
                                         f"same settings (or delete the journal to start over)", file=str(self.path))
            else:
                self.db.set_info("optimize_settings", json.dumps(settings))
            self.db.ensure_run(RUN_ID, str(args.task), args.optimizer, args.optimizer, args.seed, 0, args.budget,
                               args.batch_size)
            self.stored = self.db.count(RUN_ID)
            self.budget = budget
            if budget.seconds is not None and self.stored:
                used = self.db.con.execute("SELECT MAX(wall) FROM evaluations WHERE run_id=?",
                                           (RUN_ID,)).fetchone()[0] or 0.0
                self.budget = Budget(budget.evaluations, max(budget.seconds - used, 1e-9))
            self.storage: RunStorage = self.db.storage(RUN_ID, problem)
        except BaseException:
            self.close(keep=True)
            raise

    def _lock(self) -> None:
        import fcntl
        self.lock = lock = open(self.path.with_name(self.path.name + ".lock"), "a+")
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            lock.close()
            self.lock = None
            raise InputError("another robodesign optimize is writing this journal (use another --out)",
                             file=str(self.path)) from None

    def close(self, keep: bool) -> None:
        """Close the journal; ``keep=False`` (the search ended) deletes it, and so does ``keep=True`` when it
        holds no evaluation (a search stopped before its first result has nothing to resume)."""
        if getattr(self, "db", None) is not None:
            try:
                keep = keep and self.db.count(RUN_ID) > 0
            except Exception:  # noqa: BLE001 - unreadable: keep it for the user to look at
                pass
            self.db.close()
            del self.db  # closed: ``getattr(self, "db", None)`` is None
        if not keep:
            for p in (self.path, Path(f"{self.path}-wal"), Path(f"{self.path}-shm")):
                p.unlink(missing_ok=True)
        if self.lock is not None:
            import fcntl
            fcntl.flock(self.lock, fcntl.LOCK_UN)
            self.lock.close()
            self.lock = None
            self.path.with_name(self.path.name + ".lock").unlink(missing_ok=True)


EXIT_INTERRUPTED = 130  # 128 + SIGINT, as a shell reports a command stopped by Ctrl-C


def write_best(best, out: Optional[str]) -> Path:
    """Write the solution of the feasible evaluation ``best`` (checked by the evaluator) to ``out``
    atomically (a temporary file renamed: an interrupt never leaves half a file)."""
    from robodesign.formats.solution import parse_solution
    path = Path(out or DEFAULT_OUT)
    tmp = path.with_name(path.name + ".tmp")
    parse_solution(best.solution, "best").write(tmp)
    tmp.replace(path)
    return path


def write_interrupted(args, res, journal: Journal) -> None:
    """After Ctrl-C / SIGTERM: the best checked design so far to ``--out`` and, on stderr, what was kept and
    the command that resumes the search."""
    import sys
    best = res.best_feasible
    new = len(res.history) - journal.stored
    line = f"robodesign: interrupted after {len(res.history)} evaluations ({new} in this session)"
    if best is not None and best.solution is not None:
        out = write_best(best, args.out)
        line += f"; the best design so far ({args.cost} = {best.cost:.6g}) is written to {out} (checked valid)"
    else:
        line += "; no feasible design yet, no solution written"
    print(line, file=sys.stderr)
    print(f"robodesign: the evaluations are kept in {journal.path}; resume with: "
          f"{resume_command(getattr(args, 'argv', None))}", file=sys.stderr, flush=True)
