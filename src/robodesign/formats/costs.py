"""Cost functions of CoBRA solutions (FORMAT.md §4, CoBRA paper).

Built-in terms (every default weight is 1; ``cost = Σ weight · value``):

==================  ======================================================================================
``cyc``             ``t[-1]``, the last time stamp (not t_N − t_0), as the reference does
``mechEnergy``      Σ_{k<N−1} |τ_k · dq_k| · (t_{k+1} − t_k): absolute *total* power (dot product over the
                    joints) times the step, left rectangle rule; τ = full drivetrain torque (with motor inertia
                    and friction)
``linkMechEnergy``  same formula with the link-side torque (no motor inertia, no friction)
``qDist``           Σ_k Σ_j |q_{k+1,j} − q_{k,j}| (rad and m mixed)
``effort``          Σ |τ| over all samples and joints · (t_1 − t_0). **Quirk kept for compatibility:** the
                    reference multiplies by the *first* step only, which is exact for uniform time steps.
``mass``            total robot mass [kg]
``numJ``            number of actuated joints
``fulfillN``        number of goals achieved (use a negative weight for a reward)
``fulfillP``        goals achieved / number of goals (0 if the task has no goals)
==================  ======================================================================================

Named compounds: ``Liu2`` = mechEnergy + 0.2·cyc and ``Whit2`` = 0.025·numJ + 0.1·mass.
Table V of the paper lists the two compounds as separate columns for an IMPROV-like arm: Whit2 = 1.62
(= 0.025·6 + 0.1·14.7 kg) and Liu2 = 101.5 (= 100.4 J + 0.2·5.47 s), consistent with these weights.

Notation (both parse to the same terms):

* CoBRA/Timor: ``"cyc_0.2,mechEnergy_1"`` — comma-separated ``abbr`` or ``abbr_weight``; the weight is the
  text after the *first* ``_``. Unlike the reference (which silently drops anything after a second ``_``)
  the whole remainder must be a plain decimal number.
* Paper: ``"[(cyc|0.2),(mechEnergy|1)]"``; ``(name)`` without a weight means weight 1.
* A bare compound name ``"Liu2"`` (or ``"Liu2_2"``, which scales its terms; or a compound inside a list).

Decisions: ``""`` and ``"[]"`` are the empty cost (value 0), as in the reference. A term that appears twice
is merged by adding its weights (same value, deterministic descriptor). Weights must be finite numbers and,
unlike the reference, non-negative, except on rewards (``fulfillN``, ``fulfillP``: ``fulfillN_-1`` is the
reference's way to reward achieved goals): a cost such as ``cyc_-1`` would rank the slowest robot first.
Terms with weight 0 are not evaluated (so they never trigger a torque computation).

Writer rule (``CostFunction.descriptor``): each term is ``abbr`` if its weight is exactly 1, else
``abbr_<w>`` with the shortest Python float text that reads back as exactly w (``cyc_0.2``, ``fulfillN_-1.0``,
``cyc_0.99995``), the strings are sorted and joined by ``,``. The reference rounds weights to 4 decimals
(``cyc_0.99995`` would be written ``cyc``); robodesign keeps them exact, so ``parse_cost(c.descriptor()) == c``
always holds and a leaderboard keyed by the descriptor never mixes different weights. Weights larger than
``MAX_WEIGHT`` = 1e6 in magnitude are refused (bad input): they would overflow a cost to ±inf.

Torques are lazy: :class:`CostContext` accepts ``tau``/``tau_link`` as arrays or zero-argument callables
and calls them at most once, only when a term needs them.
"""
from __future__ import annotations

import dataclasses
import difflib
import math
import re
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from robodesign.core.errors import InputError, PathPart, RobodesignError, describe_value

ArrayOrLazy = Union[np.ndarray, Sequence, Callable[[], Any], None]


class MissingQuantityError(RobodesignError, ValueError):
    """A cost term needs a quantity (torques, mass, …) that the context does not provide."""


# ---------------------------------------------------------------------------------------------------------
# Context
# ---------------------------------------------------------------------------------------------------------
@dataclass
class CostContext:
    """Everything a cost term may need. Arrays: ``t`` (N,), ``q``/``dq``/``ddq``/``tau``/``tau_link`` (N, dof).

    ``dq``/``ddq`` default to ``numpy.gradient`` of q along t (as the solution format fills them).
    ``tau``, ``tau_link``, ``mass`` may be zero-argument callables; they are evaluated once, on first use.
    ``num_joints`` defaults to ``q.shape[1]``.
    """
    t: np.ndarray  # t and q: array-likes, made float arrays by __post_init__ (never lazy)
    q: np.ndarray
    dq: ArrayOrLazy = None
    ddq: ArrayOrLazy = None
    tau: ArrayOrLazy = None
    tau_link: ArrayOrLazy = None
    mass: Union[float, Callable[[], float], None] = None
    num_joints: Optional[int] = None
    goals_achieved: Optional[int] = None
    num_goals: Optional[int] = None
    _cache: Dict[str, Any] = field(default_factory=dict, init=False, repr=False)
    _terms: Dict[str, Tuple["CostTerm", float]] = field(default_factory=dict, init=False, repr=False)

    def __post_init__(self):
        self.t = np.asarray(self.t, dtype=float).reshape(-1)
        q = np.asarray(self.q, dtype=float)
        if q.ndim == 1:
            q = q.reshape(len(self.t), -1) if len(self.t) else q.reshape(0, 0)
        self.q = q
        if q.shape[0] != self.t.shape[0]:
            raise InputError(f"q has {q.shape[0]} samples but t has {self.t.shape[0]}")

    @property
    def dof(self) -> int:
        return int(self.q.shape[1]) if self.q.ndim == 2 else 0

    def get(self, name: str):
        """The resolved value of ``name`` (arrays as float (N, dof)); lazy values are computed once."""
        if name in self._cache:
            return self._cache[name]
        if name in ("t", "q"):
            return getattr(self, name)
        raw = getattr(self, name)
        if callable(raw):
            raw = raw()
        if name in ("dq", "ddq") and raw is None:
            base = self.q if name == "dq" else self.get("dq")
            raw = _gradient(base, self.t)
        if name == "num_joints" and raw is None:
            raw = self.dof
        if raw is None:
            raise MissingQuantityError(f"this cost needs {_QUANTITY_NAMES.get(name, name)}, "
                                       "which the evaluation context does not provide")
        if name in ("dq", "ddq", "tau", "tau_link"):
            raw = np.asarray(raw, dtype=float)
            if raw.shape != self.q.shape:
                raise InputError(f"{name} has shape {raw.shape}, expected {self.q.shape} like q")
        self._cache[name] = raw
        return raw

    def is_evaluated(self, name: str) -> bool:
        return name in self._cache

    def term_value(self, name: str) -> float:
        """The value of the registered term ``name`` here, ``float(fn(ctx))``: computed at the first ask and kept with
        the term it came from (a term registered anew since is asked again). A term that raises is not kept."""
        term = _REGISTRY[name]
        hit = self._terms.get(name)
        if hit is None or hit[0] is not term:
            hit = self._terms[name] = (term, float(term.fn(self)))
        return hit[1]


_QUANTITY_NAMES = {"tau": "drivetrain joint torques (tau)", "tau_link": "link-side joint torques (tau_link)",
                   "mass": "the robot mass", "goals_achieved": "the number of achieved goals",
                   "num_goals": "the number of goals"}


def _gradient(a: np.ndarray, t: np.ndarray) -> np.ndarray:
    if a.shape[0] < 2:
        return np.zeros_like(a)
    return np.gradient(a, t, axis=0)


# ---------------------------------------------------------------------------------------------------------
# Built-in cost values
# ---------------------------------------------------------------------------------------------------------
def _cyc(ctx: CostContext) -> float:
    return float(ctx.t[-1]) if len(ctx.t) else 0.0


def _energy(ctx: CostContext, which: str) -> float:
    if len(ctx.t) < 2:
        return 0.0
    tau = ctx.get(which)
    power = np.abs(np.einsum("ij,ij->i", tau, ctx.get("dq")))[:-1]
    return float(np.sum(power * np.diff(ctx.t)))


def _qdist(ctx: CostContext) -> float:
    return float(np.sum(np.abs(np.diff(ctx.q, axis=0)))) if len(ctx.t) > 1 else 0.0


def _effort(ctx: CostContext) -> float:
    if len(ctx.t) < 2:
        return 0.0
    return float(np.sum(np.abs(ctx.get("tau"))) * (ctx.t[1] - ctx.t[0]))


def _fulfill_p(ctx: CostContext) -> float:
    n = ctx.get("num_goals")
    return float(ctx.get("goals_achieved")) / n if n else 0.0


@dataclass(frozen=True)
class CostTerm:
    """A registered cost term and what the rest of robodesign may rely on about it:

    * ``non_negative``: its value is never negative (bound pruning may count it as ≥ 0);
    * ``needs_torques``: it reads ``tau``/``tau_link`` (inverse dynamics along the trajectory);
    * ``trajopt``: trajectory optimization (:mod:`robodesign.solvers.trajopt`) has a differentiable model of it;
    * ``reward``: it measures something to *maximise*, so a negative weight is allowed (``fulfillN_-1``, as in
      the reference); every other term only takes weights ≥ 0.
    """
    name: str
    fn: Callable[[CostContext], float]
    description: str
    non_negative: bool = False
    needs_torques: bool = False
    trajopt: bool = False
    reward: bool = False


_REGISTRY: Dict[str, CostTerm] = {}
_COMPOUNDS: Dict[str, Tuple[Tuple[str, float], ...]] = {}
_COMPOUND_DESCRIPTIONS: Dict[str, str] = {}
_NAMED: List[Optional[tuple]] = [None]  # named_costs' last (state of the registry, answer)
MAX_WEIGHT = 1e6  # |weight| above this is refused: cyc_1e308 or fulfillN_-1e308 would overflow to ±inf
_NAME_RE = re.compile(r"^[A-Za-z][A-Za-z0-9]*$")
_NUMBER_RE = re.compile(r"^[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?$")


def _weight_problem(name: str, w: float) -> Optional[str]:
    """Why ``w`` is not an acceptable weight of term ``name`` (None if it is)."""
    if not math.isfinite(w):
        return f"weight {w} of cost {name!r} must be finite"
    if abs(w) > MAX_WEIGHT:
        return f"weight {w:g} of cost {name!r} is larger than {MAX_WEIGHT:g} in magnitude (it would overflow costs)"
    if w < 0 and not _REGISTRY[name].reward:
        rewards = ", ".join(n for n, t in _REGISTRY.items() if t.reward)
        return (f"weight {w:g} of cost {name!r} is negative: costs are minimised, so only rewards ({rewards}) "
                "may take a negative weight")
    return None


def register_cost(name: str, fn: Callable[[CostContext], float], description: str, *,
                  overwrite: bool = False, non_negative: bool = False, needs_torques: bool = False,
                  reward: bool = False) -> None:
    """Add a cost term usable in descriptors. ``fn(ctx) -> float`` gets a :class:`CostContext`.

    Names are letters and digits, starting with a letter (``_ , | : [ ] ( )`` are separators). The flags
    are the term's properties (:class:`CostTerm`); only built-in terms have a trajectory-optimization model.
    """
    if not isinstance(name, str) or not _NAME_RE.match(name):
        raise ValueError(f"invalid cost name {name!r}: use letters and digits, starting with a letter")
    if not callable(fn):
        raise TypeError("fn must be callable")
    if not overwrite and (name in _REGISTRY or name in _COMPOUNDS):
        raise ValueError(f"cost {name!r} is already registered (pass overwrite=True to replace it)")
    _COMPOUNDS.pop(name, None)
    _REGISTRY[name] = CostTerm(name, fn, description, non_negative=non_negative, needs_torques=needs_torques,
                               reward=reward)


def register_compound(name: str, terms: Mapping[str, float] | Iterable[Tuple[str, float]], description: str, *,
                      overwrite: bool = False) -> None:
    """Add a named weighted sum of registered terms, e.g. ``register_compound("Liu2", {...}, "...")``."""
    if not isinstance(name, str) or not _NAME_RE.match(name):
        raise ValueError(f"invalid cost name {name!r}: use letters and digits, starting with a letter")
    items = tuple((str(k), float(w)) for k, w in (terms.items() if isinstance(terms, Mapping) else terms))
    for k, w in items:
        if k not in _REGISTRY:
            raise ValueError(f"compound {name!r} uses unknown cost {k!r}")
        problem = _weight_problem(k, w)
        if problem:
            raise ValueError(f"compound {name!r}: {problem}")
    if not overwrite and (name in _REGISTRY or name in _COMPOUNDS):
        raise ValueError(f"cost {name!r} is already registered (pass overwrite=True to replace it)")
    _REGISTRY.pop(name, None)
    _COMPOUNDS[name] = items
    _COMPOUND_DESCRIPTIONS[name] = description


def cost_term(name: str) -> CostTerm:
    """The registered term ``name`` (InputError naming the known costs if there is none)."""
    if name not in _REGISTRY:
        raise InputError(_unknown_cost_message(name))
    return _REGISTRY[name]


def cost_terms() -> Dict[str, CostTerm]:
    """name → :class:`CostTerm` of every registered term (compounds expand to these)."""
    return dict(_REGISTRY)


def known_costs() -> Dict[str, str]:
    """name → description of every registered term and compound."""
    out = {k: v.description for k, v in _REGISTRY.items()}
    out.update(_COMPOUND_DESCRIPTIONS)
    return out


register_cost("cyc", _cyc, "cycle time: last time stamp t[-1] [s]", non_negative=True)
register_cost("mechEnergy", lambda c: _energy(c, "tau"),
              "mechanical energy Σ|τ·dq|·Δt with drivetrain torque (motor inertia + friction) [J]",
              non_negative=True, needs_torques=True)
register_cost("linkMechEnergy", lambda c: _energy(c, "tau_link"),
              "mechanical energy Σ|τ·dq|·Δt with link-side torque [J]", non_negative=True, needs_torques=True)
register_cost("qDist", _qdist, "joint-space distance Σ|Δq| (rad and m mixed)", non_negative=True)
register_cost("effort", _effort, "effort Σ|τ| · (t1 − t0) [N·m·s]", non_negative=True, needs_torques=True)
register_cost("mass", lambda c: float(c.get("mass")), "total robot mass [kg]", non_negative=True)
register_cost("numJ", lambda c: float(c.get("num_joints")), "number of actuated joints", non_negative=True)
register_cost("fulfillN", lambda c: float(c.get("goals_achieved")), "number of achieved goals", non_negative=True,
              reward=True)
register_cost("fulfillP", _fulfill_p, "fraction of achieved goals", non_negative=True, reward=True)
# the terms solvers/trajopt.py models with CasADi (cycle time, drivetrain energy, effort)
for _name in ("cyc", "mechEnergy", "effort"):
    _REGISTRY[_name] = dataclasses.replace(_REGISTRY[_name], trajopt=True)
_BUILTIN_TERMS = frozenset(_REGISTRY)
register_compound("Liu2", (("mechEnergy", 1.0), ("cyc", 0.2)), "Liu2 = mechEnergy + 0.2·cyc")
register_compound("Whit2", (("numJ", 0.025), ("mass", 0.1)), "Whit2 = 0.025·numJ + 0.1·mass")


# ---------------------------------------------------------------------------------------------------------
# CostFunction
# ---------------------------------------------------------------------------------------------------------
def _format_weight(w: float) -> str:
    """The shortest text that reads back as exactly ``w`` (``0.2``, ``-1.0``, ``0.99995``)."""
    return repr(float(w))


@dataclass(frozen=True)
class CostFunction:
    """A weighted sum of registered cost terms. ``terms`` is sorted by name; ``name`` is the compound name
    (``Liu2``) when the cost was given as one; it is not part of equality."""
    terms: Tuple[Tuple[str, float], ...] = ()
    name: Optional[str] = field(default=None, compare=False)

    def __post_init__(self):
        merged: Dict[str, float] = {}
        for n, w in self.terms:
            if n not in _REGISTRY:
                raise InputError(_unknown_cost_message(n))
            merged[n] = merged.get(n, 0.0) + float(w)
        for n, w in merged.items():
            problem = _weight_problem(n, w)
            if problem:
                raise InputError(problem)
        object.__setattr__(self, "terms", tuple(sorted(merged.items())))

    @classmethod
    def parse(cls, text: str, file: Optional[str] = None, path: Sequence[PathPart] | str | None = None) \
            -> "CostFunction":
        return parse_cost(text, file, path)

    @property
    def is_empty(self) -> bool:
        return not self.terms

    def descriptor(self) -> str:
        """CoBRA ``costFunction`` string (the reference writer rule, see module docstring)."""
        parts = []
        for n, w in self.terms:
            parts.append(n if w == 1 else f"{n}_{_format_weight(w)}")
        return ",".join(sorted(parts))

    def paper_notation(self) -> str:
        """``[(cyc|0.2),(mechEnergy|1)]``."""
        return "[" + ",".join(f"({n}|{_format_weight(w).removesuffix('.0')})" for n, w in self.terms) + "]"

    def __str__(self) -> str:
        return self.name or self.descriptor()

    def weight(self, term: str) -> float:
        return dict(self.terms).get(term, 0.0)

    @property
    def needs_torques(self) -> bool:
        """Whether evaluating this cost runs inverse dynamics (a term with non-zero weight needs torques)."""
        return any(_REGISTRY[n].needs_torques for n in self.needs())

    def needs(self) -> set:
        """Names of the registered terms with non-zero weight."""
        return {n for n, w in self.terms if w != 0}

    def raw_values(self, ctx: CostContext) -> Dict[str, float]:
        """Unweighted value of each term with non-zero weight."""
        return {n: ctx.term_value(n) for n, w in self.terms if w != 0}

    def breakdown(self, ctx: CostContext) -> Dict[str, float]:
        """term → weight · value (terms with weight 0 give 0 without being evaluated). Sums to ``evaluate``."""
        return {n: (w * ctx.term_value(n) if w != 0 else 0.0) for n, w in self.terms}

    def evaluate(self, ctx: CostContext) -> float:
        return float(sum(self.breakdown(ctx).values()))

    def __add__(self, other: "CostFunction") -> "CostFunction":
        if not isinstance(other, CostFunction):
            return NotImplemented
        return CostFunction(self.terms + other.terms)

    def __mul__(self, k: float) -> "CostFunction":
        if isinstance(k, bool) or not isinstance(k, (int, float)):
            return NotImplemented
        return CostFunction(tuple((n, w * k) for n, w in self.terms))

    __rmul__ = __mul__

    def trajopt_weights(self) -> Dict[str, float]:
        """term → weight of the terms trajectory optimization models (``CostTerm.trajopt``)."""
        return {n: w for n, w in self.terms if _REGISTRY[n].trajopt}

    def __reduce__(self):
        """A cost pickles with the definitions of its terms that are not built in, so a worker process that
        never ran the code registering them (a plugin imported by the driver, a term registered at run
        time) knows them: unpickling registers each missing term. A term's ``fn`` must then be picklable
        (a module-level function)."""
        defs = tuple(_REGISTRY[n] for n, _ in self.terms if n in _REGISTRY and n not in _BUILTIN_TERMS)
        return (_restore_cost, (self.terms, self.name, defs))


def named_costs() -> Dict[str, CostFunction]:
    """name → :class:`CostFunction` of every registered term (weight 1) and compound (its terms, named), the
    costs :func:`known_costs` lists, built from the registry without parsing text (once per state of the registry:
    the judge asks at every check; a new dict each time, of the same frozen costs)."""
    key = (tuple(_REGISTRY.items()), tuple(_COMPOUNDS.items()))
    hit = _NAMED[0]
    if hit is None or hit[0] != key:
        out = {n: CostFunction(((n, 1.0),)) for n in _REGISTRY}
        out.update({n: CostFunction(terms, name=n) for n, terms in _COMPOUNDS.items()})
        hit = _NAMED[0] = (key, out)
    return dict(hit[1])


def _restore_cost(terms, name, defs) -> "CostFunction":
    for term in defs:
        if term.name not in _REGISTRY and term.name not in _COMPOUNDS:
            _REGISTRY[term.name] = term
    return CostFunction(terms, name=name)


def _unknown_cost_message(name: str) -> str:
    known = list(_REGISTRY) + list(_COMPOUNDS)
    close = difflib.get_close_matches(name, known, n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    return f"unknown cost {name!r}{hint}; known costs: " + ", ".join(known)


def _parse_weight(text: str, term: str, file, path) -> float:
    s = text.strip()
    if not _NUMBER_RE.match(s):
        raise InputError(f"weight {text!r} of cost {term!r} is not a number (expected e.g. {term}_0.5)",
                         file=file, path=path)
    w = float(s)
    if not math.isfinite(w):
        raise InputError(f"weight {text!r} of cost {term!r} must be finite", file=file, path=path)
    return w


def _expand(name: str, weight: float, file, path) -> list:
    if name in _REGISTRY:
        return [(name, weight)]
    if name in _COMPOUNDS:
        return [(n, w * weight) for n, w in _COMPOUNDS[name]]
    raise InputError(_unknown_cost_message(name), file=file, path=path)


_PAPER_TERM = re.compile(r"\(\s*([^()|,\s]*)\s*(?:\|([^()|,]*))?\)")


def parse_cost(text: Any, file: Optional[str] = None, path: Sequence[PathPart] | str | None = None) \
        -> CostFunction:
    """Parse a cost descriptor in either notation (see module docstring). Errors name file and path."""
    if not isinstance(text, str):
        raise InputError(f"expected a cost function string, got {describe_value(text)}", file=file, path=path)
    s = text.strip()
    if not s or s == "[]":
        return CostFunction(())
    terms: list = []
    if s.startswith("["):
        if not s.endswith("]"):
            raise InputError(f"cost {text!r} starts with '[' but does not end with ']' "
                             "(expected e.g. [(cyc|0.2),(mechEnergy|1)])", file=file, path=path)
        inner = s[1:-1].strip()
        for item in (inner.split(",") if inner else []):
            m = _PAPER_TERM.fullmatch(item.strip())
            if not m:
                raise InputError(f"cannot read term {item.strip()!r} of cost {text!r}: expected terms like "
                                 "(cyc|0.2) separated by commas", file=file, path=path)
            name, w = m.group(1), m.group(2)
            if not name:
                raise InputError(f"empty cost name in term {item.strip()!r} of {text!r}", file=file, path=path)
            weight = _parse_weight(w, name, file, path) if w is not None else 1.0
            terms += _expand(name, weight, file, path)
        name = None
    else:
        for part in s.split(","):
            part = part.strip()
            if not part:
                raise InputError(f"empty term in cost {text!r} (check the commas)", file=file, path=path)
            n, sep, w = part.partition("_")
            n = n.strip()
            if not n:
                raise InputError(f"missing cost name in term {part!r}", file=file, path=path)
            weight = _parse_weight(w, n, file, path) if sep else 1.0
            terms += _expand(n, weight, file, path)
        name = s if s in _COMPOUNDS else None
    merged: Dict[str, float] = {}
    for n, w in terms:
        merged[n] = merged.get(n, 0.0) + w
    for n, w in merged.items():
        problem = _weight_problem(n, w)
        if problem:
            raise InputError(f"cost {text!r}: {problem}", file=file, path=path)
    return CostFunction(tuple(terms), name=name)
