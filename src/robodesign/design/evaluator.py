"""The shared evaluator: Candidate → Evaluation, through the staged solve pipeline.

A candidate's evaluation is a pure function of (candidate, problem, settings, seed), where the
:class:`~robodesign.design.problem.Problem` fixes the task, module set, cost and base-pose bounds: the
per-candidate seed is derived from the study seed and the candidate key, so results do not depend on
evaluation order, executor or process. The cache key covers all of them (:meth:`Evaluator.cache_key`).

Score (smaller is better): a feasible candidate scores the checker's cost of its checked solution
(one judge). An infeasible one scores ``INFEASIBLE + (stages left)·STAGE_PENALTY − goals reached +
graded shortfall``, so every feasible candidate beats every infeasible one, and among infeasible ones
those that got further (more stages, more goals) rank better — optimizers still learn from them. The
graded shortfall (:func:`graded_shortfall`, in [0, 1)) ranks candidates that failed at the same stage with
the same goals by how far they missed: metres beyond the reach bound at ``reach``, Nm over the torque
limit at ``static_torque`` (``Evaluation.shortfall``); it is 0 when the stage measures none, so such
scores are those of earlier releases.
"""
from __future__ import annotations

import hashlib
import json
import math
import time
from dataclasses import asdict, dataclass, field, fields, replace
from typing import Dict, List, Optional

from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.design.solve import STAGES, SolveSettings, solve
from robodesign.formats.module_spec import ModuleSet
from robodesign.formats.task_spec import Task

#: the rules that make an evaluation of (candidate, problem, settings, seed), numbered: a change of robodesign that
#: gives other evaluations for the same inputs takes the next number, and a stored run made under other rules is
#: not resumed (experiment/storage.py). 1: up to 2026-11-28; 2: each goal's IK draws from a random stream of its
#: own and every goal's first solution comes before any goal's others (design/goal_planner.py)
EVALUATION_RULES = 2

INFEASIBLE = 1e9
STAGE_PENALTY = 1e6
#: the shortfall at which the graded penalty is 1/2, per stage and unit: 0.1 m beyond the reach bound,
#: 10 Nm over the torque limit
SHORTFALL_SCALE = {"reach": 0.1, "static_torque": 10.0}


@dataclass
class Evaluation:
    candidate: Candidate
    feasible: bool
    cost: Optional[float]
    score: float
    stage: str  # first failed stage or "done"
    stage_index: int
    goals_reached: int
    seconds: float
    seed: int
    stages: List[dict] = field(default_factory=list)
    message: str = ""
    solution: Optional[dict] = None  # CoBRA JSON of the checked solution (feasible candidates)
    costs: Dict[str, float] = field(default_factory=dict)  # every built-in cost of the checked solution
    # how far the failed stage missed (metres beyond the reach bound at "reach", Nm over the torque limit at
    # "static_torque"); None when it passed or the stage measures none
    shortfall: Optional[float] = None

    def to_json(self) -> dict:
        d = asdict(self)
        d["candidate"] = self.candidate.to_json()
        return d

    @staticmethod
    def from_json(d: dict) -> "Evaluation":
        d = dict(d)
        c = d.pop("candidate")
        return Evaluation(candidate=Candidate(tuple(c["order"]), tuple(c["base"])), **d)


def graded_shortfall(stage: str, shortfall: Optional[float]) -> float:
    """The graded penalty of an infeasible candidate, in [0, 1): s / (s + scale) for a shortfall s in the
    stage's unit (:data:`SHORTFALL_SCALE`), 0 without one. Increasing in s, so a candidate that misses by
    less ranks better, and below 1, so it never outweighs a goal reached or a stage passed."""
    scale = SHORTFALL_SCALE.get(stage)
    if scale is None or shortfall is None or not shortfall > 0:
        return 0.0
    if not math.isfinite(shortfall):
        return 1.0 - 1e-6
    return min(float(shortfall) / (float(shortfall) + scale), 1.0 - 1e-6)


def score_of(feasible: bool, cost: Optional[float], stage_index: int, goals_reached: int,
             shortfall: Optional[float] = None) -> float:
    if feasible and cost is not None:
        return float(cost)
    stage = STAGES[stage_index] if stage_index < len(STAGES) else "done"
    return INFEASIBLE + (len(STAGES) - stage_index) * STAGE_PENALTY - goals_reached + \
        graded_shortfall(stage, shortfall)


def candidate_seed(study_seed: int, key: str) -> int:
    h = hashlib.sha256(f"{study_seed}|{key}".encode()).digest()
    return int.from_bytes(h[:4], "little")


_SETTINGS_FIELDS = frozenset(f.name for f in fields(SolveSettings))


def with_seed(settings: SolveSettings, seed: int) -> SolveSettings:
    """``dataclasses.replace(settings, seed=seed)``: a SolveSettings is a plain dataclass (every field an argument of
    ``__init__``, stored as given; no ``__post_init__``), so a copy of its fields with the seed set is the object
    ``replace`` makes (in a tenth of its time). Anything else (a subclass, extra attributes) goes through ``replace``."""
    if type(settings) is not SolveSettings or settings.__dict__.keys() != _SETTINGS_FIELDS:
        return replace(settings, seed=seed)
    copy = object.__new__(SolveSettings)
    copy.__dict__.update(settings.__dict__)
    copy.seed = seed
    return copy


def evaluation_settings(**overrides) -> SolveSettings:
    """Solve settings for optimizer evaluations: 150 IK restarts per goal (``solve`` uses 300). On PTP_3 with
    IMPROV this keeps every candidate that 1000 restarts find feasible at the IK stage while screening
    ≥ 200 candidates/s per core (docs/benchmarks.md). Every restart runs (``ik_saturate`` = 0): stopping a goal's
    restarts when its solutions stop growing halves a feasible candidate's IK stage but gave slightly worse best
    designs per search (docs/benchmarks.md, "IK restarts that stop when a goal's solutions stop growing")."""
    return SolveSettings(**{"ik_restarts": 150, **overrides})


@dataclass(frozen=True)
class EvaluatorSpec:
    """Everything an evaluator needs, as plain data (picklable: a problem built from files travels as
    their references and is reloaded once per process)."""
    problem: Problem
    settings: SolveSettings = field(default_factory=evaluation_settings)
    seed: int = 0
    keep_solutions: bool = True

    def fingerprint(self) -> str:
        """A hash of everything besides the candidate that changes an evaluation: the problem (task, module
        set, cost, base bounds), the solve settings and the study seed."""
        d = {"problem": self.problem.fingerprint(), "settings": asdict(self.settings), "seed": int(self.seed),
             "solution": bool(self.keep_solutions)}
        return hashlib.sha256(json.dumps(d, sort_keys=True, default=str).encode()).hexdigest()[:16]


class Evaluator:
    """Candidate → Evaluation for one :class:`EvaluatorSpec`. ``cache`` (a dict, may be shared between
    evaluators) maps :meth:`cache_key` → Evaluation."""

    def __init__(self, spec: EvaluatorSpec, cache: Optional[Dict[str, Evaluation]] = None):
        self.spec = spec
        self.problem = spec.problem
        self.cache: Dict[str, Evaluation] = {} if cache is None else cache
        self._context = spec.fingerprint()

    @property
    def task(self) -> Task:
        return self.problem.task

    @property
    def module_set(self) -> ModuleSet:
        return self.problem.module_set

    def cache_key(self, candidate: Candidate) -> str:
        """The candidate's key under this evaluator's problem, settings and seed."""
        return f"{self._context}|{candidate.key()}"

    def __call__(self, candidate: Candidate) -> Evaluation:
        key = self.cache_key(candidate)
        hit = self.cache.get(key)
        if hit is not None:
            return hit
        ev = self.evaluate(candidate)
        self.cache[key] = ev
        return ev

    def evaluate(self, candidate: Candidate) -> Evaluation:
        t0 = time.perf_counter()
        seed = candidate_seed(self.spec.seed, candidate.key())
        problem = self.problem
        settings = with_seed(self.spec.settings, seed)
        res = solve(problem.task, problem.module_set, list(candidate.order), problem.base_pose(candidate),
                    cost=problem.cost, settings=settings)
        feasible = res.feasible
        cost = res.cost if feasible else None
        ev = Evaluation(candidate=candidate, feasible=feasible, cost=cost,
                        score=score_of(feasible, cost, res.stage_index, res.goals_reached, res.shortfall),
                        stage=res.stage,
                        stage_index=res.stage_index, goals_reached=res.goals_reached,
                        seconds=time.perf_counter() - t0, seed=seed, stages=[s.to_json() for s in res.stages],
                        message=res.message[:500],
                        solution=res.solution.to_json()
                        if (feasible and self.spec.keep_solutions and res.solution is not None) else None,
                        costs=dict(res.verdict.costs) if res.verdict is not None else {},
                        shortfall=None if feasible else res.shortfall)
        return ev
