"""Designing the robots of a collaborative cell (``robodesign optimize`` on a collaborative task).

The search decomposes by robot: every robot's design (module order, base pose within its placement) is
optimized by the chosen optimizer plugin on its own part of the task (its goals, its base placement,
the shared obstacles) with the same budget each; the ``top_k`` best checked designs of each robot are then
combined, in order of increasing summed cost, by prioritized planning (:func:`robodesign.collab.core.solve_collab`)
until the collaborative checker accepts a combination. The robots' coupling (waiting for each other) is
therefore resolved only among those combinations: a pair of designs that is good alone but blocks the
other robot is skipped for the next pair. docs/collaborative.md.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Tuple, Union

import numpy as np

from robodesign.collab.core import CollabSolveResult, CollabTask, RobotSetup, assign_goals, solve_collab
from robodesign.formats.costs import CostFunction, parse_cost
from robodesign.formats.module_spec import ModuleSet


@dataclass
class RobotDesign:
    order: Tuple[str, ...]
    base_pose: np.ndarray
    cost: float  # the robot's checked cost on its own part of the task


@dataclass
class CollabOptimizeResult:
    result: Optional[CollabSolveResult]  # the accepted combination (None: none was accepted)
    designs: Dict[str, List[RobotDesign]]  # per robot, its best designs alone (best first)
    evaluations: Dict[str, int]
    combinations_tried: int = 0
    seconds: float = 0.0
    notes: List[str] = field(default_factory=list)

    @property
    def feasible(self) -> bool:
        return self.result is not None and self.result.feasible


def optimize_collab(ctask: CollabTask, module_set: ModuleSet, optimizer: str, cost: Union[CostFunction, str], budget,
                    seed: int = 0,
                    options: Optional[dict] = None, top_k: int = 3, settings=None,
                    on_robot: Optional[Callable[[str, object], None]] = None, rules: Optional[dict] = None,
                    base_search: bool = True, batch_size: int = 1,
                    executor_factory: Optional[Callable] = None) -> CollabOptimizeResult:
    """Optimize every robot's design on its part of ``ctask`` (``budget``: an ``optimize.Budget``, per robot),
    then combine the ``top_k`` designs per robot by prioritized planning (best summed cost first). ``cost``: a
    CostFunction, or a descriptor parsed here once; the object reaches every study and combination. ``rules``
    and ``base_search`` define every robot's search space as for :meth:`robodesign.design.problem.Problem.build`.
    Each robot's study asks ``batch_size`` candidates at a time and evaluates them with the executor that
    ``executor_factory(spec)`` returns with its close function (default: in this process), e.g.
    :func:`robodesign.cli.commands.optimize_executor` for ``--workers``; the result does not depend on it.
    ``settings`` (a ``SolveSettings``) solves the combinations; its planner, plan time and timing method are
    also those of every robot's evaluations (which keep the evaluator's own IK restarts)."""
    import time

    from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
    from robodesign.design.optimize import SerialExecutor, Study, create_optimizer
    from robodesign.design.problem import Problem
    t0 = time.perf_counter()
    cost = cost if isinstance(cost, CostFunction) else parse_cost(cost, path="cost")
    planning = {} if settings is None else {"planner": settings.planner, "plan_time": settings.plan_time,
                                            "timing": settings.timing}
    nominal = [RobotSetup(rid, module_set, ()) for rid in ctask.robot_ids]
    assignment = assign_goals(ctask, nominal)
    designs: Dict[str, List[RobotDesign]] = {}
    evaluations: Dict[str, int] = {}
    for k, rid in enumerate(ctask.robot_ids):
        part = ctask.task_for(rid, [g for g, r in assignment.items() if r == rid])
        problem = Problem.build(part, module_set, cost, rules=rules, base_search=base_search)
        spec = EvaluatorSpec(problem, evaluation_settings(**planning), seed=seed + k)
        opt = create_optimizer(optimizer, problem, seed=seed + k, options=dict(options or {}))
        executor, close = executor_factory(spec) if executor_factory else (SerialExecutor(Evaluator(spec)), None)
        try:
            res = Study(opt, executor, budget, batch_size=batch_size).run()
        finally:
            if close is not None:
                close()
        evaluations[rid] = len(res.history)
        best: Dict[Tuple[str, ...], RobotDesign] = {}
        costed = [(e.cost, e) for e in res.history if e.feasible and e.cost is not None]  # feasible: has a cost
        for c, e in sorted(costed, key=lambda ce: ce[0]):
            key = tuple(e.candidate.order)
            if key not in best:  # the best base pose of each module order
                best[key] = RobotDesign(key, problem.base_pose(e.candidate), float(c))
        designs[rid] = list(best.values())[:top_k]
        if on_robot is not None:
            on_robot(rid, res)
    out = CollabOptimizeResult(None, designs, evaluations)
    missing = [rid for rid in ctask.robot_ids if not designs[rid]]
    if missing:
        out.notes.append(f"no feasible design alone for robot(s) {', '.join(missing)} within the budget")
        out.seconds = time.perf_counter() - t0
        return out
    combos = sorted(itertools.product(*(designs[rid] for rid in ctask.robot_ids)), key=lambda c: sum(d.cost for d in c))
    for combo in combos:
        out.combinations_tried += 1
        setups = [RobotSetup(rid, module_set, d.order, d.base_pose) for rid, d in zip(ctask.robot_ids, combo)]
        r = solve_collab(ctask, setups, cost=cost, settings=settings)
        if r.feasible:
            out.result = r
            break
        out.notes.append(f"designs {[','.join(d.order) for d in combo]}: {r.message}")
    out.seconds = time.perf_counter() - t0
    return out
