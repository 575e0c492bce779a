"""Command line interface: ``robodesign robot | check | solve | ...``.

Exit codes (the same for every subcommand):

* 0 success (a valid solution, a written file, ...);
* 1 a negative verdict: an invalid solution, no valid solution or no feasible robot found;
* 2 bad input: a malformed or invalid file, field or argument. One line on stderr naming the file and
  field, never a traceback;
* 3 an internal error (a bug in robodesign): one line "internal error, please report"; ``--debug``
  (or ``ROBODESIGN_DEBUG=1``) prints the full traceback.

With ``--json``, stdout is JSON on every path: on exit 2 or 3 it is
``{"error": message, "file": file or null, "path": JSON path or null}``.
"""
from __future__ import annotations

import argparse
import functools
import json
import math
import os
import sys
import traceback
from pathlib import Path
from typing import List, Optional

import numpy as np

from robodesign.core.errors import InputError, RobodesignError

EXIT_OK, EXIT_NEGATIVE, EXIT_BAD_INPUT, EXIT_INTERNAL = 0, 1, 2, 3


def _fmt_matrix(T) -> str:
    return "\n".join("    " + " ".join(f"{x:9.4f}" for x in row) for row in np.asarray(T))


def cmd_robot(args) -> int:
    from robodesign.cli.args import parse_base_pose, parse_floats, parse_order, print_input_warnings
    from robodesign.formats.module_io import load_module_set
    from robodesign.model.robot import Robot
    ms = load_module_set(args.modules)
    print_input_warnings(ms)
    robot = Robot.from_order(ms, parse_order(args.order),
                             base_pose=parse_base_pose(args.base_pose) if args.base_pose else None)
    q = np.zeros(robot.dof)
    if args.q:
        qv = parse_floats(args.q, "--q")
        if len(qv) != robot.dof:
            raise InputError(f"--q: the robot has {robot.dof} joints, got {len(qv)} values")
        q = np.array(qv)
    s = robot.summary(q)
    s["module_set"] = ms.name
    if args.urdf:
        from robodesign.formats.urdf import export_urdf
        s["urdf"] = str(export_urdf(robot, args.urdf))
    if args.json:
        print(json.dumps(s))
        return 0
    _print_summary(s)
    return 0


def _print_summary(s: dict) -> None:
    lim = s["joint_limits"]
    print(f"robot     {s['module_set']}: {','.join(s['modules'])}")
    print(f"dof       {s['dof']}")
    print(f"mass      {s['mass']:.3f} kg")
    print(f"q         {np.round(s['q'], 4).tolist()}")
    print("TCP pose")
    print(_fmt_matrix(s["tcp_pose"]))
    print(f"gravity τ {np.round(s['gravity_torque'], 3).tolist()} Nm")
    print("joint limits")
    for k, name in enumerate(s["joint_names"]):
        print(f"    {name:24s} q [{lim['lower'][k]:7.3f}, {lim['upper'][k]:7.3f}]  dq {lim['velocity'][k]:.3f}  "
              f"ddq {lim['acceleration'][k]:.3f}  τ {lim['torque'][k]:.1f}")
    print(f"collision geometries {s['n_collision_geometries']}, self-collision pairs {s['n_self_collision_pairs']}")
    print(f"self-collision at q: {'YES' if s['self_collision'] else 'no'}")
    if s.get("urdf"):
        print(f"URDF written to {s['urdf']}")


def cmd_run(args) -> int:
    """Run an experiment config (default: the bundled configs/default.yaml); docs/experiments.md."""
    from robodesign.cli.run import cmd_run as _cmd_run
    return _cmd_run(args)


def cmd_check(args) -> int:
    from robodesign.cli.args import module_set_for_solution, print_input_warnings
    from robodesign.cli.collab import check_command, load_collab_task_file
    from robodesign.collab.core import is_collaborative
    from robodesign.core.jsonio import load_json
    from robodesign.formats.solution import parse_solution
    from robodesign.formats.task_io import load_task
    from robodesign.judge.checker import check
    ctask = load_collab_task_file(args.task)
    if ctask is not None:  # several robots in one cell: docs/collaborative.md
        return check_command(args, ctask)
    task = load_task(args.task)
    print_input_warnings(task)
    data = load_json(args.solution, display_name=Path(args.solution).name)
    if is_collaborative(data):
        raise InputError("the solution is collaborative (a 'robots' list) but the task is not: give the "
                         "collaborative task", file=Path(args.task).name)
    sol = parse_solution(data, Path(args.solution).name, source=str(args.solution))
    ms = module_set_for_solution(sol, args.modules)
    print_input_warnings(ms)
    verdict = check(task, sol, module_set=ms)
    if args.json:
        print(json.dumps(verdict.to_json()))
    else:
        print(f"task      {task.id}")
        print(f"solution  {args.solution}")
        print(f"verdict   {'VALID' if verdict.valid else 'INVALID'} ({verdict.samples} samples, "
              f"{verdict.timings.get('total', 0) * 1e3:.0f} ms)")
        if verdict.cost is not None:
            print(f"cost      {verdict.cost_function} = {verdict.cost:.6g}")
        if verdict.goals:
            print("goals     " + ", ".join(f"{g}: {'ok' if ok else 'MISSED'}" for g, ok in verdict.goals.items()))
        for v in verdict.violations:
            print(f"  - {v}")
        if verdict.costs:
            print("costs     " + ", ".join(f"{k}={v:.6g}" for k, v in verdict.costs.items()))
    return EXIT_OK if verdict.valid else EXIT_NEGATIVE


def cmd_serve(args) -> int:
    """Run the benchmark website (docs/website.md)."""
    try:
        import uvicorn  # noqa: F401  (only: is it there?)

        from robodesign.web import create_app
    except ImportError as e:
        raise InputError(f"the website needs fastapi, uvicorn, sqlalchemy and python-multipart ({e})") from None
    if args.max_upload_mb <= 0:
        raise InputError("--max-upload-mb must be positive")
    for opt in ("queue", "per_client_queue", "upload_rate", "read_rate"):
        if getattr(args, opt) < 0 or not math.isfinite(getattr(args, opt)):
            raise InputError(f"--{opt.replace('_', '-')} must be a finite number ≥ 0")
    for opt in ("body_timeout", "header_timeout", "keep_alive"):
        if not (getattr(args, opt) > 0 and math.isfinite(getattr(args, opt))):
            raise InputError(f"--{opt.replace('_', '-')} must be a positive number of seconds")
    if args.max_connections < 1:
        raise InputError("--max-connections must be at least 1")
    app = create_app(db_url=args.db, data_dir=args.data, seed=args.seed or (), seed_builtin=not args.no_builtin,
                     max_request_bytes=int(args.max_upload_mb * (1 << 20)), check_workers=args.workers,
                     admin_token=args.admin_token, open_registration=args.open_registration, queue_size=args.queue,
                     per_client_queue=max(1, args.per_client_queue), upload_rate=args.upload_rate,
                     read_rate=args.read_rate, body_timeout=args.body_timeout,
                     check_processes=not args.check_threads)
    if not args.check_threads:
        app.state.checker.start()  # the checker processes, before the first upload needs them
    for line in app.state.bench.seed_log:
        print(f"robodesign: {line}", file=sys.stderr)
    if args.open_registration:
        print("robodesign: registration is open: anyone may add tasks and module sets", file=sys.stderr)
    elif not (args.admin_token or os.environ.get("ROBODESIGN_ADMIN_TOKEN")):
        print("robodesign: no admin token (ROBODESIGN_ADMIN_TOKEN / --admin-token): registering tasks and module "
              "sets is disabled; seeds still work", file=sys.stderr)
    from robodesign.web.server import serve
    serve(app, args.host, args.port, header_timeout=args.header_timeout, keep_alive=args.keep_alive,
          max_connections=args.max_connections)
    return 0


def cmd_view(args) -> int:
    """Write a self-contained HTML page of a solution, a task or a robot (docs/viewer.md)."""
    from robodesign.cli.view import describe, run_view
    path, warnings = run_view(args.solution, task=args.task, modules=args.modules, order=args.order, q=args.q,
                              base_pose=args.base_pose, out=args.out, check=args.check, plots=not args.no_plots,
                              collision=args.collision, fps=args.fps)
    print(describe(path))
    for w in warnings:
        print(f"robodesign: warning: {w}", file=sys.stderr)
    return EXIT_NEGATIVE if warnings else EXIT_OK


class _UsageError(Exception):
    def __init__(self, parser: argparse.ArgumentParser, message: str):
        super().__init__(message)
        self.parser = parser


class _HelpFormatter(argparse.HelpFormatter):
    """Appends "(default: X)" to an option's help unless the help already says its default."""

    def _get_help_string(self, action):
        text = action.help or ""
        if (action.option_strings and action.default not in (None, False, [], argparse.SUPPRESS)
                and "default" not in text):
            text += " (default: %(default)s)"
        return text


class _Parser(argparse.ArgumentParser):
    """argparse with one-line usage errors raised (main() prints them, as JSON too with --json) and
    option values that start with "-" taken as values (``--budget -5s``, ``--q -0.3,0.2``)."""

    def __init__(self, *a, **kw):
        kw.setdefault("formatter_class", _HelpFormatter)
        super().__init__(*a, **kw)

    def error(self, message):
        raise _UsageError(self, message)

    def parse_known_args(self, args=None, namespace=None):
        if args is not None:
            args = self._join_dash_values(list(args))
        return super().parse_known_args(args, namespace)

    def _join_dash_values(self, args: List[str]) -> List[str]:
        out, i = [], 0
        while i < len(args):
            act = self._option_string_actions.get(args[i])
            if (act is not None and act.nargs is None and i + 1 < len(args) and args[i + 1].startswith("-")
                    and args[i + 1] != "--" and args[i + 1].split("=")[0] not in self._option_string_actions):
                out.append(f"{args[i]}={args[i + 1]}")
                i += 2
            else:
                if args[i] == "--":
                    return out + args[i:]
                out.append(args[i])
                i += 1
        return out


def _version() -> str:
    from robodesign import __version__
    return f"robodesign {__version__} (Python {sys.version.split()[0]})"


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="robodesign", description="Find the best modular robot for a task.",
                epilog="Exit codes: 0 success, 1 negative verdict (invalid solution, nothing feasible found), "
                       "2 bad input, 3 internal error (please report; --debug shows the traceback).")
    p.add_argument("--version", action="version", version=_version())
    p.add_argument("--debug", action="store_true", help="print the full traceback of an internal error")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    _add_robot(sub)
    _add_check(sub)
    _add_solve(sub)
    _add_optimize(sub)
    _add_optimizers(sub)
    _add_run(sub)
    _add_serve(sub)
    _add_generate(sub)
    _add_view(sub)

    for sp in sub.choices.values():  # also accepted after the subcommand: robodesign check ... --debug
        sp.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                        help="print the full traceback of an internal error")
    return p


def _add_robot(sub: "argparse._SubParsersAction") -> None:
    """``robodesign robot``: assemble a robot and print its summary."""
    r = sub.add_parser("robot", help="assemble a robot from a module order and print its summary")
    r.add_argument("modules", help="module set: a folder with modules.json, a built-in name or a URDF file")
    r.add_argument("--order", required=True, help="comma-separated module IDs, base first")
    r.add_argument("--q", help="joint values (comma-separated); default zeros")
    r.add_argument("--base-pose", help="x,y,z[,roll,pitch,yaw] or 16 numbers (row-major 4x4); default identity")
    r.add_argument("--json", action="store_true", help="print one JSON object")
    r.add_argument("--urdf", help="also write the robot as URDF to this file")
    r.set_defaults(func=cmd_robot)


def _add_check(sub: "argparse._SubParsersAction") -> None:
    """``robodesign check``: check a solution against a task."""
    c = sub.add_parser("check", help="check a CoBRA solution (or a collaborative one) against a task (exit 0 valid, "
                                     "1 invalid, 2 bad input)")
    c.add_argument("task", help="task JSON file (or a built-in task name)")
    c.add_argument("solution", help="solution JSON file")
    c.add_argument("--modules", help="module set folder or built-in name (default: the solution's moduleSet)")
    c.add_argument("--json", action="store_true", help="print {valid, violations, costs, cost} as JSON")
    c.set_defaults(func=cmd_check)


def _add_solve(sub: "argparse._SubParsersAction") -> None:
    """``robodesign solve``: plan a checked solution for one robot (or every robot of a collaborative task)."""
    from robodesign.cli import commands
    so = sub.add_parser("solve", help="plan a checked solution of a task for one robot (or for every robot of a "
                                      "collaborative task)")
    so.add_argument("task", help="task JSON file or built-in task ID")
    so.add_argument("--modules", required=True, help="module set folder or built-in name")
    so.add_argument("--order", help="comma-separated module IDs, base first (required for a single-robot task; "
                                    "for a collaborative task: every robot not given by --robot)")
    so.add_argument("--robot", action="append", default=[], metavar="ID=ORDER",
                    help="a collaborative task's robot and its module order (repeatable; default: --order)")
    so.add_argument("--base-pose", help="x,y,z[,roll,pitch,yaw] or 16 numbers; default: the task's nominal base")
    so.add_argument("--cost", default="cyc", help="cost function, e.g. cyc, mechEnergy, Liu2, cyc_0.2,mechEnergy_1")
    so.add_argument("--planner", default="rrtconnect", help="OMPL planner (rrtconnect, rrtstar, prm, bitstar, kpiece, ...)")
    so.add_argument("--plan-time", type=float, default=1.0, help="seconds per planning query")
    so.add_argument("--timing", default="toppra", choices=["toppra", "ruckig"], help="time parameterization")
    commands.add_trajectory_arguments(so)
    so.add_argument("--seed", type=int, default=0, help="random seed of IK restarts and planning")
    so.add_argument("--out", help="write the CoBRA solution here")
    so.add_argument("--json", action="store_true", help="print {feasible, stage, cost, costs, trajectory, stages, "
                                                        "solution, seconds} as one JSON object")
    add_verbosity_arguments(so, "one line per pipeline stage")
    so.set_defaults(func=commands.cmd_solve)


def _add_optimize(sub: "argparse._SubParsersAction") -> None:
    """``robodesign optimize``: search module orders (and base poses) for the best robot."""
    from robodesign.cli import commands
    op = sub.add_parser("optimize", help="search module orders (and base poses) for the best robot")
    op.add_argument("task", help="task JSON file or built-in task ID")
    op.add_argument("--modules", required=True, help="module set folder or built-in name")
    op.add_argument("--optimizer", default="random", help="installed plugin name (see: robodesign optimizers)")
    op.add_argument("--cost", default="cyc", help="cost function to minimise, e.g. cyc, mechEnergy, cyc_0.2,mass_1")
    op.add_argument("--budget", default="50evals", help="e.g. 500evals, 60s, 10min, or 500evals,60s")
    op.add_argument("--seed", type=int, default=0, help="random seed of the optimizer and of every evaluation")
    op.add_argument("--workers", type=int, help="evaluate each batch in N worker processes (default: all cores, "
                                                "but a budget of fewer than 200 evaluations and no time runs in "
                                                "this process, where a pool's start-up costs more than it saves; "
                                                "1 = in this process); the result does not depend on N")
    op.add_argument("--batch-size", type=int, default=16,
                    help="candidates asked per step and evaluated in parallel; the same seed and batch size give "
                         "the same result for any --workers (default: %(default)s)")
    op.add_argument("--chunk-size", type=int, metavar="N",
                    help="candidates per message to a worker process (default: automatic from --batch-size and "
                         "--workers: a batch of 16 on 2 workers goes in 8 messages, a stream in chunks of 4)")
    op.add_argument("--out", help="where to write the best checked solution (default best_solution.json)")
    op.add_argument("--opt", action="append", default=[], metavar="KEY=VALUE",
                    help="optimizer option (repeatable; default: none)")
    op.add_argument("--dof", help="DoF rule, e.g. 6 or 5-7 (default: 7 for a task with a goal that fixes position "
                    "and orientation among obstacles, else 6)")
    op.add_argument("--max-links", type=int, help="max passive link modules between two joints (default 1)")
    op.add_argument("--fixed-base", action="store_true", help="keep the base at its nominal pose")
    op.add_argument("--planner", default="rrtconnect", help="OMPL planner of every evaluation")
    op.add_argument("--plan-time", type=float, default=1.0,
                    help="seconds per planning query of every evaluation (a wall-clock limit: on a busy machine a "
                         "longer one keeps results independent of the load)")
    op.add_argument("--optimize-trajectory", action="store_true",
                    help="refine every move of every evaluated design with CasADi/ipopt for the cost (slow)")
    op.add_argument("--json", action="store_true", help="print the summary (best design, cost, evaluations) "
                                                        "as one JSON object; no progress lines")
    op.add_argument("--resume", action="store_true",
                    help="continue the interrupted search of this command (its journal <out>.journal.sqlite beside "
                         "--out holds every evaluation so far; the same seed and budget end with the same best)")
    add_verbosity_arguments(op, "progress: a bar on a terminal, otherwise a summary line every 5 s")
    op.set_defaults(func=commands.cmd_optimize)


def _add_optimizers(sub: "argparse._SubParsersAction") -> None:
    """``robodesign optimizers``: list the installed optimizer plugins."""
    from robodesign.cli import commands
    ol = sub.add_parser("optimizers", help="list installed optimizer plugins")
    ol.add_argument("--verbose", "-v", action="store_true",
                    help="also list each plugin's options (type, default, range, help)")
    ol.add_argument("--json", action="store_true", help="print {name: entry point} as one JSON object "
                    "(with --verbose: description and options too)")
    ol.set_defaults(func=commands.cmd_optimizers)


def _add_run(sub: "argparse._SubParsersAction") -> None:
    """``robodesign run``: run an experiment config."""
    run = sub.add_parser("run", help="run an experiment config (default: the built-in demo); resumable")
    from robodesign.cli.run import add_run_arguments
    add_run_arguments(run)
    run.set_defaults(func=cmd_run)


def _add_serve(sub: "argparse._SubParsersAction") -> None:
    """``robodesign serve``: run the benchmark website."""
    sv = sub.add_parser("serve", help="run the benchmark website (upload, check and rank solutions)")
    sv.add_argument("--db", help="SQLAlchemy database URL (default: SQLite <data>/bench.db; "
                                 "e.g. postgresql://user:pw@host/bench)")
    sv.add_argument("--data", default="robodesign_data", help="data folder: database, task and module set files "
                                                               "(default: ./robodesign_data)")
    sv.add_argument("--seed", action="append", metavar="DIR",
                    help="also register the tasks/ and modules/ of this folder at startup (repeatable)")
    sv.add_argument("--no-builtin", action="store_true", help="do not register the built-in assets/ at startup")
    sv.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1)")
    sv.add_argument("--port", type=int, default=8000, help="port (default 8000)")
    sv.add_argument("--max-upload-mb", type=float, default=20.0, help="request size limit in MiB (default 20)")
    sv.add_argument("--workers", type=int, default=None, help="checker processes (threads with --check-threads; "
                                                             "default: number of CPUs, 2..8)")
    sv.add_argument("--admin-token", help="token that registers tasks and module sets (header X-Admin-Token or "
                                          "Authorization: Bearer); default: $ROBODESIGN_ADMIN_TOKEN (preferred: "
                                          "a command line is visible to other users)")
    sv.add_argument("--open-registration", action="store_true",
                    help="let anyone register tasks and module sets (no admin token)")
    sv.add_argument("--queue", type=int, default=8, help="uploads that may wait for a checker thread (default 8; "
                                                         "beyond: 429 with Retry-After)")
    sv.add_argument("--per-client-queue", type=int, default=2, help="uploads one client may have in the queue "
                                                                    "(default 2)")
    sv.add_argument("--upload-rate", type=float, default=30.0, help="uploads/changes per minute per client "
                                                                    "(default 30; 0 = no limit)")
    sv.add_argument("--read-rate", type=float, default=20.0, help="page/API reads per second per client "
                                                                  "(default 20; 0 = no limit)")
    sv.add_argument("--check-threads", action="store_true", help="check uploads in threads of the server process "
                                                                 "(default: in --workers separate processes)")
    sv.add_argument("--body-timeout", type=float, default=120.0, help="seconds a request body may take to "
                                                                      "arrive (default 120; slower: 408)")
    sv.add_argument("--header-timeout", type=float, default=10.0, help="seconds a connection may take to send a "
                                                                       "request's headers (default 10; then closed)")
    sv.add_argument("--keep-alive", type=float, default=5.0, help="seconds an idle keep-alive connection stays open")
    sv.add_argument("--max-connections", type=int, default=1000, help="open connections at most (beyond: closed at "
                                                                      "once)")
    sv.set_defaults(func=cmd_serve)


def _add_generate(sub: "argparse._SubParsersAction") -> None:
    """``robodesign generate``: write seeded tasks of a task family."""
    ge = sub.add_parser("generate", help="write seeded CoBRA tasks of a published task family into a folder "
                                         "(whitman2020, liu2020, bpo2024; --list)")
    from robodesign.cli.generate import add_generate_arguments, cmd_generate
    add_generate_arguments(ge)
    ge.set_defaults(func=cmd_generate)


def _add_view(sub: "argparse._SubParsersAction") -> None:
    """``robodesign view``: write an HTML page of a solution, task or robot."""
    vw = sub.add_parser("view", help="write one self-contained HTML page that shows a solution (animated), "
                                     "a task or a robot")
    from robodesign.cli.view import add_view_arguments
    add_view_arguments(vw)
    vw.set_defaults(func=cmd_view)


@functools.lru_cache(maxsize=1)
def _parser() -> argparse.ArgumentParser:
    """The parser of :func:`main`, built once per process (building it costs ~45 ms, which dominated the fuzz
    tests' thousands of in-process calls). Reusing it is safe: parsing reads the parser and writes only a new
    namespace; :func:`_parse` copies list defaults and :func:`_command` finds the command by name at each call."""
    return build_parser()


def _parse(parser: argparse.ArgumentParser, argv: List[str]) -> argparse.Namespace:
    """``parser.parse_args(argv)``, with every list value copied: an option that was not given holds the parser's
    own default list (``--opt``, ``--robot``), which a command appending to it would change for later calls."""
    args = parser.parse_args(argv)
    for name, value in vars(args).items():
        if isinstance(value, list):
            setattr(args, name, list(value))
    return args


def _command(func):
    """The command function ``set_defaults(func=...)`` named, looked up in its module now (as a parser built
    at this call would have found it; tests replace commands with monkeypatch)."""
    module = sys.modules.get(getattr(func, "__module__", ""), None)
    return getattr(module, func.__name__, func) if module is not None and "." not in func.__qualname__ else func


def add_verbosity_arguments(p: argparse.ArgumentParser, default: str) -> None:
    """``--quiet`` and ``--verbose`` of a long command (``default``: what it prints without either)."""
    g = p.add_mutually_exclusive_group()
    g.add_argument("--quiet", "-q", action="store_true", help=f"no progress output, only the result (default: {default})")
    g.add_argument("--verbose", "-v", action="store_true", help="more progress output (optimize: one line per "
                                                                 "evaluation)")


def _close_matches(word: str, choices) -> str:
    import difflib
    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _did_you_mean(parser: argparse.ArgumentParser, message: str, argv: List[str]) -> tuple:
    """The parser whose usage to show and ``message`` with "did you mean" for a misspelt subcommand or
    option (``--budjet`` → ``--budget``)."""
    sub = next((a for a in parser._actions if isinstance(a, argparse._SubParsersAction)), None)
    if sub is None:
        return parser, message
    if message.startswith("argument COMMAND: invalid choice:"):
        word = message.split("'")[1] if "'" in message else ""
        return parser, f"unknown command {word!r}{_close_matches(word, sub.choices)}; commands: " \
                       f"{', '.join(sub.choices)}"
    if message.startswith("unrecognized arguments:"):
        command = next((a for a in argv if a in sub.choices), None)
        target = sub.choices[command] if command else parser
        options = [o for a in target._actions for o in a.option_strings if o.startswith("--")]
        words = message.split(":", 1)[1].split()
        hints = []
        for w in words:
            if w.startswith("-"):
                hints.append(f"{w}{_close_matches(w.split('=')[0], options)}")
            else:
                hints.append(repr(w))
        return target, f"unrecognized arguments: {' '.join(hints)}"
    return parser, message


def _raise_interrupt(signum, frame):
    """SIGTERM ends a command as Ctrl-C does (optimize keeps its best design, run its results)."""
    raise KeyboardInterrupt


def _fail(code: int, line: str, as_json: bool, error: Optional[str] = None, file: Optional[str] = None,
          path: Optional[str] = None) -> int:
    """One line on stderr; with --json also {"error", "file", "path"} on stdout. Returns ``code``."""
    print(f"robodesign: {'internal error' if code == EXIT_INTERNAL else 'error'}: {line}", file=sys.stderr)
    if as_json:
        print(json.dumps({"error": error or line, "file": file, "path": path or None}))
    return code


class _PipeGuard:
    """``sys.stdout`` while a command runs: once the reader has gone (``robodesign check ... | head``), further
    output is dropped instead of raising BrokenPipeError, so the command still ends with its own exit code."""

    def __init__(self, inner):
        self._inner, self.broken = inner, False

    def _close_pipe(self) -> None:
        self.broken = True
        try:  # the interpreter's last flush at exit must not fail either
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, self._inner.fileno())
            os.close(devnull)
        except (OSError, AttributeError, ValueError):
            pass

    def write(self, text):
        if not self.broken:
            try:
                return self._inner.write(text)
            except BrokenPipeError:
                self._close_pipe()
        return len(text)

    def flush(self):
        if not self.broken:
            try:
                self._inner.flush()
            except BrokenPipeError:
                self._close_pipe()

    def __getattr__(self, name):
        return getattr(self._inner, name)


def main(argv: Optional[List[str]] = None) -> int:
    out = sys.stdout
    guard = sys.stdout = _PipeGuard(out)
    try:
        return _main(argv)
    finally:
        guard.flush()
        if sys.stdout is guard:
            sys.stdout = out


def _main(argv: Optional[List[str]] = None) -> int:
    argv = [str(a) for a in (sys.argv[1:] if argv is None else argv)]
    as_json = "--json" in argv
    debug = "--debug" in argv or os.environ.get("ROBODESIGN_DEBUG", "") not in ("", "0")
    import signal
    import threading
    old_term = None
    if threading.current_thread() is threading.main_thread():
        old_term = signal.signal(signal.SIGTERM, _raise_interrupt)
    parser = _parser()
    try:
        args = _parse(parser, argv)
        args.argv = argv  # the command line as given (optimize prints its resume command)
        return int(_command(args.func)(args) or 0)
    except _UsageError as e:
        target, message = (e.parser, str(e)) if e.parser is not parser else _did_you_mean(parser, str(e), argv)
        target.print_usage(sys.stderr)
        command = target.prog.removeprefix("robodesign").strip()
        return _fail(EXIT_BAD_INPUT, f"{command}: {message}" if command else message, as_json)
    except InputError as e:
        return _fail(EXIT_BAD_INPUT, str(e), as_json, e.reason, e.file, e.json_path)
    except RobodesignError as e:
        return _fail(EXIT_BAD_INPUT, str(e), as_json)
    except KeyboardInterrupt:
        print("robodesign: interrupted", file=sys.stderr)
        return 130
    except Exception as e:  # a bug: its own exit code and a short line; the traceback only on request
        if debug:
            traceback.print_exc()
        what = f"{type(e).__name__}: {e}"
        what = what if len(what) <= 200 else what[:197] + "..."
        hint = "with the output of --debug" if debug else "(run again with --debug for the traceback)"
        return _fail(EXIT_INTERNAL, f"{what}. This is a bug in robodesign, please report it {hint}", as_json)
    finally:
        if old_term is not None:
            signal.signal(signal.SIGTERM, old_term)


if __name__ == "__main__":
    sys.exit(main())
