"""Implementations of the ``solve``, ``optimize`` and ``optimizers`` CLI commands."""
from __future__ import annotations

import json
import time
from typing import List

from robodesign.cli.journal import EXIT_INTERRUPTED, Journal, resume_command, write_best, write_interrupted
from robodesign.cli.progress import Progress, progress_mode
from robodesign.cli.workers import (  # noqa: F401 - re-exported: their home before cli.workers
    POOL_MIN_EVALUATIONS,
    optimize_executor,
    optimize_workers,
    search_rules,
    short_budget,
)
from robodesign.core.errors import InputError
from robodesign.design.diagnosis import diagnose
from robodesign.experiment.report import base_pose_text


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


def trajectory_mode(cost, choice: str = "auto", optimize_flag: bool = False) -> str:
    """"time-optimal" or "optimize" for a cost (a CostFunction, or --cost's text) and the --trajectory /
    --optimize-trajectory options."""
    from robodesign.formats.costs import CostFunction, cost_term, parse_cost
    if optimize_flag:
        if choice == "time-optimal":
            raise InputError("--optimize-trajectory contradicts --trajectory time-optimal")
        return "optimize"
    if choice != "auto":
        return choice
    # optimize for the terms trajectory optimization lowers beyond the time-optimal profile: the modelled
    # torque integrals (mechEnergy, effort)
    weights = (cost if isinstance(cost, CostFunction) else parse_cost(cost, path="--cost")).terms
    energy_like = [n for n, w in weights if w > 0 and cost_term(n).trajopt and cost_term(n).needs_torques]
    return "optimize" if energy_like else "time-optimal"


def cmd_solve(args) -> int:
    from robodesign.cli.args import parse_order, print_input_warnings
    from robodesign.cli.collab import load_collab_task_file, solve_command
    from robodesign.design.solve import SolveSettings, check_settings, solve
    from robodesign.formats.assembly import Assembly
    from robodesign.formats.costs import parse_cost
    from robodesign.formats.module_io import load_module_set
    from robodesign.formats.task_io import load_task
    cost = parse_cost(args.cost, path="--cost")  # once: the object travels to solve and the solution file
    mode = trajectory_mode(cost, args.trajectory, args.optimize_trajectory)
    check_settings(SolveSettings(planner=args.planner, plan_time=args.plan_time, timing=args.timing))
    ctask = load_collab_task_file(args.task)
    if ctask is not None:  # several robots in one cell: docs/collaborative.md
        return solve_command(args, ctask, mode, cost)
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
    res = solve(task, ms, order, _base_pose(args.base_pose, task), cost=cost, settings=settings)
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
        for s in res.stages if not getattr(args, "quiet", False) else ():
            msg = s.message if getattr(args, "verbose", False) else s.message[:150]
            print(f"  {s.name:14s} {'ok ' if s.passed else 'FAIL'} {s.seconds * 1e3:8.1f} ms  {msg}")
        how = ("time-optimal (TOPP-RA)" if args.timing == "toppra" else "time-optimal (ruckig)") \
            if mode == "time-optimal" else f"optimized for {args.cost} (CasADi/ipopt)"
        chosen = " (--trajectory auto, from the cost)" if args.trajectory == "auto" and not args.optimize_trajectory \
            else ""
        print(f"trajectory   {how}{chosen}")
        if res.feasible and res.verdict is not None:  # (feasible: a valid verdict)
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


def cmd_optimize(args) -> int:
    from robodesign.cli.args import parse_options, print_input_warnings
    from robodesign.cli.collab import load_collab_task_file, optimize_command
    from robodesign.design.solve import SolveSettings, check_settings
    check_settings(SolveSettings(planner=args.planner, plan_time=args.plan_time))  # before any evaluation
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
    spec = EvaluatorSpec(problem, evaluation_settings(planner=args.planner, optimize_trajectory=args.optimize_trajectory,
                                                      plan_time=args.plan_time), seed=args.seed)
    opt = create_optimizer(args.optimizer, problem, seed=args.seed, options=parse_options(args.opt))
    workers = optimize_workers(args.workers, args.batch_size, args.chunk_size, budget)
    if args.workers is None and short_budget(budget) and not (args.json or args.quiet):
        print(f"evaluating in this process: {budget.evaluations} evaluations are fewer than a worker pool's "
              f"start-up pays for ({POOL_MIN_EVALUATIONS}); --workers N uses N processes")
    journal = Journal(args, problem, budget)  # every evaluation committed: Ctrl-C loses nothing (--resume)
    clock_start = time.perf_counter()  # a time budget counts from here: the worker pool's start-up is spent from it
    executor, close_executor = optimize_executor(spec, workers, args.chunk_size)
    progress = Progress(journal.budget, progress_mode(args))
    walls: List[float] = []  # wall time of each evaluation (a resumed search: since the search began)

    def on_evaluation(i, e, best):
        walls.append(journal.storage.wall())
        progress(i, e, best)
    res = None
    try:
        res = Study(opt, executor, journal.budget, batch_size=args.batch_size, storage=journal.storage,
                    on_evaluation=on_evaluation, stop_on_interrupt=True, clock_start=clock_start).run()
        if res.stopped == "interrupted":  # the best so far is saved before anything else can be interrupted
            progress.close()
            write_interrupted(args, res, journal)
    finally:
        progress.close()
        close_executor(now=res is None or res.stopped == "interrupted")
        journal.close(keep=res is None or res.stopped == "interrupted")
    return _report_optimize(args, problem, res, walls, workers, executor, journal)


def _report_optimize(args, problem, res, walls: List[float], workers: int, executor, journal: Journal) -> int:
    """Write the best checked solution, print the summary (JSON or text, with the diagnosis when nothing valid was
    found) and return the exit code of ``robodesign optimize``."""
    from robodesign.experiment.suites import record_of_run
    run = record_of_run("", args.task, args.optimizer, args.seed, [
        {"feasible": e.feasible, "cost": e.cost, "stage": e.stage, "stage_index": e.stage_index, "wall": w,
         "message": e.message} for e, w in zip(res.history, walls)])
    best = res.best
    out = None
    if best is not None and best.feasible and best.solution is not None:
        out = write_best(best, args.out)
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
               "resumed_evaluations": journal.stored,
               "resume": resume_command(getattr(args, "argv", None)) if res.stopped == "interrupted" else None,
               "budget_overrun": res.overrun, "last_evaluation_seconds": res.last_evaluation_seconds,
               "dropped": res.dropped}
    diagnosis = diagnose(problem, res.history, res.stopped)  # why nothing valid was found (docs/diagnosis.md)
    summary["diagnosis"] = diagnosis.to_json()
    if args.json:
        print(json.dumps(summary))
    else:
        _print_optimize_text(args, problem, res, summary, workers, out, run, diagnosis)
    if res.stopped == "interrupted":
        return EXIT_INTERRUPTED
    return 0 if best is not None and best.feasible else 1


def _print_optimize_text(args, problem, res, summary: dict, workers: int, out, run, diagnosis) -> None:
    """The text summary of ``robodesign optimize``."""
    best = res.best
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
        print(f"base pose    {base_pose_text(bp.tolist())}")
        print(f"cost         {args.cost} = {best.cost:.6g}")
        print(f"solution     {out} (checked valid)")
    else:
        print("no feasible robot found within the budget"
              + (f"; the best candidate failed at stage '{best.stage}': {best.message}" if best else ""))
        if run.stage_counts:
            from robodesign.experiment.suites import stage_counts_text
            print(f"every candidate stopped at or before stage '{run.stopped_at}' (failures per stage: "
                  f"{stage_counts_text(run.stage_counts)})")
        print(f"diagnosis    {diagnosis.message}")
