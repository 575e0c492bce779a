"""``robodesign run [CONFIG] [--out DIR] [--resume DIR] [--executor serial|process|ray] [--workers N]
[--address ADDR] [--chunk-size N]`` (the ``run`` subcommand; ``robodesign.cli.entry`` delegates here)."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from robodesign.core.errors import InputError

DEFAULT_CONFIG = "configs/default.yaml"


def add_run_arguments(run: argparse.ArgumentParser) -> None:
    run.add_argument("config", nargs="?", help=f"experiment config (YAML); default: the bundled {DEFAULT_CONFIG} "
                                               "(the built-in pick-and-place demo)")
    run.add_argument("--out", metavar="DIR", help="results folder (default: results/<config name>-<timestamp>/)")
    run.add_argument("--resume", metavar="DIR", help="continue the experiment in this results folder (after a "
                                                     "crash or kill); finished runs are skipped")
    run.add_argument("--restart", action="store_true",
                     help="with --resume: start the experiment over in its folder when its results database is "
                          "missing or damaged (the old database and best files are moved to damaged-<time>/)")
    run.add_argument("--executor", choices=("serial", "process", "ray"), help="override the config's executor")
    run.add_argument("--workers", type=int, help="worker processes / Ray actors (default: the config's, else "
                                                 "the number of CPUs)")
    run.add_argument("--address", help="Ray cluster address HOST:PORT (with --executor ray; default: start a "
                                        "private local Ray instance)")
    run.add_argument("--chunk-size", type=int, metavar="N",
                     help="candidates per message to a worker process or Ray actor (default: the config's "
                          "executor.chunk_size, else automatic from the batch size and --workers)")
    run.add_argument("--progress", choices=("auto", "bar", "lines", "summary", "none"), default="auto",
                     help="progress display: auto (default) is a bar on a terminal, otherwise a summary line every "
                          "5 s at most; lines: one line per evaluation")
    g = run.add_mutually_exclusive_group()
    g.add_argument("--quiet", "-q", action="store_true", help="the same as --progress none")
    g.add_argument("--verbose", "-v", action="store_true", help="the same as --progress lines")
    run.add_argument("--no-report", action="store_true", help="do not write the report (CSV, plots, HTML)")


def default_config_path() -> Path:
    from robodesign.core.paths import project_root
    return project_root() / DEFAULT_CONFIG


def cmd_run(args) -> int:
    from robodesign.experiment.config import load_experiment
    from robodesign.experiment.report import base_pose_text, search_offsets_text
    from robodesign.experiment.runner import default_out_dir, load_resume, make_progress, run_experiment

    if args.workers is not None and args.workers < 1:
        raise InputError("--workers must be at least 1")
    if args.chunk_size is not None and args.chunk_size < 1:
        raise InputError(f"--chunk-size must be at least 1, got {args.chunk_size}")
    if args.address and (args.executor or "ray") != "ray":
        raise InputError("--address needs --executor ray")
    executor = args.executor or ("ray" if args.address else None)
    if args.restart and not args.resume:
        raise InputError("--restart needs --resume DIR (it starts the experiment in that folder over)")
    if args.resume:
        if args.config:
            raise InputError("give either a CONFIG or --resume DIR, not both (a resumed experiment uses the "
                             "config.yaml saved in its folder)")
        if args.out:
            raise InputError("--out cannot be combined with --resume")
        out = Path(args.resume)
        exp, text, _meta = load_resume(out)
        cfg_path = None
    else:
        cfg_path = Path(args.config) if args.config else default_config_path()
        exp, text = load_experiment(cfg_path, display=args.config or str(cfg_path))
        out = Path(args.out) if args.out else default_out_dir(exp.name)
    progress = make_progress("none" if args.quiet else "lines" if args.verbose else args.progress)
    n_runs = len(list(exp.runs()))
    progress.message(f"experiment {exp.name}: {len(exp.problems)} task(s) × {len(exp.optimizers)} optimizer(s) × "
                     f"{len(exp.seeds)} seed(s) = {n_runs} runs → {out}")
    try:
        outcome = run_experiment(exp, out, config_text=text, config_path=cfg_path, resume=bool(args.resume),
                                 restart=args.restart, executor=executor, workers=args.workers, address=args.address,
                                 chunk_size=args.chunk_size, progress=progress, report=not args.no_report)
    except KeyboardInterrupt:  # Ctrl-C or SIGTERM: every evaluation so far is stored in the folder
        progress.close()
        if not (out / "meta.json").is_file():
            raise
        import shlex
        print(f"robodesign: interrupted; the results so far are in {out}; continue with: "
              f"robodesign run --resume {shlex.quote(str(out))}", file=sys.stderr, flush=True)
        return 130
    finally:
        progress.close()
    print(f"\n{outcome.evaluations} evaluations ({outcome.new_evaluations} new) in {outcome.runs} runs, "
          f"{outcome.seconds:.1f} s")
    in_suite = {p.name for p in exp.problems if p.suite}
    for task, b in outcome.best.items():
        if task in in_suite:
            continue  # summarized per suite below
        if b is None:
            print(f"best robot for {task}: none feasible found")
            continue
        import json
        sol = json.loads(b["solution"]) if b.get("solution") else {}
        bp = (sol.get("basePose") or [None])[0]
        params = json.loads(b["base"])
        print(f"best robot for {task}: {b['optimizer']} seed {b['run_seed']}, cost {sol.get('costFunction', '')} = "
              f"{b['cost']:.6g}")
        print(f"  module order  {','.join(json.loads(b['module_order']))}")
        print(f"  base pose     {base_pose_text(bp)}" + (f"  (search offsets {search_offsets_text(params)})"
                                                       if params else ""))
    if in_suite:
        print_suites(outcome.out_dir)
    print(f"results: {outcome.out_dir}")
    if outcome.report:
        print(f"report:  {outcome.report}")
    return 0


def print_suites(out: Path) -> None:
    """One line per suite and optimizer: solved share, best costs, time to the first feasible design, and
    where the unsolved runs stopped."""
    import json

    from robodesign.experiment.storage import ExperimentDB
    from robodesign.experiment.suites import cell, problems_of, records_from_db, suite_of_problems, summarize_suites
    db = ExperimentDB(out / "evaluations.sqlite")
    try:
        meta = json.loads((out / "meta.json").read_text())
        summary = summarize_suites(records_from_db(db, suite_of_problems(meta), problems_of(meta)))
    finally:
        db.close()
    for s in summary:
        line = (f"suite {s['suite']} · {s['optimizer']}: solved {s['solved']}/{s['runs']} runs "
                f"({cell('solved_pct', s['solved_pct'])}) of {s['tasks']} tasks; best cost median "
                f"{cell('', s['best_cost_median'])} [min {cell('', s['best_cost_min'])}, max "
                f"{cell('', s['best_cost_max'])}]; first feasible after {cell('', s['first_feasible_s_median'])} s "
                f"(median)")
        if s["out_of_reach"]:
            line += (f"; {s['out_of_reach']} provably out of reach, solved {cell('solved_pct', s['solved_pct_reachable'])}"
                     f" of the rest")
        if s["unsolved_stopped_at"]:
            line += f"; unsolved runs stopped at: {s['unsolved_stopped_at']}"
        print(line)
