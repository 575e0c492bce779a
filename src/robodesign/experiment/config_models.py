"""The experiment config's schema: YAML reading (duplicate keys and alias bombs refused) and the pydantic models
of the config file, validated for their shape. :mod:`.config` loads a file into them and resolves what they name."""
from __future__ import annotations

import dataclasses
import re
from typing import TYPE_CHECKING, Any, Dict, List, Literal, Optional

import yaml
from pydantic import BaseModel, ConfigDict, Field, create_model, field_validator, model_validator

from robodesign.core.errors import InputError
from robodesign.design.optimize import Budget
from robodesign.design.solve import SolveSettings

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
