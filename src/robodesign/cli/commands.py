"""Implementations of the ``solve``, ``optimize`` and ``optimizers`` CLI commands."""
from __future__ import annotations

import json
import sys
import time
from typing import Dict, List, Optional

import numpy as np

from robodesign.core.errors import InputError


def _base_pose(text, task):
    from robodesign.cli.args import parse_base_pose
    return parse_base_pose(text) if text else task.nominal_base_pose


TRAJECTORY_CHOICES = ("auto", "time-optimal", "optimize")


def add_trajectory_arguments(p) -> None:
    p.add_argument("--trajectory", choices=TRAJECTORY_CHOICES, default="auto",
                   help="how each move is timed: time-optimal (TOPP-RA/ruckig), optimize (then refined with "
                        "CasADi/ipopt for the cost), or auto: optimize when the cost has an energy-like term "
                        "(mechEnergy, effort, Liu2, ...), else time-optimal (default: auto)")
    p.add_argument("--optimize-trajectory", action="store_true", help="the same as --trajectory optimize")


def trajectory_mode(cost: str, choice: str = "auto", optimize_flag: bool = False) -> str:
    """"time-optimal" or "optimize" for a cost and the --trajectory / --optimize-trajectory options."""
    from robodesign.formats.costs import cost_term, parse_cost
    if optimize_flag:
        if choice == "time-optimal":
            raise InputError("--optimize-trajectory contradicts --trajectory time-optimal")
        return "optimize"
    if choice != "auto":
        return choice
    # optimize for the terms trajectory optimization lowers beyond the time-optimal profile: the modelled
    # torque integrals (mechEnergy, effort)
    weights = parse_cost(cost, path="--cost").terms
    energy_like = [n for n, w in weights if w > 0 and cost_term(n).trajopt and cost_term(n).needs_torques]
    return "optimize" if energy_like else "time-optimal"


def cmd_solve(args) -> int:
    from robodesign.cli.args import parse_order, print_input_warnings
    from robodesign.cli.collab import load_collab_task_file, solve_command
    from robodesign.design.solve import SolveSettings, solve
    from robodesign.formats.assembly import Assembly
    from robodesign.formats.module_io import load_module_set
    from robodesign.formats.task_io import load_task
    from robodesign.solvers.planning import available_planners
    mode = trajectory_mode(args.cost, args.trajectory, args.optimize_trajectory)
    if args.planner.lower() not in [p.lower() for p in available_planners()]:
        raise InputError(f"--planner: unknown planner {args.planner!r} (available: {', '.join(available_planners())})")
    if args.plan_time <= 0:
        raise InputError("--plan-time must be positive")
    ctask = load_collab_task_file(args.task)
    if ctask is not None:  # several robots in one cell: docs/collaborative.md
        return solve_command(args, ctask, mode)
    if args.robot:
        raise InputError("--robot is for a collaborative task; this task has one robot: use --order")
    if not args.order:
        raise InputError("--order is required (comma-separated module IDs, base first)")
    task = load_task(args.task)
    ms = load_module_set(args.modules)
    print_input_warnings(task, ms)
    order = parse_order(args.order)
    try:
        Assembly.from_order(ms, order)  # an order that cannot be assembled is bad input, as in `robodesign robot`
    except InputError as e:
        raise InputError(f"--order: {e}") from None
    settings = SolveSettings(planner=args.planner, plan_time=args.plan_time, timing=args.timing,
                             optimize_trajectory=mode == "optimize", seed=args.seed)
    t0 = time.perf_counter()
    res = solve(task, ms, order, _base_pose(args.base_pose, task), cost=args.cost, settings=settings)
    elapsed = time.perf_counter() - t0
    out = None
    if res.solution is not None and args.out:
        out = res.solution.write(args.out)
    if args.json:
        print(json.dumps({"feasible": res.feasible, "stage": res.stage, "message": res.message, "trajectory": mode,
                          "stages": [s.to_json() for s in res.stages], "cost": res.cost,
                          "costs": res.verdict.costs if res.verdict else {},
                          "goals_achieved": res.goals_achieved, "num_goals": res.num_goals,
                          "goals_missed": res.goals_missed,
                          "solution": str(out) if out else None, "seconds": elapsed}))
    else:
        for s in res.stages:
            print(f"  {s.name:14s} {'ok ' if s.passed else 'FAIL'} {s.seconds * 1e3:8.1f} ms  {s.message[:150]}")
        how = ("time-optimal (TOPP-RA)" if args.timing == "toppra" else "time-optimal (ruckig)") \
            if mode == "time-optimal" else f"optimized for {args.cost} (CasADi/ipopt)"
        chosen = " (--trajectory auto, from the cost)" if args.trajectory == "auto" and not args.optimize_trajectory \
            else ""
        print(f"trajectory   {how}{chosen}")
        if res.feasible:
            print(f"VALID solution of {task.id}: {res.verdict.cost_function} = {res.cost:.6g}  ({elapsed:.2f} s)")
            print("costs  " + ", ".join(f"{k}={v:.6g}" for k, v in res.verdict.costs.items()))
            print(f"goals  {res.goals_achieved} of {res.num_goals} achieved"
                  + (f" (missed: {', '.join(res.goals_missed)}; the task does not require every goal)"
                     if res.goals_missed else ""))
        else:
            print(f"no valid solution: stage '{res.stage}' failed: {res.message}")
        if out:
            print(f"solution written to {out}")
    return 0 if res.feasible else 1


def cmd_optimizers(args) -> int:
    from dataclasses import asdict

    from robodesign.design.optimize import available_optimizers, option_specs
    eps = available_optimizers()
    plugins = {}
    for name, ep in sorted(eps.items()):
        try:  # a broken third-party plugin must not break the listing
            cls = ep.load()
            desc = getattr(cls, "description", "") or (cls.__doc__ or "").strip().splitlines()[0]
            opts = option_specs(cls)
        except Exception as e:
            desc, opts = f"(cannot be loaded: {e})", []
        plugins[name] = (ep.value, desc, opts)
    if args.json:
        if getattr(args, "verbose", False):
            print(json.dumps({n: {"entry_point": v, "description": d, "options": [asdict(o) for o in opts]}
                              for n, (v, d, opts) in plugins.items()}))
        else:
            print(json.dumps({n: v for n, (v, _, _) in plugins.items()}))
        return 0
    if not plugins:
        print("no optimizer plugins installed (pip install -e ./optimizers)")
        return 0
    for name, (value, desc, opts) in plugins.items():
        print(f"{name:12s} {value:55s} {desc}")
        if getattr(args, "verbose", False):
            for o in opts:
                print(f"    --opt {o.describe()}")
            if not opts:
                print("    (no declared options)")
    return 0


def search_rules(args) -> Dict[str, int]:
    """The search-space rules of ``--dof`` and ``--max-links``."""
    rules = {}
    if args.dof:
        lo, _, hi = args.dof.partition("-")
        rules["min_dof"], rules["max_dof"] = int(lo), int(hi or lo)
    if args.max_links is not None:
        rules["max_links_between"] = args.max_links
    return rules


def cmd_optimize(args) -> int:
    from robodesign.cli.args import parse_options, print_input_warnings
    from robodesign.cli.collab import load_collab_task_file, optimize_command
    ctask = load_collab_task_file(args.task)
    if ctask is not None:  # several robots in one cell: docs/collaborative.md
        return optimize_command(args, ctask)
    from robodesign.design.evaluator import EvaluatorSpec, evaluation_settings
    from robodesign.design.optimize import Budget, Study, create_optimizer
    from robodesign.design.problem import Problem
    from robodesign.formats.costs import parse_cost
    budget = Budget.parse(args.budget)
    rules = search_rules(args)
    problem = Problem.build(args.task, args.modules, parse_cost(args.cost, path="--cost"), rules=rules,
                            base_search=not args.fixed_base)
    print_input_warnings(problem.task)
    spec = EvaluatorSpec(problem, evaluation_settings(planner=args.planner, optimize_trajectory=args.optimize_trajectory),
                         seed=args.seed)
    opt = create_optimizer(args.optimizer, problem, seed=args.seed, options=parse_options(args.opt))
    workers = optimize_workers(args.workers, args.batch_size, args.chunk_size, budget)
    if args.workers is None and short_budget(budget) and not args.json:
        print(f"evaluating in this process: {budget.evaluations} evaluations are fewer than a worker pool's "
              f"start-up pays for ({POOL_MIN_EVALUATIONS}); --workers N uses N processes")
    clock_start = time.perf_counter()  # a time budget counts from here: the worker pool's start-up is spent from it
    executor, close_executor = optimize_executor(spec, workers, args.chunk_size)
    progress = _Progress(budget, quiet=args.json)
    walls: List[float] = []  # wall time of each evaluation since the study started

    def on_evaluation(i, e, best):
        walls.append(time.perf_counter() - progress.t0)
        progress(i, e, best)
    try:
        res = Study(opt, executor, budget, batch_size=args.batch_size, on_evaluation=on_evaluation,
                    clock_start=clock_start).run()
    finally:
        progress.close()
        close_executor()
    from robodesign.experiment.suites import record_of_run
    run = record_of_run("", args.task, args.optimizer, args.seed, [
        {"feasible": e.feasible, "cost": e.cost, "stage": e.stage, "stage_index": e.stage_index, "wall": w,
         "message": e.message} for e, w in zip(res.history, walls)])
    best = res.best
    out = None
    if best is not None and best.feasible and best.solution is not None:
        from robodesign.formats.solution import parse_solution
        sol = parse_solution(best.solution, "best")
        out = sol.write(args.out or "best_solution.json")
    summary = {"optimizer": args.optimizer, "evaluations": len(res.history), "seconds": res.seconds,
               "workers": workers, "batch_size": args.batch_size,
               "messages": executor.pool.messages if workers > 1 else 0,
               "stopped": res.stopped, "feasible": bool(best and best.feasible),
               "best": None if best is None else {"order": list(best.candidate.order), "base": list(best.candidate.base),
                                                  "base_pose": problem.base_pose(best.candidate).tolist(),
                                                  "cost": best.cost, "stage": best.stage, "message": best.message,
                                                  "costs": best.costs},
               "solution": str(out) if out else None, "first_feasible_seconds": run.first_feasible_s,
               "stopped_at": run.stopped_at or None, "stage_counts": run.stage_counts,
               "budget_overrun": res.overrun, "last_evaluation_seconds": res.last_evaluation_seconds,
               "dropped": res.dropped}
    if args.json:
        print(json.dumps(summary))
    else:
        sent = f", {summary['messages']} messages to them" if workers > 1 else ""
        print(f"{len(res.history)} evaluations in {res.seconds:.1f} s ({res.stopped}; {workers} worker(s){sent}, "
              f"batches of {args.batch_size}); {sum(e.feasible for e in res.history)} feasible")
        if res.overrun:
            print(f"time budget exceeded by {res.overrun:.1f} s: evaluations running at the deadline finished "
                  f"(the longest took {res.last_evaluation_seconds or 0.0:.1f} s); {res.dropped} asked candidate(s) "
                  f"not evaluated")
        if best is not None and best.feasible:
            bp = problem.base_pose(best.candidate)
            print(f"best robot   {','.join(best.candidate.order)}")
            print(f"base pose    xyz {np.round(bp[:3, 3], 4).tolist()}  yaw {np.degrees(np.arctan2(bp[1, 0], bp[0, 0])):.1f}°")
            print(f"cost         {args.cost} = {best.cost:.6g}")
            print(f"solution     {out} (checked valid)")
        else:
            print("no feasible robot found within the budget"
                  + (f"; the best candidate failed at stage '{best.stage}': {best.message}" if best else ""))
            if run.stage_counts:
                from robodesign.experiment.suites import stage_counts_text
                print(f"every candidate stopped at or before stage '{run.stopped_at}' (failures per stage: "
                      f"{stage_counts_text(run.stage_counts)})")
    return 0 if best is not None and best.feasible else 1


#: without ``--workers``, a budget of fewer evaluations than this (and no time limit) runs in this process:
#: a worker pool's start-up (~0.7 s: spawn, import, load, warm up) costs more than it saves there (random
#: search on PTP_3/IMPROV, the whole command: 50 evaluations 2.3 s in the process against 2.8 s with 2
#: workers, 100: 2.7 / 3.3 s, 200: 4.4 / 4.2 s, 400: 5.4 / 4.7 s; docs/benchmarks.md)
POOL_MIN_EVALUATIONS = 200


def optimize_workers(workers, batch_size: int, chunk_size: Optional[int] = None, budget=None) -> int:
    """``--workers`` (default: every core this process may use, or 1 for an evaluations-only ``budget`` below
    :data:`POOL_MIN_EVALUATIONS`), at most one per candidate of a batch; ``--batch-size`` and
    ``--chunk-size`` are checked on the way."""
    import os
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
    else the experiments' process pool (results are the same for any number of workers)."""
    from robodesign.design.evaluator import Evaluator
    from robodesign.design.optimize import SerialExecutor
    if workers == 1:
        return SerialExecutor(Evaluator(spec)), lambda: None
    from robodesign.experiment.executors import ProcessPool
    pool = ProcessPool({"optimize": spec}, workers, chunk_size)
    return pool.bind("optimize"), pool.close


class _Progress:
    """A rich progress bar on a terminal, one line per evaluation otherwise."""

    def __init__(self, budget, quiet=False):
        self.quiet = quiet
        self.t0 = time.perf_counter()
        self.bar = None
        if not quiet and sys.stderr.isatty():
            from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
            self.bar = Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed} evals"),
                                TimeElapsedColumn(), transient=True)
            self.bar.start()
            self.task = self.bar.add_task("optimizing", total=budget.evaluations)

    def __call__(self, i, ev, best):
        if self.quiet:
            return
        b = f"{best.cost:.4g}" if best is not None and best.feasible else "—"
        if self.bar is not None:
            self.bar.update(self.task, advance=1, description=f"best {b}")
        else:
            state = f"cost {ev.cost:.4g}" if ev.feasible else f"failed at {ev.stage}"
            print(f"[{i + 1:4d}] {time.perf_counter() - self.t0:7.1f}s  {ev.candidate.key():40s} {state:24s} best {b}",
                  file=sys.stderr, flush=True)

    def close(self):
        if self.bar is not None:
            self.bar.stop()
