"""The shared evaluator: Candidate → Evaluation, through the staged solve pipeline.

A candidate's evaluation is a pure function of (candidate, task, module set, cost, settings, seed):
the per-candidate seed is derived from the study seed and the candidate key, so results do not
depend on evaluation order, executor or process. Results are cached per candidate key.

Score (smaller is better): a feasible candidate scores the checker's cost of its checked solution
(one judge). An infeasible one scores ``INFEASIBLE + (stages left)·STAGE_PENALTY − goals reached``,
so every feasible candidate beats every infeasible one, and among infeasible ones those that got
further (more stages, more goals) rank better — optimizers still learn from them.
"""
from __future__ import annotations

import hashlib
import time
from dataclasses import asdict, dataclass, field
from typing import Dict, List, Optional, Union


from .module_spec import ModuleSet
from .search_space import Candidate, SearchSpace
from .solve import STAGES, SolveSettings, solve
from .task_spec import Task

INFEASIBLE = 1e9
STAGE_PENALTY = 1e6


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

    def to_json(self) -> dict:
        d = asdict(self)
        d["candidate"] = self.candidate.to_json()
        return d

    @staticmethod
    def from_json(d: dict) -> "Evaluation":
        d = dict(d)
        c = d.pop("candidate")
        return Evaluation(candidate=Candidate(tuple(c["order"]), tuple(c["base"])), **d)


def score_of(feasible: bool, cost: Optional[float], stage_index: int, goals_reached: int) -> float:
    if feasible and cost is not None:
        return float(cost)
    return INFEASIBLE + (len(STAGES) - stage_index) * STAGE_PENALTY - goals_reached


def candidate_seed(study_seed: int, key: str) -> int:
    h = hashlib.sha256(f"{study_seed}|{key}".encode()).digest()
    return int.from_bytes(h[:4], "little")


def evaluation_settings(**overrides) -> SolveSettings:
    """Solve settings for optimizer evaluations: 150 IK restarts per goal (``solve`` uses 300). On PTP_3 with
    IMPROV this keeps every candidate that 1000 restarts find feasible at the IK stage while screening
    ≥ 200 candidates/s per core (docs/benchmarks.md)."""
    return SolveSettings(**{"ik_restarts": 150, **overrides})


@dataclass
class EvaluatorSpec:
    """Everything an evaluator needs, as plain data (picklable; heavy objects are rebuilt per process)."""
    task: Union[str, Task]
    module_set: Union[str, ModuleSet]
    cost: str = "cyc"
    settings: SolveSettings = field(default_factory=evaluation_settings)
    seed: int = 0
    keep_solutions: bool = True


class Evaluator:
    def __init__(self, spec: EvaluatorSpec):
        self.spec = spec
        self._task: Optional[Task] = None
        self._ms: Optional[ModuleSet] = None
        self.cache: Dict[str, Evaluation] = {}

    @property
    def task(self) -> Task:
        if self._task is None:
            from .task_io import load_task
            self._task = self.spec.task if isinstance(self.spec.task, Task) else load_task(self.spec.task)
        return self._task

    @property
    def module_set(self) -> ModuleSet:
        if self._ms is None:
            from .module_io import load_module_set
            ms = self.spec.module_set
            self._ms = ms if isinstance(ms, ModuleSet) else load_module_set(ms)
        return self._ms

    def search_space(self, **rules) -> SearchSpace:
        """The search space of this task and module set; base bounds from the task's base placement."""
        from .search_space import BaseBounds
        bb = BaseBounds.from_tolerance(self.task.base_placement)
        return SearchSpace(self.module_set, base_bounds=bb, **rules)

    def __call__(self, candidate: Candidate, base_bounds=None) -> Evaluation:
        key = candidate.key()
        hit = self.cache.get(key)
        if hit is not None:
            return hit
        ev = self.evaluate(candidate, base_bounds)
        self.cache[key] = ev
        return ev

    def evaluate(self, candidate: Candidate, base_bounds=None) -> Evaluation:
        t0 = time.perf_counter()
        seed = candidate_seed(self.spec.seed, candidate.key())
        task = self.task
        if base_bounds is None:
            from .search_space import BaseBounds
            base_bounds = BaseBounds.from_tolerance(task.base_placement)
        base = base_bounds.pose(candidate.base) if candidate.base else task.nominal_base_pose
        settings = SolveSettings(**{**asdict(self.spec.settings), "seed": seed})
        res = solve(task, self.module_set, list(candidate.order), base, cost=self.spec.cost, settings=settings)
        feasible = res.feasible
        cost = res.cost if feasible else None
        ev = Evaluation(candidate=candidate, feasible=feasible, cost=cost,
                        score=score_of(feasible, cost, res.stage_index, res.goals_reached), stage=res.stage,
                        stage_index=res.stage_index, goals_reached=res.goals_reached,
                        seconds=time.perf_counter() - t0, seed=seed, stages=[s.to_json() for s in res.stages],
                        message=res.message[:500],
                        solution=res.solution.to_json() if (feasible and self.spec.keep_solutions) else None,
                        costs=dict(res.verdict.costs) if res.verdict is not None else {})
        return ev
