"""Worker and search-space helpers shared by ``robodesign optimize`` of one robot (``cli.commands``) and of a
collaborative cell (``cli.collab``): how many worker processes, which executor, which search rules."""
from __future__ import annotations

import os
from typing import Dict, Optional

from robodesign.core.errors import InputError

#: without ``--workers``, a budget of fewer evaluations than this (and no time limit) runs in this process:
#: a worker pool's start-up (~0.7 s: spawn, import, load, warm up) costs more than it saves there (random
#: search on PTP_3/IMPROV, the whole command: 50 evaluations 2.3 s in the process against 2.8 s with 2
#: workers, 100: 2.7 / 3.3 s, 200: 4.4 / 4.2 s, 400: 5.4 / 4.7 s; docs/benchmarks.md)
POOL_MIN_EVALUATIONS = 200


def search_rules(args) -> Dict[str, int]:
    """The search-space rules of ``--dof`` and ``--max-links``."""
    rules = {}
    if args.dof:
        lo, _, hi = args.dof.partition("-")
        rules["min_dof"], rules["max_dof"] = int(lo), int(hi or lo)
    if args.max_links is not None:
        rules["max_links_between"] = args.max_links
    return rules


def optimize_workers(workers, batch_size: int, chunk_size: Optional[int] = None, budget=None) -> int:
    """``--workers`` (default: every core this process may use, or 1 for an evaluations-only ``budget`` below
    :data:`POOL_MIN_EVALUATIONS`), at most one per candidate of a batch; ``--batch-size`` and
    ``--chunk-size`` are checked on the way."""
    if batch_size < 1:
        raise InputError(f"--batch-size must be at least 1, got {batch_size}")
    if chunk_size is not None and chunk_size < 1:
        raise InputError(f"--chunk-size must be at least 1, got {chunk_size}")
    if workers is None:
        if short_budget(budget):
            return 1
        try:
            workers = len(os.sched_getaffinity(0))
        except AttributeError:
            workers = os.cpu_count() or 1
    elif workers < 1:
        raise InputError(f"--workers must be at least 1, got {workers}")
    return max(1, min(int(workers), batch_size))


def short_budget(budget) -> bool:
    """Whether ``budget`` (a :class:`~robodesign.design.optimize.Budget`) is too short for a worker pool to pay off."""
    return budget is not None and budget.seconds is None and budget.evaluations is not None \
        and budget.evaluations < POOL_MIN_EVALUATIONS


def optimize_executor(spec, workers: int, chunk_size: Optional[int] = None):
    """The executor of ``robodesign optimize`` and a function that closes it: in this process for one worker,
    else the experiments' process pool (results are the same for any number of workers). The close function
    takes ``now=True`` after an interrupt (the workers are terminated rather than waited for)."""
    from robodesign.design.evaluator import Evaluator
    from robodesign.design.optimize import SerialExecutor
    if workers == 1:
        return SerialExecutor(Evaluator(spec)), lambda now=False: None
    from robodesign.experiment.executors import ProcessPool
    pool = ProcessPool({"optimize": spec}, workers, chunk_size)
    return pool.bind("optimize"), pool.close
