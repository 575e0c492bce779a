"""Progress of the long commands (``optimize``): a bar on a terminal; off a terminal (a log, a pipe, CI) a
summary line at most every :data:`SUMMARY_SECONDS`; ``--verbose`` one line per evaluation, ``--quiet`` (and
``--json``) none."""
from __future__ import annotations

import sys
import time

#: off a terminal, at most one progress line per this many seconds (the issue's "quiet by default")
SUMMARY_SECONDS = 5.0


def progress_mode(args) -> str:
    """"none", "lines", "bar" or "summary" from ``--json``, ``--quiet``, ``--verbose`` and the terminal."""
    if getattr(args, "json", False) or getattr(args, "quiet", False):
        return "none"
    if getattr(args, "verbose", False):
        return "lines"
    return "bar" if sys.stderr.isatty() else "summary"


class Progress:
    """Progress of a study on stderr; called as ``on_evaluation(index, evaluation, best)``."""

    def __init__(self, budget, mode: str = "summary", every: float = SUMMARY_SECONDS):
        self.mode = mode
        self.every = float(every)
        self.t0 = time.perf_counter()
        self.last = self.t0
        self.count = 0
        self.feasible = 0
        self.bar = None
        if mode == "bar":
            from rich.progress import BarColumn, TextColumn, TimeElapsedColumn
            from rich.progress import Progress as RichProgress
            self.bar = RichProgress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed} evals"),
                                    TimeElapsedColumn(), transient=True)
            self.bar.start()
            self.task = self.bar.add_task("optimizing", total=budget.evaluations)

    @staticmethod
    def _best(best) -> str:
        return f"{best.cost:.4g}" if best is not None and best.feasible else "—"

    def __call__(self, i: int, ev, best) -> None:
        self.count = i + 1
        self.feasible += bool(ev.feasible)
        if self.mode == "none":
            return
        now = time.perf_counter()
        if self.bar is not None:
            self.bar.update(self.task, advance=1, description=f"best {self._best(best)}")
        elif self.mode == "lines":
            state = f"cost {ev.cost:.4g}" if ev.feasible else f"failed at {ev.stage}"
            print(f"[{i + 1:4d}] {now - self.t0:7.1f}s  {ev.candidate.key():40s} {state:24s} best {self._best(best)}",
                  file=sys.stderr, flush=True)
        elif now - self.last >= self.every:
            self.last = now
            print(f"[{now - self.t0:7.1f}s] {self.count} evaluations, {self.feasible} feasible, best "
                  f"{self._best(best)}", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.stop()
            self.bar = None
