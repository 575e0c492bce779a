"""Optuna samplers through optuna's ask/tell interface (an in-memory study, seeded sampler).

* ``multi_objective=False`` (default): TPE (``TPESampler(multivariate=True, group=True)``, which
  models conditional search spaces), one objective: the evaluation's ``score`` (the cost of a
  feasible design; infeasible designs get the evaluator's large score, which still orders them by
  the stage they reached and the goals they reached).
* ``multi_objective=True``: NSGA-II (``NSGAIISampler``), objectives from ``objectives`` (default
  ``"score,mass"``: the score and the robot mass). Available objectives: ``score``, ``mass`` (sum of
  the module masses, the checker's ``mass`` cost), ``modules`` (number of modules), ``dof``. All are
  minimised. Infeasibility is a constraint (``trial.set_constraint("infeasibility", v)``, optuna 5's
replacement of ``constraints_func``): v is 0 for a feasible
  design and (stages not passed + 1/(1 + goals reached)) > 0 otherwise, so NSGA-II prefers feasible
  designs and, among infeasible ones, those that got further. ``self.best`` (the study's best) is still
  the best score; the Pareto front is ``self.study.best_trials``.

Encoding (a conditional, define-by-run search space): the order is a sequence of categorical choices
along ``space.successors``: position i chooses among the successors of the prefix chosen so far that
still have a valid completion (``count_completions > 0``), until an end effector is chosen. Optuna
requires the same choices for a parameter name (``suggest_categorical`` registers one
``CategoricalDistribution`` per name), so the parameter of position i is named ``m{i}`` for
the first set of choices seen at that position and ``m{i}.{k}`` for the k-th different set (the names
are deterministic). Free base parameters are floats ``base_x``, ``base_y``, ``base_z``, ``base_yaw``
within their bounds.

Duplicates: a sampled candidate that was evaluated before is not asked again; its trial is told the
stored values at once (counts as a trial, not as an evaluation) and the sampler is asked again — up to
``max_duplicates`` times, after which a random unseen candidate is enqueued (``enqueue_trial``) so that
the sampler learns from it too. When no unseen candidate can be found, ``ask`` returns None.

Options (``--opt key=value``; ``robodesign optimizers --verbose`` lists them): ``multi_objective``,
``objectives``, ``n_startup_trials``, ``population_size``, ``max_duplicates``.

Deterministic for a seed (the sampler is seeded with the optimizer's seed); optuna's logging is set to
WARNING and its experimental-feature warnings are silenced.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Dict, List, Optional, Sequence, Tuple

import optuna
from optuna.trial import TrialState

from robodesign.plugin import BASE_PARAMS, STAGES, Candidate, Optimizer, option

OBJECTIVES = ("score", "mass", "modules", "dof")


class OptunaOptimizer(Optimizer):
    name = "optuna"
    description = "optuna TPE (single objective) or NSGA-II (multi_objective=True) via ask/tell"

    @dataclass(frozen=True)
    class Options:
        multi_objective: bool = option(False, help="NSGA-II with `objectives` instead of single-objective TPE")
        objectives: Tuple[str, ...] = option(("score", "mass"), help="NSGA-II objectives, comma-separated, at "
                                             "least 2 of " + ", ".join(OBJECTIVES))
        n_startup_trials: int = option(10, low=0, help="TPE: random trials before the model is used")
        population_size: int = option(20, low=2, help="NSGA-II population size")
        max_duplicates: int = option(10, low=1, help="resamples of evaluated candidates before a random one is "
                                                     "enqueued")

    def __init__(self, problem, seed: int = 0, **options):
        super().__init__(problem, seed, **options)
        o = self.options
        if o.multi_objective:
            bad = [x for x in o.objectives if x not in OBJECTIVES]
            if bad or len(o.objectives) < 2:
                raise ValueError(f"optuna: objectives must be ≥ 2 of {', '.join(OBJECTIVES)}, "
                                 f"got {','.join(o.objectives)!r}")
        optuna.logging.set_verbosity(optuna.logging.WARNING)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
            sampler: optuna.samplers.BaseSampler
            if o.multi_objective:
                sampler = optuna.samplers.NSGAIISampler(population_size=o.population_size, seed=self.seed)
                self.study = optuna.create_study(directions=["minimize"] * len(o.objectives), sampler=sampler)
            else:
                sampler = optuna.samplers.TPESampler(seed=self.seed, n_startup_trials=o.n_startup_trials,
                                                     multivariate=True, group=True)
                self.study = optuna.create_study(direction="minimize", sampler=sampler)
        self._names: Dict[int, List[Tuple[str, ...]]] = {}   # position → choice sets seen (in order)
        self._pending: Dict[str, optuna.trial.Trial] = {}      # key → trial asked, not yet told
        self._values: Dict[str, Tuple[List[float], float]] = {}  # key → (objective values, constraint)
        self._free = tuple(self.space.base_bounds.free)
        self._completable: Dict[Tuple[str, ...], bool] = {}
        self._exhausted = False

    # -- encoding ----------------------------------------------------------------------------------------
    def param_name(self, position: int, choices: Sequence[str]) -> str:
        """The parameter name of ``position`` with these choices (``m{i}``, or ``m{i}.{k}`` for the k-th
        other choice set seen at that position)."""
        seen = self._names.setdefault(position, [])
        t = tuple(choices)
        if t not in seen:
            seen.append(t)
        k = seen.index(t)
        return f"m{position}" if k == 0 else f"m{position}.{k}"

    def _choices(self, prefix: Tuple[str, ...]) -> List[str]:
        out = []
        for m in self.space.successors(prefix):
            p = prefix + (m,)
            ok = self._completable.get(p)
            if ok is None:
                ok = self._completable[p] = self.space.count_completions(p) > 0
            if ok:
                out.append(m)
        return out

    def _walk(self, trial) -> Candidate:
        """Sample (or replay enqueued) parameters of ``trial`` into a candidate."""
        order: Tuple[str, ...] = ()
        while True:
            choices = self._choices(order)
            if not choices:
                break
            name = self.param_name(len(order), choices)
            m = trial.suggest_categorical(name, choices)
            order += (m,)
            if self.space.module_info(m).kind == "eef":
                break
        bb = self.space.base_bounds
        base = tuple(float(trial.suggest_float(f"base_{BASE_PARAMS[i]}", bb.lower[i], bb.upper[i]))
                     for i in self._free)
        return Candidate(order, base)

    def _params_of(self, c: Candidate) -> Dict[str, object]:
        params: Dict[str, object] = {}
        for i, m in enumerate(c.order):
            params[self.param_name(i, self._choices(tuple(c.order[:i])))] = m
        for i, v in zip(self._free, c.base):
            params[f"base_{BASE_PARAMS[i]}"] = float(v)
        return params

    # -- ask / tell ----------------------------------------------------------------------------------------
    def _tell_known(self, trial, key: str) -> None:
        values, constraint = self._values[key]
        if self.options.multi_objective:
            trial.set_constraint("infeasibility", constraint)
        self.study.tell(trial, values if self.options.multi_objective else values[0])

    def ask(self) -> Optional[Candidate]:
        if self._exhausted:
            return None
        for _ in range(self.options.max_duplicates):
            trial = self.study.ask()
            c = self._walk(trial)
            k = c.key()
            if k in self._values:          # evaluated before: tell the stored values, sample again
                self._tell_known(trial, k)
                continue
            if k in self._pending or self.space.validate_order(c.order) is not None:
                self.study.tell(trial, state=TrialState.FAIL)
                continue
            self._pending[k] = trial
            return c
        # the sampler keeps proposing known designs: enqueue a random unseen one
        for _ in range(200):
            c = self.space.random_candidate(self.rng)
            k = c.key()
            if k in self._values or k in self._pending:
                continue
            self.study.enqueue_trial(self._params_of(c))
            trial = self.study.ask()
            c2 = self._walk(trial)
            if c2.key() != k:  # should not happen; never ask a candidate twice
                self.study.tell(trial, state=TrialState.FAIL)
                continue
            self._pending[k] = trial
            return c2
        self._exhausted = True
        return None

    def _objective_values(self, ev) -> Tuple[List[float], float]:
        c = ev.candidate
        vals = []
        for o in (self.options.objectives if self.options.multi_objective else ("score",)):
            if o == "score":
                vals.append(float(ev.score))
            elif o == "mass":
                vals.append(float(sum(self.space.module_info(m).mass for m in c.order)))
            elif o == "modules":
                vals.append(float(len(c.order)))
            else:
                vals.append(float(sum(self.space.module_info(m).dof for m in c.order)))
        constraint = 0.0 if ev.feasible else float(len(STAGES) - ev.stage_index) + 1.0 / (1.0 + ev.goals_reached)
        return vals, constraint

    def tell(self, evaluation) -> None:
        k = evaluation.candidate.key()
        self._values[k] = self._objective_values(evaluation)
        trial = self._pending.pop(k, None)
        if trial is not None:
            self._tell_known(trial, k)
