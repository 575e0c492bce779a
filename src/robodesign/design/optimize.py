"""The optimizer plugin API and the study loop.

Writing an optimizer (docs/plugins.md; everything a plugin uses is importable from this module, see
``__all__``): subclass :class:`Optimizer`, implement ``ask()`` (return the
next :class:`Candidate`, or ``None`` when the optimizer has nothing left to propose) and optionally
``tell(evaluation)``, declare its options as a dataclass ``Options`` of :func:`option` fields; register
the class under the entry-point group ``robodesign.optimizers``. The optimizer sees the
:class:`~robodesign.design.problem.Problem` (``self.problem``: task, module set, cost ``self.cost``, search
space ``self.space``), its validated ``self.options`` and its own seeded ``self.rng``; the
:class:`Study` owns the loop, the budget, the evaluator, the executor and the storage.
:func:`create_optimizer` builds a plugin by name (a plugin written against the removed
``Optimizer(space, seed, **options)`` API is refused with a message saying how to port it).

Determinism: the study asks ``batch_size`` candidates, evaluates them (in parallel or not), and
tells the results *in ask order*; evaluations are pure functions of the candidate. The same seed
and batch size therefore give the same run on any executor, and a run can be resumed by replaying
stored evaluations. An optimizer whose ``ask()`` never depends on what it was told (class attribute
``independent_asks = True``, e.g. random search) asks the same candidates whenever the tells arrive: on an
executor that streams (``imap``, the process pool) the study then asks ahead of the evaluations, so the
workers never wait at the end of a batch for its slowest candidate; the results are the same.
"""
from __future__ import annotations

import difflib
import inspect
import math
import re
import time
from abc import ABC, abstractmethod
from dataclasses import MISSING, dataclass, field, fields, is_dataclass
from importlib import metadata
from typing import (
    Any,
    Callable,
    ClassVar,
    Dict,
    Iterable,
    Iterator,
    List,
    Mapping,
    Optional,
    Sequence,
    Type,
    Union,
    cast,
    get_args,
    get_origin,
    get_type_hints,
)

import numpy as np

from robodesign.core.errors import InputError
from robodesign.core.gc_heap import startup_heap_frozen
from robodesign.design.evaluator import Evaluation
from robodesign.design.problem import Problem
from robodesign.design.search_space import BASE_PARAMS, Candidate, SearchSpace
from robodesign.design.solve import STAGES
from robodesign.formats.costs import CostFunction

#: everything an optimizer plugin needs, importable from this module
__all__ = ["Optimizer", "option", "OptionError", "Problem", "SearchSpace", "Candidate", "Evaluation", "STAGES",
           "BASE_PARAMS", "create_optimizer", "load_optimizer", "available_optimizers", "option_specs",
           "parse_options", "optimize", "Budget", "Study", "StudyResult", "SerialExecutor"]

ENTRY_POINT_GROUP = "robodesign.optimizers"


class Optimizer(ABC):
    """Base class of optimizer plugins.

    ``problem`` is the :class:`~robodesign.design.problem.Problem` (``self.problem``; its search space is also
    ``self.space`` and its cost ``self.cost``). ``options`` come from the CLI (``--opt key=value``) or a
    config; a plugin declares them as a dataclass ``Options`` (fields made with :func:`option`), and the
    base class validates and converts them into ``self.options`` (an ``Options`` instance): an unknown
    option or a bad value raises :class:`OptionError` naming the valid options.
    """

    name: str = ""
    description: str = ""
    #: the plugin's options: a dataclass whose fields (made with :func:`option`) are name, type, default,
    #: range or choices and help. None: the plugin takes no options.
    Options: ClassVar[Optional[type]] = None
    #: True promises that ``ask()`` never depends on the evaluations told (random search): the study may
    #: then ask ahead of them and keep parallel workers busy across batches, with the same results
    independent_asks: ClassVar[bool] = False

    def __init__(self, problem: Problem, seed: int = 0, **options):
        if not isinstance(problem, Problem):
            raise TypeError(f"optimizer {type(self).__name__}: Optimizer(...) takes a "
                            f"robodesign.design.problem.Problem, got {type(problem).__name__} (docs/plugins.md)")
        self.problem: Problem = problem
        self.space = problem.space
        #: the cost function the study evaluates
        self.cost: CostFunction = problem.cost
        self.seed = int(seed)
        self.rng = np.random.default_rng(self.seed)
        self.options = parse_options(type(self), options)
        self.history: List[Evaluation] = []
        self.best: Optional[Evaluation] = None

    @abstractmethod
    def ask(self) -> Optional[Candidate]:
        """The next candidate to evaluate, or None when exhausted."""

    def tell(self, evaluation: Evaluation) -> None:
        """Receive the evaluation of a candidate this optimizer asked for (in ask order)."""

    # called by the study; plugins normally do not override it
    def _observe(self, evaluation: Evaluation) -> None:
        self.history.append(evaluation)
        if self.best is None or evaluation.score < self.best.score:
            self.best = evaluation
        self.tell(evaluation)


# -- typed options ------------------------------------------------------------------------------------------
class OptionError(InputError):
    """An unknown, missing or bad optimizer option (CLI exit code 2); ``option`` is its name."""

    def __init__(self, message: str, option: str):
        super().__init__(message)
        self.option = option


def option(default: Any = MISSING, *, help: str = "", low: Optional[float] = None, high: Optional[float] = None,
           choices: Optional[Sequence] = None):
    """One field of a plugin's ``Options`` dataclass: its default (omit it for a required option), the
    closed range ``[low, high]`` of a number, the allowed ``choices`` and a one-line ``help``."""
    meta = {"help": help, "low": low, "high": high, "choices": tuple(choices) if choices is not None else None}
    return field(default=default, metadata=meta)


@dataclass(frozen=True)
class OptionSpec:
    """What ``robodesign optimizers --verbose`` shows of one option."""
    name: str
    type: str
    default: Any
    required: bool
    help: str
    low: Optional[float] = None
    high: Optional[float] = None
    choices: Optional[tuple] = None

    @property
    def range(self) -> str:
        """``in [low, high]``, ``≥ low``, ``≤ high`` or empty."""
        if self.low is not None and self.high is not None:
            return f"in [{self.low}, {self.high}]"
        if self.low is not None:
            return f"≥ {self.low}"
        return f"≤ {self.high}" if self.high is not None else ""

    def describe(self, help: bool = True) -> str:
        """``name (type, default D, ≥ low): help`` — as ``robodesign optimizers --verbose`` prints it."""
        d = "required" if self.required else f"default {_show(self.default)}"
        if self.choices is not None:
            d += ", one of " + "|".join(map(str, self.choices))
        elif self.range:
            d += f", {self.range}"
        return f"{self.name} ({self.type}, {d})" + (f": {self.help}" if help and self.help else "")


def _show(v) -> str:
    """An option value as it is written on the command line."""
    if v is None:
        return "none"
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, (tuple, list)):
        return ",".join(map(str, v))
    return str(v)


def option_specs(cls: Type[Optimizer]) -> List[OptionSpec]:
    """The declared options of a plugin class, in declaration order ([] when it declares none)."""
    opts = getattr(cls, "Options", None)
    if opts is None:
        return []
    if not is_dataclass(opts):
        raise TypeError(f"{cls.__name__}.Options must be a dataclass")
    hints = get_type_hints(opts)
    out = []
    for f in fields(opts):
        required = f.default is MISSING and f.default_factory is MISSING
        default = None if required else (f.default if f.default is not MISSING
                                          else cast(Callable[[], Any], f.default_factory)())  # not MISSING here
        m = f.metadata
        out.append(OptionSpec(f.name, _type_name(hints[f.name]), default, required, m.get("help", ""),
                              m.get("low"), m.get("high"), m.get("choices")))
    return out


def parse_options(cls: Type[Optimizer], values: Mapping[str, Any]):
    """Validate and convert ``values`` (strings from the CLI, YAML scalars, ...) against ``cls.Options``.
    Returns an ``Options`` instance, or an empty dict for a plugin that declares no ``Options`` (it takes
    no options: any given is an :class:`OptionError`)."""
    plugin = getattr(cls, "name", "") or cls.__name__
    opts = getattr(cls, "Options", None)
    if opts is None:
        for k in values:
            raise OptionError(f"optimizer {plugin!r} takes no options (it declares no Options), got {k!r}", str(k))
        return {}
    specs = {s.name: s for s in option_specs(cls)}
    valid = ", ".join(s.describe(help=False) for s in specs.values()) or "none"

    def fail(key: str, msg: str):
        raise OptionError(f"optimizer {plugin!r}: {msg} (valid options: {valid})", str(key))

    for k in values:
        if k not in specs:
            close = difflib.get_close_matches(str(k), list(specs), n=1)
            fail(k, f"unknown option {k!r}" + (f" (did you mean {close[0]!r}?)" if close else ""))
    hints = get_type_hints(opts)
    out = {}
    for name, s in specs.items():
        if name not in values:
            if s.required:
                fail(name, f"option {name!r} is required")
            continue
        v = values[name]
        try:
            v = _convert(v, hints[name])
        except (TypeError, ValueError):
            fail(name, f"option {name!r}: expected {s.type}, got {v!r}")
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            if (s.low is not None and v < s.low) or (s.high is not None and v > s.high):
                fail(name, f"option {name!r}: {v!r} is not {s.range}")
        if s.choices is not None and v is not None and v not in s.choices:
            fail(name, f"option {name!r}: {v!r} is not one of {', '.join(map(str, s.choices))}")
        out[name] = v
    return opts(**out)


_NONE = ("none", "null", "")
_TRUE = ("true", "yes", "on", "1")
_FALSE = ("false", "no", "off", "0")


def _convert(v: Any, tp) -> Any:
    """``v`` as type ``tp`` (bool, int, float, str, Optional[...] and Tuple[str|int|float, ...])."""
    origin, args = get_origin(tp), get_args(tp)
    if origin is Union:
        inner = [a for a in args if a is not type(None)]
        if v is None or (isinstance(v, str) and v.strip().lower() in _NONE):
            return None
        return _convert(v, inner[0])
    if origin in (tuple, list):
        item = args[0] if args else str
        if isinstance(v, str):
            parts = [p.strip() for p in v.split(",") if p.strip()]
        else:
            parts = list(v) if isinstance(v, (list, tuple)) else [v]
        return tuple(_convert(p, item) for p in parts)
    if tp is bool:
        if isinstance(v, bool):
            return v
        t = str(v).strip().lower()
        if t in _TRUE or t in _FALSE:
            return t in _TRUE
        raise ValueError(v)
    if tp is int:
        if isinstance(v, bool):
            raise TypeError(v)
        if isinstance(v, float):
            if not v.is_integer():
                raise ValueError(v)
            return int(v)
        return int(str(v).strip()) if isinstance(v, str) else int(v)
    if tp is float:
        if isinstance(v, bool):
            raise TypeError(v)
        x = float(v)
        if not math.isfinite(x):
            raise ValueError(v)
        return x
    if tp is str:
        if isinstance(v, bool) or not isinstance(v, (str, int, float)):
            raise TypeError(v)
        return str(v)
    raise TypeError(f"unsupported option type {tp!r}")


def _type_name(tp) -> str:
    origin, args = get_origin(tp), get_args(tp)
    if origin is Union:
        return " or ".join(_type_name(a) for a in args if a is not type(None)) + " or none"
    if origin in (tuple, list):
        return f"comma-separated {_type_name(args[0]) if args else 'str'}s"
    return getattr(tp, "__name__", str(tp))


def create_optimizer(plugin: Union[str, Type[Optimizer]], problem: Problem, seed: int = 0,
                     options: Optional[Mapping[str, Any]] = None) -> Optimizer:
    """The optimizer ``plugin`` (an installed name or a class) for ``problem``; bad options and plugin
    errors about them are one :class:`~robodesign.core.errors.InputError`. A plugin written against the
    removed API before :class:`Problem` (``__init__(self, space, seed, **options)``) is an InputError that
    says how to port it (docs/plugins.md)."""
    cls = load_optimizer(plugin) if isinstance(plugin, str) else plugin
    name = getattr(cls, "name", "") or cls.__name__
    options = dict(options or {})
    if _takes_space(cls):
        raise InputError(f"optimizer {name!r} is written against the plugin API before Problem "
                         "(__init__(self, space, ...)), which this release no longer runs: take a Problem, "
                         "__init__(self, problem, seed=0, **options), declare Options and read self.cost "
                         "(docs/plugins.md)")
    try:
        return cls(problem, seed=seed, **options)
    except OptionError:
        raise
    except (TypeError, ValueError) as e:  # a plugin's own check of its options: its message, no traceback
        msg = str(e).removeprefix(f"{name}: ")
        raise InputError(f"optimizer {name!r}: {msg}") from None


def _takes_space(cls) -> bool:
    params = list(inspect.signature(cls.__init__).parameters.values())[1:]
    return bool(params) and params[0].name == "space"


def available_optimizers() -> Dict[str, metadata.EntryPoint]:
    """name → entry point of every installed optimizer plugin."""
    return {ep.name: ep for ep in metadata.entry_points(group=ENTRY_POINT_GROUP)}


def load_optimizer(name: str) -> Type[Optimizer]:
    eps = available_optimizers()
    if name not in eps:
        known = ", ".join(sorted(eps)) or "none installed"
        raise InputError(f"unknown optimizer {name!r} (installed: {known})")
    cls = eps[name].load()
    if not (isinstance(cls, type) and issubclass(cls, Optimizer)):
        raise InputError(f"entry point {name!r} ({eps[name].value}) is not an Optimizer subclass")
    return cls


@dataclass(frozen=True)
class Budget:
    evaluations: Optional[int] = None
    seconds: Optional[float] = None

    @staticmethod
    def parse(text: str) -> "Budget":
        """``500``, ``500evals``, ``60s``, ``10min``, ``2h`` or both joined with ``,``."""
        ev, sec = None, None
        for part in str(text).replace(" ", "").split(","):
            m = re.fullmatch(r"(\d+)(evals?|evaluations?)?", part)
            if m:
                ev = int(m.group(1))
                continue
            m = re.fullmatch(r"(\d+(?:\.\d+)?)(s|sec|m|min|h)", part)
            if m:
                f = {"s": 1, "sec": 1, "m": 60, "min": 60, "h": 3600}[m.group(2)]
                sec = float(m.group(1)) * f
                continue
            raise InputError(f"budget {text!r}: use e.g. 500evals, 60s, 10min or 500evals,60s")
        if ev is not None and ev < 1 or sec is not None and sec <= 0:
            raise InputError(f"budget {text!r} must be positive")
        return Budget(ev, sec)

    def exhausted(self, n: int, elapsed: float) -> bool:
        return (self.evaluations is not None and n >= self.evaluations) or \
            (self.seconds is not None and elapsed >= self.seconds)


class SerialExecutor:
    """Evaluates a batch in this process."""
    name = "serial"

    def __init__(self, evaluator: Callable[[Candidate], Evaluation]):
        self.evaluator = evaluator

    def map(self, candidates: Sequence[Candidate]) -> List[Evaluation]:
        return [self.evaluator(c) for c in candidates]

    def imap(self, candidates: Iterable[Candidate], batch_size: int = 1) -> Iterator[Evaluation]:
        """The evaluations of ``candidates`` one by one, each candidate pulled only when the previous one is
        evaluated (so a study with a time budget asks nothing after its deadline)."""
        for c in candidates:
            yield self.evaluator(c)

    def close(self) -> None:
        pass


@dataclass
class StudyResult:
    best: Optional[Evaluation]
    history: List[Evaluation]
    seconds: float
    stopped: str  # "budget" | "exhausted" | "interrupted" (Study(stop_on_interrupt=True))
    #: the study's own accounting of a time budget (None without one): seconds past the budget when it ended
    #: (0 if it ended before), the own time of the longest evaluation that ended after the deadline (every
    #: such evaluation was asked before it), and how many asked candidates were not evaluated because the
    #: deadline had passed before they were sent
    overrun: Optional[float] = None
    last_evaluation_seconds: Optional[float] = None
    dropped: int = 0

    @property
    def best_feasible(self) -> Optional[Evaluation]:
        return self.best if self.best is not None and self.best.feasible else None


class Study:
    """Owns the optimization loop: ask a batch → evaluate (executor) → store → tell, until the budget ends.

    ``storage`` (optional) has ``load() -> list[Evaluation]`` (stored evaluations in ask order, for
    resuming) and ``append(index, evaluation)``. ``on_evaluation(index, evaluation, best)`` is called
    after each evaluation (progress bars, anytime curves). ``stop_on_interrupt``: Ctrl-C ends the study
    with what it has (see :meth:`run`) instead of raising ``KeyboardInterrupt``.
    """

    def __init__(self, optimizer: Optimizer, executor, budget: Budget, batch_size: int = 1, storage=None,
                 on_evaluation: Optional[Callable] = None, stop_on_interrupt: bool = False,
                 clock_start: Optional[float] = None):
        #: the ``time.perf_counter()`` from which a time budget counts (None: when :meth:`run` starts); the
        #: CLI passes the time before it started its worker pool, so that the pool's start-up is spent from
        #: the budget too
        self.clock_start = clock_start
        self.optimizer = optimizer
        self.stop_on_interrupt = bool(stop_on_interrupt)
        self.executor = executor
        self.budget = budget
        self.batch_size = max(1, int(batch_size))
        self.storage = storage
        self.on_evaluation = on_evaluation

    @startup_heap_frozen()
    def run(self) -> StudyResult:
        """Run the study until the budget ends or the optimizer is exhausted. With ``stop_on_interrupt``, a
        ``KeyboardInterrupt`` (Ctrl-C; the CLI turns SIGTERM into one) ends it too: the result then holds the
        evaluations told so far (``stopped == "interrupted"``); those stored are replayed by a resume, the
        ones in flight are evaluated again. Meanwhile the garbage collector skips the objects that were alive
        when it started (:mod:`robodesign.core.gc_heap`)."""
        t0 = self._start()
        try:
            if getattr(self.optimizer, "independent_asks", False) and hasattr(self.executor, "imap"):
                return self._run_ahead()
            return self._run_batches()
        except KeyboardInterrupt:
            if not self.stop_on_interrupt:
                raise
            opt = self.optimizer
            return StudyResult(best=opt.best, history=list(opt.history), seconds=time.perf_counter() - t0,
                               stopped="interrupted")

    def _run_batches(self) -> StudyResult:
        t0 = self._start()
        stored = self.storage.load() if self.storage is not None else []
        history: List[Evaluation] = []
        opt = self.optimizer
        stopped = "budget"
        while True:
            n = len(history)
            # the time budget counts only evaluations made in this session: replaying stored ones takes none
            if self.budget.exhausted(n, time.perf_counter() - t0 if n >= len(stored) else 0.0):
                break
            size = self.batch_size
            if self.budget.evaluations is not None:
                size = min(size, self.budget.evaluations - n)
            batch: List[Candidate] = []
            late = False
            for _ in range(size):
                if batch and n + len(batch) >= len(stored) and self._late(t0):
                    late = True  # asking itself ran past the deadline (slow asks): nothing more is sent
                    break
                c = opt.ask()
                if c is None:
                    break
                batch.append(c)
            if not batch:
                stopped = "exhausted"
                break
            results: List[Optional[Evaluation]] = [None] * len(batch)
            todo = []
            for i, c in enumerate(batch):
                idx = n + i
                if idx < len(stored):
                    if stored[idx].candidate.key() != c.key():
                        raise InputError(f"cannot resume: evaluation {idx} was {stored[idx].candidate.key()!r} "
                                         f"but the optimizer now asks {c.key()!r} (different settings or seed?)")
                    results[i] = stored[idx]
                else:
                    todo.append(i)
            if todo:
                fresh = self._evaluate([batch[i] for i in todo], t0)
                for i, ev in zip(todo, fresh):
                    results[i] = ev
                    if self.storage is not None:
                        self.storage.append(n + i, ev)
                if len(fresh) < len(todo):  # the deadline passed within the batch: tell what was evaluated
                    self._dropped += len(todo) - len(fresh)
                    results = results[:todo[len(fresh)]]
            for i, done in enumerate(results):
                assert done is not None  # every result up to the first candidate not evaluated is filled
                opt._observe(done)
                history.append(done)
                if self.on_evaluation is not None:
                    self.on_evaluation(n + i, done, opt.best)
            if self._dropped or late:
                break
            if len(batch) < size:
                stopped = "exhausted"
                break
        return self._result(opt, history, t0, stopped)

    # -- the time budget ------------------------------------------------------------------------------------
    # With a time budget the study asks nothing after the deadline, and a batch is streamed to the executor
    # (``imap``, one candidate per message) so that a candidate not yet sent when the deadline passes is not
    # evaluated at all: the study ends at the deadline plus the own time of the evaluations already running
    # (StudyResult.overrun, last_evaluation_seconds). Without ``imap`` the executor gets one candidate at a
    # time. Evaluation budgets evaluate whole batches, as before.
    def _late(self, t0: float) -> bool:
        return self.budget.seconds is not None and time.perf_counter() - t0 >= self.budget.seconds

    def _evaluate(self, candidates: List[Candidate], t0: float) -> List[Evaluation]:
        """The evaluations of ``candidates`` in order: all of them without a time budget; with one, those sent
        before the deadline."""
        if self.budget.seconds is None:
            return list(self.executor.map(candidates))
        if not hasattr(self.executor, "imap"):
            out: List[Evaluation] = []
            for c in candidates:
                if self._late(t0):
                    break
                out.extend(self._arrived(ev, t0) for ev in self.executor.map([c]))
            return out

        def until_deadline():
            for c in candidates:
                if self._late(t0):
                    return
                yield c
        return [self._arrived(ev, t0) for ev in self.executor.imap(until_deadline(), 1)]

    def _arrived(self, ev: Evaluation, t0: float) -> Evaluation:
        """Note the own time of an evaluation that arrives after the deadline."""
        if self._late(t0):
            self._late_seconds.append(float(ev.seconds))
        return ev

    def _start(self) -> float:
        self._dropped = 0
        self._late_seconds: List[float] = []
        return time.perf_counter() if self.clock_start is None else float(self.clock_start)

    def _result(self, opt: Optimizer, history: List[Evaluation], t0: float, stopped: str) -> StudyResult:
        seconds = time.perf_counter() - t0
        res = StudyResult(best=opt.best, history=history, seconds=seconds, stopped=stopped, dropped=self._dropped)
        if self.budget.seconds is not None:
            res.overrun = max(0.0, seconds - self.budget.seconds)
            res.last_evaluation_seconds = max(self._late_seconds) if self._late_seconds else None
        return res

    def _run_ahead(self) -> StudyResult:
        """The loop for an optimizer with ``independent_asks``: stored evaluations are replayed, then the
        candidates are asked as the executor's stream pulls them (ahead of the tells) and told, stored and
        reported in ask order, as :meth:`run` does."""
        t0 = self._start()
        stored = self.storage.load() if self.storage is not None else []
        history: List[Evaluation] = []
        opt = self.optimizer
        stopped = ["budget"]

        def deliver(ev: Evaluation) -> None:
            opt._observe(ev)
            history.append(ev)
            if self.on_evaluation is not None:
                self.on_evaluation(len(history) - 1, ev, opt.best)

        def ask(n: int, elapsed: float) -> Optional[Candidate]:
            if self.budget.exhausted(n, elapsed):
                return None
            c = opt.ask()
            if c is None:
                stopped[0] = "exhausted"
            return c

        for idx, ev in enumerate(stored):  # replaying takes no time of the budget
            c = ask(idx, 0.0)
            if c is None:
                break
            if ev.candidate.key() != c.key():
                raise InputError(f"cannot resume: evaluation {idx} was {ev.candidate.key()!r} "
                                 f"but the optimizer now asks {c.key()!r} (different settings or seed?)")
            deliver(ev)
        else:
            def fresh():
                n = len(history)
                while True:
                    c = ask(n, time.perf_counter() - t0)
                    if c is None:
                        return
                    n += 1
                    yield c
            # a time budget streams one candidate per message: none waits in a chunk past the deadline
            for ev in self.executor.imap(fresh(), 1 if self.budget.seconds is not None else self.batch_size):
                self._arrived(ev, t0)
                if self.storage is not None:
                    self.storage.append(len(history), ev)
                deliver(ev)
        return self._result(opt, history, t0, stopped[0])


def optimize(problem: Problem, plugin: Union[str, Type[Optimizer]], budget: Union[str, Budget], *, seed: int = 0,
             options: Optional[Mapping[str, Any]] = None, batch_size: int = 1, settings=None,
             on_evaluation: Optional[Callable] = None) -> StudyResult:
    """Search ``problem`` with optimizer ``plugin`` in this process: the Python twin of ``robodesign optimize``.
    ``budget``: a :class:`Budget` or its text (``"200evals"``, ``"60s"``); ``settings``: the evaluations'
    :class:`~robodesign.design.solve.SolveSettings` (default: :func:`~robodesign.design.evaluator.evaluation_settings`)."""
    from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
    opt = create_optimizer(plugin, problem, seed=seed, options=options)
    ev = Evaluator(EvaluatorSpec(problem, settings if settings is not None else evaluation_settings(), seed=seed))
    budget = budget if isinstance(budget, Budget) else Budget.parse(budget)
    return Study(opt, SerialExecutor(ev), budget, batch_size=batch_size, on_evaluation=on_evaluation).run()
