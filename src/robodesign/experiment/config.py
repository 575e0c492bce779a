"""Experiment configs: YAML → validated :class:`ExperimentConfig` → :class:`ResolvedExperiment`.

Two steps, both with errors that name the file and the field (``configs/x.yaml: optimizers[1].budget:
budget '5x': use e.g. 500evals, ...``), raised as :class:`robodesign.core.errors.InputError` (CLI exit code 2):

1. :func:`load_config` reads the YAML (syntax errors with line/column, duplicate keys rejected) and
   validates its *shape* with pydantic (unknown fields, types, ranges, budgets, costs, benchmark IDs).
2. :func:`resolve_config` resolves what the config names: task files, module sets, optimizer plugins
   (loaded and instantiated once with their options), rules against the module set. Relative paths are
   relative to the folder of the config file.

The reference of every field is docs/experiments.md.
"""
from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Dict, Iterator, List, Literal, Optional, Sequence, Tuple

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, create_model, field_validator, model_validator

from robodesign.core.errors import InputError, PathPart, format_json_path
from robodesign.design.optimize import Budget
from robodesign.design.problem import Problem
from robodesign.design.solve import SolveSettings, check_settings

DEFAULT_BUDGET = "50evals"
EXECUTORS = ("serial", "process", "ray")


# ------------------------------------------------------------------------------------------------
# YAML
# ------------------------------------------------------------------------------------------------
class _UniqueKeyLoader(yaml.SafeLoader):
    """SafeLoader that rejects duplicate mapping keys (PyYAML silently keeps the last one)."""


def _construct_mapping(loader, node, deep=False):
    loader.flatten_mapping(node)
    seen = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        if key in seen:
            m = key_node.start_mark
            raise yaml.constructor.ConstructorError(
                None, None, f"duplicate key {key!r} (first at line {seen[key] + 1})", m)
        seen[key] = key_node.start_mark.line
    return yaml.SafeLoader.construct_mapping(loader, node, deep)


_UniqueKeyLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)


MAX_YAML_NODES = 100_000
"""Most values a config may hold once its aliases (``*name``) are expanded: an "alias bomb" (each level repeating the
one before ten times) is refused before it is built instead of taking minutes and gigabytes."""


def _expanded_size(root) -> int:
    """Nodes of the YAML node graph ``root`` with every alias expanded (aliases share node objects), counted
    without expanding: each distinct node once, memoised, iteratively; capped at MAX_YAML_NODES + 1 (also for a
    node that contains itself)."""
    cap = MAX_YAML_NODES + 1
    sizes: Dict[int, int] = {}
    open_: set = set()
    stack = [(root, False)]
    while stack:
        node, done = stack.pop()
        if isinstance(node, yaml.SequenceNode):
            kids = list(node.value)
        elif isinstance(node, yaml.MappingNode):
            kids = [x for pair in node.value for x in pair]
        else:
            sizes[id(node)] = 1
            continue
        if done:
            open_.discard(id(node))
            sizes[id(node)] = min(cap, 1 + sum(sizes[id(k)] for k in kids))
            continue
        if id(node) in sizes:
            continue
        if any(id(k) in open_ or k is node for k in kids):
            return cap  # recursive: infinite once expanded
        open_.add(id(node))
        stack.append((node, True))
        stack.extend((k, False) for k in kids if id(k) not in sizes)
    return sizes[id(root)]


def _load_yaml(text: str, display: str) -> Any:
    loader = _UniqueKeyLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        n = _expanded_size(node)
        if n > MAX_YAML_NODES:
            raise InputError(f"the YAML holds more than {MAX_YAML_NODES} values once its aliases (*name) are "
                             "expanded; write the values out or use fewer aliases", file=display)
        return loader.construct_document(node)
    finally:
        loader.dispose()


def read_yaml(text: str, display: str) -> Any:
    from robodesign.core.jsonio import MAX_DEPTH, check_values
    try:
        return check_values(_load_yaml(text, display), display)
    except RecursionError:
        raise InputError(f"YAML nested deeper than {MAX_DEPTH} levels", file=display) from None
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
        what = " ".join(x for x in (e.context, e.problem) if x) or str(e)
        raise InputError(f"{where}invalid YAML: {what}", file=display) from None
    except yaml.YAMLError as e:
        raise InputError(f"invalid YAML: {e}", file=display) from None


# ------------------------------------------------------------------------------------------------
# schema
# ------------------------------------------------------------------------------------------------
_STRICT = ConfigDict(extra="forbid", str_strip_whitespace=True)


def _budget_text(v):
    if v is None:
        return v
    if isinstance(v, bool):
        raise ValueError(f"expected a budget such as 500evals or 60s, got {v!r}")
    if isinstance(v, (int, float)):
        v = str(v)
    if not isinstance(v, str):
        raise ValueError(f"expected a budget such as 500evals, 60s or 500evals,60s, got {v!r}")
    Budget.parse(v)  # raises InputError (a ValueError) with the reason
    return v


def _str_list(v, what="name"):
    if v is None:
        return v
    if isinstance(v, (str, int)) and not isinstance(v, bool):
        return [str(v)]
    if isinstance(v, list):
        return [str(x) if isinstance(x, int) and not isinstance(x, bool) else x for x in v]
    return v


def _plain_name(v, what: str, note: str = ""):
    """``v`` (a name or label that names results, or None) when it holds only letters, digits, '_', '.', '+', '-'."""
    if v is not None and not re.fullmatch(r"[A-Za-z0-9_.+\-]+", v):
        raise ValueError(f"{what} {v!r}: use letters, digits, '_', '.', '+', '-' only{note}")
    return v


def _entry_list(v, key: str):
    """A list of entries given as one or a list, where a bare string ``s`` stands for ``{key: s}``."""
    if isinstance(v, str):
        v = [v]
    if isinstance(v, list):
        return [{key: x} if isinstance(x, str) else x for x in v]
    return v


def _check_cost(v: str) -> str:
    from robodesign.formats.costs import parse_cost
    c = parse_cost(v)
    if c.is_empty:
        raise ValueError("empty cost function")
    return v


class Rules(BaseModel):
    """Search-space rules (``SearchSpace``): DoF range, passive links between joints, allowed modules."""
    model_config = _STRICT
    min_dof: Optional[int] = Field(None, ge=1)  # None: the task's (design.problem.default_dof)
    max_dof: Optional[int] = Field(None, ge=1)
    max_links_between: int = Field(1, ge=0)
    max_modules: int = Field(16, ge=2)
    bases: Optional[List[str]] = None
    end_effectors: Optional[List[str]] = None
    exclude: List[str] = Field(default_factory=list)

    @model_validator(mode="before")
    @classmethod
    def _dof(cls, data):
        if isinstance(data, dict) and "dof" in data:
            data = dict(data)
            d = data.pop("dof")
            if isinstance(d, list) and len(d) == 2:
                data.setdefault("min_dof", d[0])
                data.setdefault("max_dof", d[1])
            elif isinstance(d, int) and not isinstance(d, bool):
                data.setdefault("min_dof", d)
                data.setdefault("max_dof", d)
            else:
                raise ValueError(f"dof: expected a number or [min, max], got {d!r}")
        return data

    _lists = field_validator("bases", "end_effectors", "exclude", mode="before")(classmethod(
        lambda cls, v: _str_list(v)))

    @model_validator(mode="after")
    def _range(self):
        if self.min_dof is not None and self.max_dof is not None and self.min_dof > self.max_dof:
            raise ValueError(f"min_dof ({self.min_dof}) is larger than max_dof ({self.max_dof})")
        return self

    def merged(self, override: Optional["Rules"]) -> "Rules":
        if override is None:
            return self
        return self.model_copy(update={k: getattr(override, k) for k in override.model_fields_set})


class _Overrides(BaseModel):
    """What a task or suite entry may set for itself instead of the config's values."""
    model_config = _STRICT
    modules: Optional[str] = None
    cost: Optional[List[str]] = None
    rules: Optional[Rules] = None
    base_search: Optional[bool] = None

    _c = field_validator("cost", mode="before")(classmethod(lambda cls, v: _str_list(v)))

    @field_validator("cost")
    @classmethod
    def _costs(cls, v):
        if v is not None:
            if not v:
                raise ValueError("give at least one cost")
            for c in v:
                _check_cost(c)
        return v


class TaskEntry(_Overrides):
    """One task: a task ID (searched in ``task_dirs`` then the built-in tasks) or a task file."""
    task: str
    name: Optional[str] = None


class SuiteGenerate(BaseModel):
    """How a suite's tasks are generated (``robodesign generate FAMILY``) when its folder lacks them."""
    model_config = _STRICT
    family: str
    count: int = Field(ge=1)
    seed: int = Field(0, ge=0)
    options: Dict[str, Any] = Field(default_factory=dict)

    @model_validator(mode="after")
    def _known(self):
        from robodesign.generate import get_family
        get_family(self.family).resolve(dict(self.options))  # unknown family or option, bad value: InputError
        return self


class SuiteEntry(_Overrides):
    """A task suite: every task file of a folder (generated there first from ``generate`` when missing),
    summarized together in the report (solved share, best costs, time to the first feasible design)."""
    name: str
    folder: Optional[str] = None
    generate: Optional[List[SuiteGenerate]] = None  # one block or a list (e.g. several structures of a family)

    @field_validator("generate", mode="before")
    @classmethod
    def _one_or_list(cls, v):
        return [v] if isinstance(v, dict) else v

    _name = field_validator("name")(classmethod(lambda cls, v: _plain_name(v, "name", " (it prefixes the task names)")))

    @model_validator(mode="after")
    def _where(self):
        if self.folder is None and self.generate is None:
            raise ValueError("give the suite a 'folder' of task files, a 'generate' block, or both")
        return self


class BenchmarkEntry(BaseModel):
    """A CoBRA benchmark ID ``Robot:Cost:Task`` (robot = the module set to optimise)."""
    model_config = _STRICT
    id: str
    name: Optional[str] = None
    rules: Optional[Rules] = None
    base_search: Optional[bool] = None

    @field_validator("id")
    @classmethod
    def _bid(cls, v):
        from robodesign.formats.benchmark_id import BenchmarkID
        bid = BenchmarkID.parse(v)
        if bid.is_collaborative or bid.robot.robots[0].kind != "module_set":
            raise ValueError(f"benchmark ID {v!r}: only module-set robots (Name or M-Name) can be optimised")
        return v


class OptimizerEntry(BaseModel):
    model_config = _STRICT
    name: str
    label: Optional[str] = None
    options: Dict[str, Any] = Field(default_factory=dict)
    budget: Optional[str] = None
    batch_size: Optional[int] = Field(None, ge=1)

    _b = field_validator("budget", mode="before")(classmethod(lambda cls, v: _budget_text(v)))

    _label = field_validator("label")(classmethod(lambda cls, v: _plain_name(v, "label")))

    @property
    def key(self) -> str:
        return self.label or self.name


class ExecutorConfig(BaseModel):
    model_config = _STRICT
    kind: Literal["serial", "process", "ray"] = "serial"
    workers: Optional[int] = Field(None, ge=1)
    address: Optional[str] = None
    chunk_size: Optional[int] = Field(None, ge=1)  # process and ray executors: candidates per message (None: automatic)


def _solve_model():
    from robodesign.design.evaluator import evaluation_settings
    defaults = dataclasses.asdict(evaluation_settings())  # the same defaults as the optimize CLI and the API
    fields = {f.name: (type(f.default) if f.default is not None else Any, defaults[f.name])
              for f in dataclasses.fields(SolveSettings) if f.name != "seed"}  # seeds: per candidate (the evaluator)
    return create_model("SolveConfig", __config__=_STRICT, **fields)


if TYPE_CHECKING:  # a model class made at import from SolveSettings' fields
    SolveConfig = BaseModel
else:
    SolveConfig = _solve_model()


class ExperimentConfig(BaseModel):
    """The whole config file (docs/experiments.md)."""
    model_config = _STRICT
    name: Optional[str] = None
    description: str = ""
    task_dirs: List[str] = Field(default_factory=list)
    module_dirs: List[str] = Field(default_factory=list)
    modules: Optional[str] = None
    cost: List[str] = Field(default_factory=lambda: ["cyc"])
    rules: Rules = Field(default_factory=Rules)
    base_search: bool = True
    tasks: List[TaskEntry] = Field(default_factory=list)
    benchmarks: List[BenchmarkEntry] = Field(default_factory=list)
    suites: List[SuiteEntry] = Field(default_factory=list)
    optimizers: List[OptimizerEntry] = Field(min_length=1)
    budget: str = DEFAULT_BUDGET
    seeds: List[int] = Field(default_factory=lambda: [0], min_length=1)
    eval_seed: Optional[int] = Field(None, ge=0)
    batch_size: int = Field(1, ge=1)
    executor: ExecutorConfig = Field(default_factory=ExecutorConfig)
    solve: SolveConfig = Field(default_factory=SolveConfig)

    _b = field_validator("budget", mode="before")(classmethod(lambda cls, v: _budget_text(v)))
    _c = field_validator("cost", "task_dirs", "module_dirs", mode="before")(classmethod(lambda cls, v: _str_list(v)))

    @field_validator("cost")
    @classmethod
    def _costs(cls, v):
        if not v:
            raise ValueError("give at least one cost")
        for c in v:
            _check_cost(c)
        return v

    _name = field_validator("name")(classmethod(lambda cls, v: _plain_name(v, "name", " (it names the results folder)")))

    _tasks = field_validator("tasks", mode="before")(classmethod(lambda cls, v: _entry_list(v, "task")))
    _benchmarks = field_validator("benchmarks", mode="before")(classmethod(lambda cls, v: _entry_list(v, "id")))
    _optimizers = field_validator("optimizers", mode="before")(classmethod(lambda cls, v: _entry_list(v, "name")))

    @field_validator("executor", mode="before")
    @classmethod
    def _executor(cls, v):
        return {"kind": v} if isinstance(v, str) else v

    @field_validator("seeds", mode="before")
    @classmethod
    def _seeds(cls, v):
        if isinstance(v, int) and not isinstance(v, bool):
            return [v]
        return v

    @field_validator("seeds")
    @classmethod
    def _seeds_unique(cls, v):
        if any(s < 0 for s in v):
            raise ValueError("seeds must be non-negative integers")
        if len(set(v)) != len(v):
            raise ValueError(f"seeds must be distinct, got {v}")
        return v

    @model_validator(mode="after")
    def _something_to_do(self):
        if not self.tasks and not self.benchmarks and not self.suites:
            raise ValueError("give at least one entry in 'tasks', 'benchmarks' or 'suites'")
        names = [x.name for x in self.suites]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"suite {dup[0]!r} is listed twice: give the suites distinct names")
        keys = [o.key for o in self.optimizers]
        dup = sorted({k for k in keys if keys.count(k) > 1})
        if dup:
            raise ValueError(f"optimizer {dup[0]!r} is listed twice: give the entries distinct 'label's")
        return self


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
    from robodesign.core.paths import DEFAULT_MODULE_SET
    from robodesign.formats.module_io import load_module_set
    from robodesign.formats.task_io import load_task

    base_dir = Path(base_dir)
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
        from robodesign.formats.benchmark_id import BenchmarkID
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

    # load every task and module set once: file errors name the file and field
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

    # names: the task ID; disambiguated by cost / module set / base search when several entries share it
    for r in raw:
        r["task_id"] = tasks[r["task_ref"]].id
        r["ms_name"] = sets[r["modules_ref"]].name
    problems: List[ProblemEntry] = []
    for r in raw:
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
        name = _slug(name).strip("/")
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
