"""Experiment configs: YAML → validated :class:`ExperimentConfig` → :class:`ResolvedExperiment`.

Two steps, both with errors that name the file and the field (``configs/x.yaml: optimizers[1].budget:
budget '5x': use e.g. 500evals, ...``), raised as :class:`robodesign.core.errors.InputError` (CLI exit code 2):

1. :func:`load_config` reads the YAML (syntax errors with line/column, duplicate keys rejected) and
   validates its *shape* with pydantic (unknown fields, types, ranges, budgets, costs, benchmark IDs).
2. :func:`resolve_config` resolves what the config names: task files, module sets, optimizer plugins
   (loaded and instantiated once with their options), rules against the module set. Relative paths are
   relative to the folder of the config file.

The schema itself (YAML reading and the pydantic models) is :mod:`.config_models`, re-exported here. The reference
of every field is docs/experiments.md.
"""
from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, Iterator, List, Optional, Sequence, Tuple

from pydantic import BaseModel, ValidationError

from robodesign.core.errors import InputError, PathPart, format_json_path
from robodesign.design.optimize import Budget
from robodesign.design.problem import Problem
from robodesign.design.solve import SolveSettings, check_settings
from robodesign.experiment.config_models import DEFAULT_BUDGET as DEFAULT_BUDGET
from robodesign.experiment.config_models import EXECUTORS as EXECUTORS
from robodesign.experiment.config_models import MAX_YAML_NODES as MAX_YAML_NODES
from robodesign.experiment.config_models import BenchmarkEntry as BenchmarkEntry
from robodesign.experiment.config_models import ExecutorConfig as ExecutorConfig
from robodesign.experiment.config_models import ExperimentConfig as ExperimentConfig
from robodesign.experiment.config_models import OptimizerEntry as OptimizerEntry
from robodesign.experiment.config_models import Rules as Rules
from robodesign.experiment.config_models import SolveConfig as SolveConfig
from robodesign.experiment.config_models import SuiteEntry as SuiteEntry
from robodesign.experiment.config_models import SuiteGenerate as SuiteGenerate
from robodesign.experiment.config_models import TaskEntry as TaskEntry
from robodesign.experiment.config_models import read_yaml as read_yaml


# ------------------------------------------------------------------------------------------------
# loading
# ------------------------------------------------------------------------------------------------
def _format_pydantic(e: ValidationError, display: str) -> InputError:
    msgs = []
    for err in e.errors():
        loc = [p for p in err.get("loc", ()) if isinstance(p, (str, int))]
        msg = str(err.get("msg", ""))
        for prefix in ("Value error, ", "Assertion failed, "):
            if msg.startswith(prefix):
                msg = msg[len(prefix):]
        typ = err.get("type", "")
        if typ == "extra_forbidden":
            parent = loc[:-1]
            msg = f"unknown field {loc[-1]!r}" + _known_fields_hint(parent)
        elif typ == "missing":
            msg = "required field is missing"
        elif "input" in err and typ not in ("value_error", "assertion_error") and not isinstance(err["input"], dict):
            msg += f" (got {err['input']!r})"
        msgs.append((format_json_path(loc), msg))
    path, msg = msgs[0]
    extra = "".join(f"\n  {display}: {p + ': ' if p else ''}{m}" for p, m in msgs[1:])
    return InputError(msg + extra, file=display, path=path or None)


def _known_fields_hint(parent: Sequence) -> str:
    model: Any = ExperimentConfig
    for p in parent:
        if isinstance(p, int):
            continue
        f = getattr(model, "model_fields", {}).get(p)
        if f is None:
            return ""
        ann = f.annotation
        args = getattr(ann, "__args__", ()) or ()
        cand = [ann, *args, *[a2 for a in args for a2 in (getattr(a, "__args__", ()) or ())]]
        model = next((c for c in cand if isinstance(c, type) and issubclass(c, BaseModel)), None)
        if model is None:
            return ""
    names = list(getattr(model, "model_fields", {}))
    return f" (known: {', '.join(names)})" if names else ""


def parse_config(data: Any, display: str) -> ExperimentConfig:
    if data is None:
        raise InputError("the config is empty", file=display)
    if not isinstance(data, dict):
        raise InputError(f"a config must be a YAML mapping (key: value), got {type(data).__name__}", file=display)
    try:
        return ExperimentConfig.model_validate(data)
    except ValidationError as e:
        raise _format_pydantic(e, display) from None


def load_config(path, display: Optional[str] = None) -> Tuple[ExperimentConfig, str]:
    """Read and validate a config file. Returns (config, the YAML text)."""
    p = Path(path)
    display = display or str(path)
    if not p.is_file():
        raise InputError("no such config file", file=display)
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"cannot read the config: {e}", file=display) from None
    return parse_config(read_yaml(text, display), display), text


# ------------------------------------------------------------------------------------------------
# resolution
# ------------------------------------------------------------------------------------------------
@dataclass
class ProblemEntry:
    """One named problem of an experiment (a task entry or benchmark ID with its cost, rules and base
    search): the :class:`~robodesign.design.problem.Problem` every run of it optimizes, built once."""
    name: str
    problem: Problem
    base_search: bool
    where: str             # config path of the entry, for messages
    suite: Optional[str] = None  # the suite (task family) the task belongs to

    @property
    def task_id(self) -> str:
        return self.problem.task.id

    @property
    def cost(self) -> str:
        return self.problem.cost_descriptor

    def evaluator_spec(self, seed: int, solve: SolveSettings):
        from robodesign.design.evaluator import EvaluatorSpec
        return EvaluatorSpec(self.problem, settings=solve, seed=int(seed))

    def to_json(self) -> dict:
        p = self.problem
        return {"name": self.name, "task_id": p.task.id, "task": p.task_ref, "modules": p.modules_ref,
                "module_set": p.module_set.name, "cost": p.cost_descriptor, "rules": p.rules(),
                "base_search": self.base_search, "suite": self.suite, "base_bounds": p.to_json()["base_bounds"],
                "fingerprint": p.fingerprint()}


@dataclass
class OptimizerRun:
    label: str
    name: str
    options: Dict[str, Any]
    budget: Budget
    budget_text: str
    batch_size: int


@dataclass
class RunSpec:
    problem: ProblemEntry
    optimizer: OptimizerRun
    seed: int

    @property
    def run_id(self) -> str:
        return run_id(self.problem.name, self.optimizer.label, self.seed)


def run_id(problem: str, optimizer: str, seed: int) -> str:
    return f"{problem}|{optimizer}|{seed}"


@dataclass
class ResolvedExperiment:
    config: ExperimentConfig
    name: str
    file: str               # display name of the config file
    base_dir: Path          # relative paths were resolved against this folder
    problems: List[ProblemEntry]
    optimizers: List[OptimizerRun]
    seeds: List[int]
    solve: SolveSettings
    executor: ExecutorConfig

    def runs(self) -> Iterator[RunSpec]:
        """Every run, in a fixed order: problem, then optimizer, then seed."""
        for p in self.problems:
            for o in self.optimizers:
                for s in self.seeds:
                    yield RunSpec(p, o, s)

    def eval_seed(self, run_seed: int) -> int:
        return self.config.eval_seed if self.config.eval_seed is not None else int(run_seed)

    def spec_id(self, problem: ProblemEntry, run_seed: int) -> str:
        return f"{problem.name}#{self.eval_seed(run_seed)}"

    def evaluator_specs(self) -> Dict[str, Any]:
        """spec id → EvaluatorSpec of every (problem, evaluation seed) the runs need."""
        out = {}
        for r in self.runs():
            sid = self.spec_id(r.problem, r.seed)
            if sid not in out:
                out[sid] = r.problem.evaluator_spec(self.eval_seed(r.seed), self.solve)
        return out


def _search_dirs(dirs: List[str], base: Path, display: str, key: str) -> List[Path]:
    out = []
    for i, d in enumerate(dirs):
        p = (base / d).resolve() if not Path(d).is_absolute() else Path(d)
        if not p.is_dir():
            raise InputError(f"no such folder {d!r} (resolved to {p})", file=display, path=[key, i])
        out.append(p)
    return out


def _find_task(ref: str, base: Path, task_dirs: List[Path], display: str, path) -> Tuple[str, Path]:
    """→ (reference for load_task, file). Order: a path relative to the config folder, task_dirs, built-in."""
    from robodesign.core.paths import builtin_tasks_dir
    cand = Path(ref)
    tried = []
    if cand.is_absolute() or ref.endswith(".json") or ref.startswith("."):
        p = cand if cand.is_absolute() else (base / cand)
        for q in (p, Path(str(p) + ".json")):
            if q.is_file():
                return str(q.resolve()), q.resolve()
        tried.append(str(p))
    name = ref[:-5] if ref.endswith(".json") else ref
    for d in task_dirs:
        q = d / f"{name}.json"
        if q.is_file():
            return str(q.resolve()), q.resolve()
        tried.append(str(q))
    q = builtin_tasks_dir() / f"{name}.json"
    if q.is_file():
        return name, q  # built-in: pass the ID (portable to other machines)
    tried.append(f"built-in {q}")
    raise InputError(f"no such task file or task ID {ref!r} (looked for: {', '.join(tried)})",
                     file=display, path=path)


def _find_modules(ref: str, base: Path, module_dirs: List[Path], display: str, path) -> str:
    from robodesign.core.paths import builtin_module_sets
    cand = Path(ref)
    tried = []
    if cand.is_absolute() or "/" in ref or ref.startswith("."):
        p = cand if cand.is_absolute() else (base / cand).resolve()
        if (p / "modules.json").is_file() or (p.is_file() and p.suffix == ".json"):
            return str(p)
        tried.append(str(p))
    for d in module_dirs:
        q = d / ref
        if (q / "modules.json").is_file():
            return str(q.resolve())
        tried.append(str(q))
    if ref in builtin_module_sets():
        return ref
    tried.append(f"built-in ({', '.join(builtin_module_sets()) or 'none'})")
    raise InputError(f"no such module set {ref!r} (looked for: {', '.join(tried)})", file=display, path=path)


SUITE_MANIFEST = ".suite.json"  # in a generated suite's folder: what was generated there, and the files


def suite_task_files(su: SuiteEntry, base: Path, display: str, where: list) -> List[Path]:
    """The task files of a suite. A plain folder: its ``*.json`` files, sorted. With ``generate``, the
    folder (default ``generated/<name>`` beside the config) holds exactly what those generator calls write,
    in call order: generated on first use (the generators are deterministic, so a folder cut short by a
    kill is completed with identical bytes) and recorded in ``.suite.json`` with the generators' versions;
    a folder generated with other arguments or by another generator version is an error, never
    overwritten."""
    import json
    folder = Path(su.folder or f"generated/{su.name}")
    folder = folder if folder.is_absolute() else (base / folder).resolve()
    if su.generate is None:
        if not folder.is_dir():
            raise InputError(f"no such folder {su.folder!r} (resolved to {folder})", file=display,
                             path=where + ["folder"])
        files = sorted(p for p in folder.glob("*.json") if not p.name.startswith("."))
        if not files:
            raise InputError(f"no task files (*.json) in {folder}", file=display, path=where + ["folder"])
        return files
    from robodesign.generate import get_family
    want = [g.model_dump() for g in su.generate]
    versions = {g.family: get_family(g.family).version for g in su.generate}
    manifest = folder / SUITE_MANIFEST
    if manifest.is_file():
        try:
            have = json.loads(manifest.read_text())
        except ValueError as e:
            raise InputError(f"unreadable {manifest}: {e}", file=display, path=where + ["folder"]) from None
        if have.get("generate") != want:
            raise InputError(f"{folder} holds tasks generated with other arguments ({have.get('generate')}): delete "
                             "it or give the suite another folder", file=display, path=where + ["generate"])
        old = {f: v for f, v in (have.get("versions") or {}).items() if versions.get(f) != v}
        if old:  # (a manifest written before versions were recorded names none: its folder is taken as it is)
            raise InputError(f"{folder} holds tasks of other generator versions "
                             f"({', '.join(f'{f} v{v}, now v{versions.get(f)}' for f, v in sorted(old.items()))}): "
                             "delete it or give the suite another folder", file=display, path=where + ["generate"])
        files = [folder / n for n in have.get("files", [])]
        if files and all(p.is_file() for p in files):
            return files
    from robodesign.generate import generate
    files = []
    for k, g in enumerate(su.generate):
        options = dict(g.options)
        for name, v in options.items():  # a file option (e.g. liu2020 machine) is relative to the config file
            if v is not None and get_family(g.family).option(name).path and not Path(str(v)).is_absolute():
                options[name] = str((base / str(v)).resolve())
        try:
            files += generate(g.family, folder, count=g.count, seed=g.seed, options=options)
        except InputError as e:
            raise InputError(str(e), file=display, path=where + ["generate", k]) from None
    if len({p.name for p in files}) != len(files):
        raise InputError("two generate blocks write the same task file: give them different options or seeds",
                         file=display, path=where + ["generate"])
    tmp = manifest.with_name(manifest.name + ".tmp")
    tmp.write_text(json.dumps({"generate": want, "versions": versions, "files": [p.name for p in files]}, indent=1))
    tmp.replace(manifest)
    return files


def _slug(s: str) -> str:
    return re.sub(r"[^A-Za-z0-9_./+\-]+", "_", s)


def resolve_config(cfg: ExperimentConfig, display: str, base_dir: Path, check_optimizers: bool = True,
                   default_name: Optional[str] = None) -> ResolvedExperiment:
    """Resolve tasks, module sets and optimizers; load each task and module set once (parse errors
    surface here), build each problem once and instantiate each optimizer with its options on the first
    problem."""
    base_dir = Path(base_dir)
    raw = _raw_entries(cfg, display, base_dir)
    tasks, sets = _load_files(raw, display)
    problems = _build_problems(raw, tasks, sets, display)

    # optimizers
    opts: List[OptimizerRun] = []
    for i, o in enumerate(cfg.optimizers):
        budget_text = o.budget or cfg.budget
        opts.append(OptimizerRun(label=o.key, name=o.name, options=dict(o.options), budget=Budget.parse(budget_text),
                                 budget_text=budget_text, batch_size=o.batch_size or cfg.batch_size))
        if check_optimizers:
            check_optimizer(o.name, o.options, problems[0].problem, display, ["optimizers", i])

    solve = SolveSettings(**cfg.solve.model_dump())
    check_settings(solve, file=display, path=["solve"])
    name = cfg.name or default_name or Path(display).stem
    return ResolvedExperiment(config=cfg, name=name, file=display, base_dir=base_dir, problems=problems,
                              optimizers=opts, seeds=list(cfg.seeds), solve=solve, executor=cfg.executor)


def _raw_entries(cfg: ExperimentConfig, display: str, base_dir: Path) -> List[dict]:
    """One dict per (entry, cost) of the tasks, benchmarks and suites, in that order, with its task and module
    set references resolved (files not loaded yet)."""
    from robodesign.core.paths import DEFAULT_MODULE_SET
    from robodesign.formats.benchmark_id import BenchmarkID

    task_dirs = _search_dirs(cfg.task_dirs, base_dir, display, "task_dirs")
    module_dirs = _search_dirs(cfg.module_dirs, base_dir, display, "module_dirs")
    default_modules = cfg.modules or DEFAULT_MODULE_SET

    raw: List[dict] = []
    for i, t in enumerate(cfg.tasks):
        where: List[PathPart] = ["tasks", i]
        task_ref, _ = _find_task(t.task, base_dir, task_dirs, display, where + ["task"])
        mod_path = where + ["modules"] if t.modules else ["modules"]
        modules_ref = _find_modules(t.modules or default_modules, base_dir, module_dirs, display, mod_path)
        for cost in (t.cost or cfg.cost):
            raw.append(dict(entry=t, where=where, task_ref=task_ref, modules_ref=modules_ref, cost=cost,
                            rules=cfg.rules.merged(t.rules), base_search=cfg.base_search if t.base_search is None
                            else t.base_search, name=t.name, n_costs=len(t.cost or cfg.cost)))
    for i, b in enumerate(cfg.benchmarks):
        where = ["benchmarks", i]
        bid = BenchmarkID.parse(b.id)
        task_ref, _ = _find_task(bid.task, base_dir, task_dirs, display, where + ["id"])
        modules_ref = _find_modules(bid.robot.robots[0].name, base_dir, module_dirs, display, where + ["id"])
        cost = b.id.split(":")[1].strip()
        raw.append(dict(entry=b, where=where, task_ref=task_ref, modules_ref=modules_ref, cost=cost,
                        rules=cfg.rules.merged(b.rules), base_search=cfg.base_search if b.base_search is None
                        else b.base_search, name=b.name, n_costs=1))

    for i, su in enumerate(cfg.suites):
        where = ["suites", i]
        mod_path = where + ["modules"] if su.modules else ["modules"]
        modules_ref = _find_modules(su.modules or default_modules, base_dir, module_dirs, display, mod_path)
        for f in suite_task_files(su, base_dir, display, where):
            for cost in (su.cost or cfg.cost):
                n_costs = len(su.cost or cfg.cost)
                raw.append(dict(entry=su, where=where, task_ref=str(f), modules_ref=modules_ref, cost=cost,
                                rules=cfg.rules.merged(su.rules), base_search=cfg.base_search if su.base_search is None
                                else su.base_search, name=f"{su.name}/{f.stem}", n_costs=n_costs, suite=su.name))
    return raw


def _load_files(raw: List[dict], display: str) -> Tuple[Dict[str, Any], Dict[str, Any]]:
    """Load every task and module set once: file errors name the file and field. → (tasks, module sets) by
    reference; sets each entry's ``task_id`` and ``ms_name``."""
    from robodesign.formats.module_io import load_module_set
    from robodesign.formats.task_io import load_task

    tasks: Dict[str, Any] = {}
    sets: Dict[str, Any] = {}
    for r in raw:
        try:
            if r["task_ref"] not in tasks:
                tasks[r["task_ref"]] = load_task(r["task_ref"])
            if r["modules_ref"] not in sets:
                sets[r["modules_ref"]] = load_module_set(r["modules_ref"])
        except InputError as e:
            raise InputError(f"{e}", file=display, path=r["where"]) from None
    for r in raw:
        r["task_id"] = tasks[r["task_ref"]].id
        r["ms_name"] = sets[r["modules_ref"]].name
    return tasks, sets


def _problem_name(r: dict, raw: List[dict]) -> str:
    """The entry's name, else its task ID disambiguated by cost / module set / base search when several entries
    share it."""
    if r["name"]:
        name = r["name"] if r["n_costs"] == 1 else f"{r['name']}-{r['cost']}"
    else:
        same = [o for o in raw if o["task_id"] == r["task_id"]]
        name = r["task_id"]
        if len({o["cost"] for o in same}) > 1:
            name += f"-{r['cost']}"
        if len({o["modules_ref"] for o in same}) > 1:
            name += f"-{r['ms_name']}"
        if len({o["base_search"] for o in same}) > 1 and not r["base_search"]:
            name += "-fixed_base"
    return _slug(name).strip("/")


def _build_problems(raw: List[dict], tasks: Dict[str, Any], sets: Dict[str, Any], display: str) -> List[ProblemEntry]:
    """One named :class:`ProblemEntry` per raw entry; two entries of the same name are an error."""
    problems: List[ProblemEntry] = []
    for r in raw:
        name = _problem_name(r, raw)
        where_text = format_json_path(r["where"])
        for p in problems:
            if p.name == name:
                raise InputError(f"two entries resolve to the same run name {name!r} ({p.where} and {where_text}): "
                                 "give one of them a distinct 'name'", file=display, path=where_text)
        rules_path = list(r["where"]) + ["rules"] if r["entry"].rules is not None else ["rules"]
        try:
            problem = Problem.build(tasks[r["task_ref"]], sets[r["modules_ref"]], r["cost"],
                                    rules=r["rules"].model_dump(), base_search=bool(r["base_search"]))
        except InputError as e:  # a rule naming a module that is not in the set (or not of that kind)
            path = e.json_path.removeprefix("rules").lstrip(".")
            raise InputError(e.reason, file=display, path=format_json_path(rules_path) + (f".{path}" if path else "")
                             ) from None
        problem = dataclasses.replace(problem, task_ref=r["task_ref"], modules_ref=r["modules_ref"])
        problems.append(ProblemEntry(name=name, problem=problem, base_search=bool(r["base_search"]), where=where_text,
                                     suite=r.get("suite")))
    return problems


def check_optimizer(name: str, options: dict, problem: Problem, display: str, path: list) -> None:
    """Instantiate optimizer ``name`` with ``options`` once, so that an unknown plugin or a bad option is an
    error naming the config file and field before anything runs."""
    from robodesign.design.optimize import OptionError, available_optimizers, create_optimizer, load_optimizer
    if name not in available_optimizers():
        known = ", ".join(sorted(available_optimizers())) or "none installed"
        raise InputError(f"unknown optimizer {name!r} (installed: {known})", file=display, path=path + ["name"])
    try:
        cls = load_optimizer(name)
    except InputError as e:
        raise InputError(e.reason, file=display, path=path + ["name"]) from None
    except (ImportError, AttributeError, SyntaxError) as e:  # a registered plugin that cannot be imported
        raise InputError(f"optimizer {name!r} is registered but cannot be loaded: {type(e).__name__}: {e}",
                         file=display, path=path + ["name"]) from None
    try:
        create_optimizer(cls, problem, seed=0, options=options)
    except OptionError as e:
        raise InputError(e.reason, file=display, path=path + ["options", e.option]) from None
    except InputError as e:
        raise InputError(e.reason, file=display, path=path + ["options"]) from None


def load_experiment(path, display: Optional[str] = None, base_dir: Optional[Path] = None,
                    default_name: Optional[str] = None) -> Tuple[ResolvedExperiment, str]:
    """load_config + resolve_config. Returns (experiment, YAML text)."""
    cfg, text = load_config(path, display)
    disp = display or str(path)
    exp = resolve_config(cfg, disp, base_dir or Path(path).resolve().parent, default_name=default_name)
    return exp, text
