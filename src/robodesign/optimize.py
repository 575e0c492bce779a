"""The optimizer plugin API and the study loop.

Writing an optimizer (docs/plugins.md): subclass :class:`Optimizer`, implement ``ask()`` (return the
next :class:`Candidate`, or ``None`` when the optimizer has nothing left to propose) and optionally
``tell(evaluation)``; register the class under the entry-point group ``robodesign.optimizers``.
The optimizer sees only the :class:`SearchSpace` and its own seeded ``self.rng``; the
:class:`Study` owns the loop, the budget, the evaluator, the executor and the storage.

Determinism: the study asks ``batch_size`` candidates, evaluates them (in parallel or not), and
tells the results *in ask order*; evaluations are pure functions of the candidate. The same seed
and batch size therefore give the same run on any executor, and a run can be resumed by replaying
stored evaluations.
"""
from __future__ import annotations

import re
import time
from abc import ABC, abstractmethod
from dataclasses import dataclass
from importlib import metadata
from typing import Callable, Dict, List, Optional, Sequence, Type

import numpy as np

from .errors import InputError
from .evaluator import Evaluation
from .search_space import Candidate, SearchSpace

ENTRY_POINT_GROUP = "robodesign.optimizers"


class Optimizer(ABC):
    """Base class of optimizer plugins. ``options`` come from the CLI/config (``--opt key=value``)."""

    name: str = ""
    description: str = ""

    def __init__(self, space: SearchSpace, seed: int = 0, **options):
        self.space = space
        self.seed = int(seed)
        self.rng = np.random.default_rng(self.seed)
        self.options = options
        self.history: List[Evaluation] = []
        self.best: Optional[Evaluation] = None

    @abstractmethod
    def ask(self) -> Optional[Candidate]:
        """The next candidate to evaluate, or None when exhausted."""

    def tell(self, evaluation: Evaluation) -> None:
        """Receive the evaluation of a candidate this optimizer asked for (in ask order)."""

    # called by the study; plugins normally do not override it
    def _observe(self, evaluation: Evaluation) -> None:
        self.history.append(evaluation)
        if self.best is None or evaluation.score < self.best.score:
            self.best = evaluation
        self.tell(evaluation)


def available_optimizers() -> Dict[str, metadata.EntryPoint]:
    """name → entry point of every installed optimizer plugin."""
    eps = metadata.entry_points()
    group = eps.select(group=ENTRY_POINT_GROUP) if hasattr(eps, "select") else eps.get(ENTRY_POINT_GROUP, [])
    return {ep.name: ep for ep in group}


def load_optimizer(name: str) -> Type[Optimizer]:
    eps = available_optimizers()
    if name not in eps:
        known = ", ".join(sorted(eps)) or "none installed"
        raise InputError(f"unknown optimizer {name!r} (installed: {known})")
    cls = eps[name].load()
    if not (isinstance(cls, type) and issubclass(cls, Optimizer)):
        raise InputError(f"entry point {name!r} ({eps[name].value}) is not an Optimizer subclass")
    return cls


@dataclass(frozen=True)
class Budget:
    evaluations: Optional[int] = None
    seconds: Optional[float] = None

    @staticmethod
    def parse(text: str) -> "Budget":
        """``500``, ``500evals``, ``60s``, ``10min``, ``2h`` or both joined with ``,``."""
        ev, sec = None, None
        for part in str(text).replace(" ", "").split(","):
            m = re.fullmatch(r"(\d+)(evals?|evaluations?)?", part)
            if m:
                ev = int(m.group(1))
                continue
            m = re.fullmatch(r"(\d+(?:\.\d+)?)(s|sec|m|min|h)", part)
            if m:
                f = {"s": 1, "sec": 1, "m": 60, "min": 60, "h": 3600}[m.group(2)]
                sec = float(m.group(1)) * f
                continue
            raise InputError(f"budget {text!r}: use e.g. 500evals, 60s, 10min or 500evals,60s")
        if ev is not None and ev < 1 or sec is not None and sec <= 0:
            raise InputError(f"budget {text!r} must be positive")
        return Budget(ev, sec)

    def exhausted(self, n: int, elapsed: float) -> bool:
        return (self.evaluations is not None and n >= self.evaluations) or \
            (self.seconds is not None and elapsed >= self.seconds)


class SerialExecutor:
    """Evaluates a batch in this process."""
    name = "serial"

    def __init__(self, evaluator: Callable[[Candidate], Evaluation]):
        self.evaluator = evaluator

    def map(self, candidates: Sequence[Candidate]) -> List[Evaluation]:
        return [self.evaluator(c) for c in candidates]

    def close(self) -> None:
        pass


@dataclass
class StudyResult:
    best: Optional[Evaluation]
    history: List[Evaluation]
    seconds: float
    stopped: str  # "budget" | "exhausted"

    @property
    def best_feasible(self) -> Optional[Evaluation]:
        return self.best if self.best is not None and self.best.feasible else None


class Study:
    """Owns the optimization loop: ask a batch → evaluate (executor) → store → tell, until the budget ends.

    ``storage`` (optional) has ``load() -> list[Evaluation]`` (stored evaluations in ask order, for
    resuming) and ``append(index, evaluation)``. ``on_evaluation(index, evaluation, best)`` is called
    after each evaluation (progress bars, anytime curves).
    """

    def __init__(self, optimizer: Optimizer, executor, budget: Budget, batch_size: int = 1, storage=None,
                 on_evaluation: Optional[Callable] = None):
        self.optimizer = optimizer
        self.executor = executor
        self.budget = budget
        self.batch_size = max(1, int(batch_size))
        self.storage = storage
        self.on_evaluation = on_evaluation

    def run(self) -> StudyResult:
        t0 = time.perf_counter()
        stored = self.storage.load() if self.storage is not None else []
        history: List[Evaluation] = []
        opt = self.optimizer
        stopped = "budget"
        while True:
            n = len(history)
            # the evaluation budget is exact; the time budget counts only evaluations made in this session
            if self.budget.evaluations is not None and n >= self.budget.evaluations:
                break
            if self.budget.seconds is not None and n >= len(stored) and time.perf_counter() - t0 >= self.budget.seconds:
                break
            size = self.batch_size
            if self.budget.evaluations is not None:
                size = min(size, self.budget.evaluations - n)
            batch: List[Candidate] = []
            for _ in range(size):
                c = opt.ask()
                if c is None:
                    break
                batch.append(c)
            if not batch:
                stopped = "exhausted"
                break
            results: List[Optional[Evaluation]] = [None] * len(batch)
            todo = []
            for i, c in enumerate(batch):
                idx = n + i
                if idx < len(stored):
                    if stored[idx].candidate.key() != c.key():
                        raise InputError(f"cannot resume: evaluation {idx} was {stored[idx].candidate.key()!r} "
                                         f"but the optimizer now asks {c.key()!r} (different settings or seed?)")
                    results[i] = stored[idx]
                else:
                    todo.append(i)
            if todo:
                fresh = self.executor.map([batch[i] for i in todo])
                for i, ev in zip(todo, fresh):
                    results[i] = ev
                    if self.storage is not None:
                        self.storage.append(n + i, ev)
            for i, ev in enumerate(results):
                opt._observe(ev)
                history.append(ev)
                if self.on_evaluation is not None:
                    self.on_evaluation(n + i, ev, opt.best)
            if len(batch) < size:
                stopped = "exhausted"
                break
        return StudyResult(best=opt.best, history=history, seconds=time.perf_counter() - t0, stopped=stopped)
