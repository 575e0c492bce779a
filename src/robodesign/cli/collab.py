"""The command line for collaborative tasks (docs/collaborative.md): ``robodesign check`` of a collaborative
solution and ``robodesign solve`` of a collaborative task. ``cli.py`` and ``commands.py`` hand over here
when the file they read is collaborative (a top-level ``"robots"`` list)."""
from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Dict, List, Optional

from robodesign.collab.core import (
    CollabTask,
    RobotSetup,
    check_collab,
    parse_collab_solution,
    parse_collab_task,
    solve_collab,
)
from robodesign.core.errors import InputError
from robodesign.core.jsonio import load_json


def _module_sets(csol, modules: Optional[str]) -> Dict[str, object]:
    """Each robot's module set: ``--modules`` for all, else the robot's own ``moduleSet`` (found locally)."""
    from robodesign.cli.args import module_set_for_solution
    return {rid: module_set_for_solution(s, modules) for rid, s in csol.robots}


def load_collab_task_file(name_or_path) -> Optional[CollabTask]:
    """The collaborative task in that file, or None when the file holds a single-robot task."""
    from robodesign.collab.core import is_collaborative
    from robodesign.formats.task_io import resolve_task_path
    f = resolve_task_path(name_or_path)
    data = load_json(f, display_name=f.name)
    return parse_collab_task(data, f) if is_collaborative(data) else None


def check_command(args, ctask: CollabTask) -> int:
    """``robodesign check TASK SOLUTION`` of a collaborative task."""
    from robodesign.cli.args import print_input_warnings
    print_input_warnings(ctask.task)
    csol = parse_collab_solution(load_json(args.solution, display_name=Path(args.solution).name),
                                 Path(args.solution).name, source=str(args.solution))
    verdict = check_collab(ctask, csol, _module_sets(csol, args.modules))
    if args.json:
        print(json.dumps(verdict.to_json()))
    else:
        print(f"task      {ctask.id} (collaborative: {', '.join(ctask.robot_ids)})")
        print(f"solution  {args.solution}")
        print(f"verdict   {'VALID' if verdict.valid else 'INVALID'}")
        if verdict.benchmark_id:
            print(f"benchmark {verdict.benchmark_id}")
        for rid, cost, cf in zip(ctask.robot_ids, verdict.costs, verdict.cost_functions):
            print(f"robot     {rid}: {cf} = " + ("—" if cost is None else f"{cost:.6g}"))
        if verdict.total_cost is not None:
            print(f"total     {verdict.total_cost:.6g}")
        print("goals     " + ", ".join(f"{g}: {r or 'MISSED'}" for g, r in verdict.goal_robot.items()))
        for who, v in verdict.violations:
            print(f"  - [{who or 'cell'}] {v}")
    return 0 if verdict.valid else 1


def parse_robot_orders(ctask: CollabTask, robots: List[str], order: Optional[str]) -> Dict[str, List[str]]:
    """``--robot ID=ORDER`` (repeatable) and ``--order`` (every robot not named) → robot ID → module order."""
    from robodesign.cli.args import parse_order
    out: Dict[str, List[str]] = {}
    for item in robots or []:
        rid, sep, o = item.partition("=")
        if not sep or not rid or not o:
            raise InputError(f"--robot: expected ID=ORDER (e.g. left=1,21,4,...), got {item!r}")
        if rid not in ctask.robot_ids:
            raise InputError(f"--robot: the task has no robot {rid!r} (robots: {', '.join(ctask.robot_ids)})")
        out[rid] = parse_order(o)
    for rid in ctask.robot_ids:
        if rid not in out:
            if order is None:
                raise InputError(f"robot {rid!r} has no module order: give --robot {rid}=ORDER or --order for all")
            out[rid] = parse_order(order)
    return out


def solve_command(args, ctask: CollabTask, mode: str, cost=None) -> int:
    """``robodesign solve`` of a collaborative task: prioritized planning (docs/collaborative.md). ``cost``:
    --cost as the CostFunction the caller parsed (default: parsed here)."""
    from robodesign.cli.args import print_input_warnings
    print_input_warnings(ctask.task)
    from robodesign.design.solve import SolveSettings
    from robodesign.formats.assembly import Assembly
    from robodesign.formats.module_io import load_module_set
    if args.base_pose:
        raise InputError("--base-pose is for one robot; a collaborative task places each robot by its "
                         "basePlacement")
    ms = load_module_set(args.modules)
    orders = parse_robot_orders(ctask, args.robot, args.order)
    for rid, o in orders.items():
        try:
            Assembly.from_order(ms, o)
        except InputError as e:
            raise InputError(f"--robot {rid}: {e}") from None
    settings = SolveSettings(planner=args.planner, plan_time=args.plan_time, timing=args.timing,
                             optimize_trajectory=mode == "optimize", seed=args.seed)
    t0 = time.perf_counter()
    if cost is None:
        from robodesign.formats.costs import parse_cost
        cost = parse_cost(args.cost, path="--cost")
    res = solve_collab(ctask, [RobotSetup(rid, ms, tuple(orders[rid])) for rid in ctask.robot_ids], cost=cost,
                       settings=settings)
    elapsed = time.perf_counter() - t0
    out = res.solution.write(args.out) if (res.solution is not None and args.out) else None
    if args.json:
        print(json.dumps({"feasible": res.feasible, "collaborative": True, "priority": list(res.priority),
                          "message": res.message, "goals": res.assignment,
                          "costs": list(res.verdict.costs) if res.verdict else None,
                          "totalCost": res.verdict.total_cost if res.verdict else None,
                          "solution": str(out) if out else None, "seconds": elapsed}))
    else:
        if res.feasible and res.verdict is not None:  # (feasible: a valid verdict)
            print(f"VALID solution of {ctask.id} (prioritized: {', '.join(res.priority)}; {elapsed:.2f} s)")
            for rid, c, cf in zip(ctask.robot_ids, res.verdict.costs, res.verdict.cost_functions):
                goals = [g for g, r in res.assignment.items() if r == rid]
                print(f"  {rid}: {cf} = {c:.6g}  goals {', '.join(goals)}")
        else:
            print(f"no valid solution: {res.message}")
        if out:
            print(f"solution written to {out}")
    return 0 if res.feasible else 1


def optimize_command(args, ctask: CollabTask) -> int:
    """``robodesign optimize`` of a collaborative task: every robot's design is searched on its part of the
    task (the budget applies per robot), then the best designs are combined by prioritized planning
    (:mod:`robodesign.collab.optimize`)."""
    from robodesign.cli.args import parse_options
    from robodesign.cli.workers import optimize_executor, optimize_workers, search_rules
    from robodesign.collab.optimize import optimize_collab
    from robodesign.design.optimize import Budget
    from robodesign.design.solve import SolveSettings, check_settings
    from robodesign.formats.costs import parse_cost
    from robodesign.formats.module_io import load_module_set
    settings = SolveSettings(planner=args.planner, plan_time=args.plan_time)
    check_settings(settings)  # cmd_optimize checked them already: a caller of this function gets the same rule
    cost = parse_cost(args.cost, path="--cost")  # once: the object travels to every study and combination
    if args.optimize_trajectory:
        raise InputError("--optimize-trajectory is not supported for a collaborative task yet")
    if getattr(args, "resume", False):
        raise InputError("--resume is not supported for a collaborative task yet (its search is not journaled)")
    budget = Budget.parse(args.budget)
    ms = load_module_set(args.modules)
    workers = optimize_workers(args.workers, args.batch_size, args.chunk_size, budget)  # budget: per robot

    def on_robot(rid, res):
        if not (args.json or getattr(args, "quiet", False)):
            feas = sum(e.feasible for e in res.history)
            print(f"robot {rid}: {len(res.history)} evaluations in {res.seconds:.1f} s ({workers} worker(s)), "
                  f"{feas} feasible alone")
    r = optimize_collab(ctask, ms, args.optimizer, cost, budget, seed=args.seed,
                        options=parse_options(args.opt), on_robot=on_robot, rules=search_rules(args),
                        base_search=not args.fixed_base, batch_size=args.batch_size, settings=settings,
                        executor_factory=lambda spec: optimize_executor(spec, workers, args.chunk_size))
    best = r.result if r.feasible else None  # the accepted combination: a valid verdict and its solution
    verdict, csol = (best.verdict, best.solution) if best is not None else (None, None)
    out = csol.write(args.out or "best_solution.json") if csol is not None else None
    if args.json:
        print(json.dumps({"feasible": r.feasible, "collaborative": True, "evaluations": r.evaluations,
                          "workers": workers, "batch_size": args.batch_size,
                          "combinations_tried": r.combinations_tried, "seconds": r.seconds,
                          "designs": {rid: [{"order": list(d.order), "cost_alone": d.cost} for d in ds]
                                      for rid, ds in r.designs.items()},
                          "costs": list(verdict.costs) if verdict is not None else None,
                          "totalCost": verdict.total_cost if verdict is not None else None,
                          "solution": str(out) if out else None, "notes": r.notes}))
    else:
        if best is not None and verdict is not None and csol is not None:
            print(f"VALID design of {ctask.id} after {r.combinations_tried} combination(s) ({r.seconds:.1f} s; "
                  f"prioritized: {', '.join(best.priority)})")
            for rid, c in zip(ctask.robot_ids, verdict.costs):
                s = csol.solution(rid)
                print(f"  {rid}: {','.join(s.module_order)}  {args.cost} = {c:.6g}")
            print(f"total cost   {verdict.total_cost:.6g}")
            print(f"solution     {out} (checked valid)")
        else:
            print("no valid design of the cell: " + ("; ".join(r.notes[-3:]) or "no combination was accepted"))
    return 0 if r.feasible else 1
