"""Base-pose search for one fixed module order: how much does moving the base save for *this* robot?

The module order is given (``--opt order=1,21,4,22,5,23,12``); the free base parameters of the search space
(x, y, z, yaw inside the task's base-placement tolerance) are searched with optuna's TPE sampler. The first
candidate is the nominal base (``space.nominal_candidate``), so the result is never worse than the design
as it stands. Samples outside the tolerance (e.g. the corners of a round tolerance) are told a huge value
and drawn again; they are not evaluated.

Typical use, after a search over the modules: refine the base of the best design(s)::

    robodesign optimize robodesign/base_placement --modules robodesign_arm --dof 7 \\
        --optimizer base_pose --opt order=2,5,21,22,21,11,22,4,21,5,22,14 --budget 80evals

Options (``--opt key=value``; ``robodesign optimizers --verbose`` lists them): ``order`` (required),
``n_startup_trials``, ``max_rejects``.

Deterministic for a seed.
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Deque, Dict, Optional, Tuple

import optuna

from robodesign.plugin import BASE_PARAMS, Candidate, Optimizer, option

_OUTSIDE = 1e300


class BasePoseSearch(Optimizer):
    name = "base_pose"
    description = "the base pose alone for a fixed module order (--opt order=...), TPE from the nominal base"

    @dataclass(frozen=True)
    class Options:
        order: Tuple[str, ...] = option(help="the module order, comma-separated (valid under the space's rules)")
        n_startup_trials: int = option(8, low=0, help="TPE: random trials before the model is used")
        max_rejects: int = option(1000, low=1, help="samples outside the tolerance in a row before ask gives up")

    def __init__(self, problem, seed: int = 0, **options):
        super().__init__(problem, seed, **options)
        space = self.space
        why = space.validate_order(self.options.order)
        if why:
            raise ValueError(f"base_pose: order {','.join(self.options.order)}: {why} "
                             f"(set the search-space rules, e.g. --dof, so that they admit it)")
        self.free = tuple(space.base_bounds.free)
        if not self.free:
            raise ValueError("base_pose: the base pose is fixed (the task's base placement has no tolerance, "
                             "or --fixed-base was given): nothing to search")
        optuna.logging.set_verbosity(optuna.logging.WARNING)
        sampler = optuna.samplers.TPESampler(seed=self.seed, n_startup_trials=self.options.n_startup_trials,
                                             multivariate=True)
        self.study = optuna.create_study(direction="minimize", sampler=sampler)
        nominal = space.nominal_candidate(self.options.order)
        self.study.enqueue_trial({self._param(i): float(v) for i, v in zip(self.free, nominal.base)})
        self._pending: Deque[Tuple[optuna.trial.Trial, str]] = deque()  # (trial, key) asked, not yet told, in order
        self._scores: Dict[str, float] = {}   # key → score told (a resampled duplicate gets the same)

    @staticmethod
    def _param(i: int) -> str:
        return f"base_{BASE_PARAMS[i]}"

    def ask(self) -> Optional[Candidate]:
        bb = self.space.base_bounds
        for _ in range(self.options.max_rejects):
            trial = self.study.ask()
            base = tuple(float(trial.suggest_float(self._param(i), bb.lower[i], bb.upper[i])) for i in self.free)
            c = Candidate(self.options.order, base)
            key = c.key()
            if not bb.valid(base):
                self.study.tell(trial, _OUTSIDE)
                continue
            if key in self._scores or any(k == key for _, k in self._pending):
                self.study.tell(trial, self._scores.get(key, _OUTSIDE))
                continue
            self._pending.append((trial, key))
            return c
        return None

    def tell(self, evaluation) -> None:
        trial, key = self._pending.popleft()
        self._scores[key] = evaluation.score
        self.study.tell(trial, evaluation.score)
