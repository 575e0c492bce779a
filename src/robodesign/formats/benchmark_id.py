"""CoBRA benchmark IDs ``Robot:Cost:Task``.

Where the grammar comes from
----------------------------
The CoBRA paper (Mayer, Külz, Althoff, "CoBRA: A Composable Benchmark for Robotics Applications",
arXiv:2203.09337, ICRA 2024; Eq. 1 and 2) identifies a benchmark by the three parts it is composed of —
robot, cost function, task — joined by ``:``, and writes cost functions as weighted term lists
``[(cyc|0.2),(mechEnergy|1)]``. We could not retrieve the paper text itself (searched the docs, pages and
code corpora, the timor-python sources and the cobra-io client), so the exact production rules of the
*robot* part are not confirmed. This module therefore implements a documented **superset**, robodesign's
own, that accepts every form we know of and keeps each part unambiguous:

.. code-block:: text

    BenchmarkID := Robot ":" Cost ":" Task
    Robot       := Single | "[" Single ("," Single)* "]"       -- a list = several robots solve the task
                                                                  together (collaborative)
    Single      := Prefix? Name
    Prefix      := "M-"   module-set optimisation: find the best assembly of the module set Name
                 | "C-"   a fixed, already composed (modular) robot called Name
                 | "IND-" an individually given, fixed robot called Name (e.g. a URDF robot)
    Name        := [A-Za-z0-9_.-]+    (a module set / robot name, e.g. IMPROV, geometric_primitive_modules)
    Cost        := a cost descriptor in either notation of :mod:`robodesign.formats.costs`
                   ("cyc_0.2,mechEnergy", "[(cyc|0.2),(mechEnergy|1)]", "Liu2"); it may contain "," "|"
                   "(" ")" "[" "]" "_" but never ":"; an empty cost is rejected.
                   With a robot list of n robots the cost part may also be a list "[C1,...,Cn]" of one
                   cost per robot (e.g. "[cyc,Liu2]"; a weighted sum inside it in bracket notation);
                   a single cost applies to every robot. ``BenchmarkID.costs`` holds the per-robot costs.
    Task        := Segment ("/" Segment)*   with Segment := [A-Za-z0-9_.-]+, not "." or ".."
                   (task IDs are namespaced with "/", e.g. simple/PTP_1)

A bare ``Name`` (no prefix) is what CoBRA solution files store in ``moduleSet``: the robot is the module
set (a fixed robot is a module set with a single assembly), so it resolves like ``M-Name``; its ``kind`` is
reported as ``"module_set"``. ``C-`` and ``IND-`` give ``kind == "fixed"``. Prefixes are case-sensitive.

Parsing splits on ``:``; since neither the robot nor the cost may contain ``:``, and task IDs in CoBRA do
not either, an ID must contain exactly two colons. ``str(bid)`` is canonical: the robot as written, the
cost as its compound name if it was given as one (``Liu2``) else its CoBRA descriptor, and the task.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Callable, NamedTuple, Optional, Sequence, Tuple

from robodesign.core.errors import InputError, PathPart, describe_value
from robodesign.formats.costs import CostFunction, parse_cost

PREFIXES = {"M-": "module_set", "C-": "fixed", "IND-": "fixed"}
_NAME_RE = re.compile(r"^[A-Za-z0-9_.\-]+$")
_SEGMENT_RE = re.compile(r"^[A-Za-z0-9_.\-]+$")


@dataclass(frozen=True)
class RobotRef:
    """One robot of the robot part: ``prefix`` ('' / 'M-' / 'C-' / 'IND-') and ``name``."""
    name: str
    prefix: str = ""

    @property
    def kind(self) -> str:
        """``"module_set"`` (bare name or ``M-``: the assembly is to be optimised) or ``"fixed"``."""
        return PREFIXES.get(self.prefix, "module_set")

    def __str__(self) -> str:
        return self.prefix + self.name


@dataclass(frozen=True)
class RobotSpec:
    robots: Tuple[RobotRef, ...]
    collaborative: bool = False  # written as a [..] list

    def __str__(self) -> str:
        inner = ",".join(str(r) for r in self.robots)
        return f"[{inner}]" if self.collaborative else inner

    @property
    def names(self) -> Tuple[str, ...]:
        return tuple(r.name for r in self.robots)


class ResolvedBenchmark(NamedTuple):
    robot: Any            # module_set_lookup result (a tuple of them for a collaborative list)
    cost: CostFunction
    task: Any             # task_lookup result, or the task ID when no lookup is given


@dataclass(frozen=True)
class BenchmarkID:
    robot: RobotSpec
    cost: CostFunction  # the cost (of the first robot when a collaborative ID gives one cost per robot)
    task: str
    costs: Tuple[CostFunction, ...] = ()  # a collaborative ID's cost per robot, in the robot list's order

    @classmethod
    def parse(cls, text: Any, file: Optional[str] = None, path: Sequence[PathPart] | str | None = None) \
            -> "BenchmarkID":
        def err(msg):
            return InputError(f"benchmark ID {text!r}: {msg}", file=file, path=path)

        if not isinstance(text, str):
            raise InputError(f"expected a benchmark ID string Robot:Cost:Task, got {describe_value(text)}",
                             file=file, path=path)
        parts = text.strip().split(":")
        if len(parts) != 3:
            raise err(f"expected three parts Robot:Cost:Task separated by ':', found {len(parts)} part(s)")
        robot_s, cost_s, task_s = (p.strip() for p in parts)
        robot = _parse_robot(robot_s, err)
        if not cost_s:
            raise err("the cost part is empty (expected e.g. cyc, Liu2 or [(cyc|0.2),(mechEnergy|1)])")
        costs = _per_robot_costs(cost_s, robot, err)
        if costs is None:
            try:
                cost = parse_cost(cost_s)
            except InputError as e:
                raise err(f"cost part: {e.reason}") from None
            costs = (cost,) * len(robot.robots) if robot.collaborative else ()
        _check_task(task_s, err)
        return cls(robot, costs[0] if costs else cost, task_s, costs)

    def __str__(self) -> str:
        if self.costs and any(c.descriptor() != self.costs[0].descriptor() for c in self.costs):
            cost = "[" + ",".join(_cost_item_text(c) for c in self.costs) + "]"
        else:
            cost = _cost_text(self.cost)
        return f"{self.robot}:{cost}:{self.task}"

    @property
    def is_collaborative(self) -> bool:
        return self.robot.collaborative

    def resolve(self, module_set_lookup: Optional[Callable[[str], Any]] = None,
                task_lookup: Optional[Callable[[str], Any]] = None) -> ResolvedBenchmark:
        return resolve(self, module_set_lookup, task_lookup)


def _cost_text(c: CostFunction) -> str:
    return c.name or c.descriptor()


def _cost_item_text(c: CostFunction) -> str:
    """A cost inside a per-robot list: a weighted sum in bracket notation (its commas would split the list)."""
    text = _cost_text(c)
    return c.paper_notation() if "," in text else text


def _top_level_items(s: str) -> list:
    """``s`` split at the commas outside brackets and parentheses."""
    items, depth, cur = [], 0, ""
    for ch in s:
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
        if ch == "," and depth == 0:
            items.append(cur)
            cur = ""
        else:
            cur += ch
    return items + [cur]


def _per_robot_costs(cost_s: str, robot: RobotSpec, err) -> Optional[Tuple[CostFunction, ...]]:
    """A collaborative ID's cost list ``[C1,...,Cn]`` (one cost per robot, n = the number of robots), or None
    when the cost part is one cost for every robot. An item is a cost name (``cyc``, ``Liu2``), a
    ``name_weight`` term or the bracket notation ``[(cyc|0.2),(mechEnergy|1)]``; a list item that is a
    weighted sum must use the bracket notation (``cyc_0.2,mechEnergy_1`` inside a list is ambiguous)."""
    if not robot.collaborative or not (cost_s.startswith("[") and cost_s.endswith("]")):
        return None
    items = [x.strip() for x in _top_level_items(cost_s[1:-1])]
    if any(x.startswith("(") for x in items):
        return None  # the weighted-term notation [(cyc|0.2),(mechEnergy|1)]: one cost for every robot
    n = len(robot.robots)
    if len(items) != n:
        raise err(f"cost part: {len(items)} costs for {n} robots (one per robot, or one cost for all; write a "
                  "weighted sum inside a list as [(cyc|0.2),(mechEnergy|1)])")
    out = []
    for k, it in enumerate(items):
        try:
            out.append(parse_cost(it))
        except InputError as e:
            raise err(f"cost of robot {k + 1} ({it!r}): {e.reason}") from None
        if out[-1].is_empty:
            raise err(f"cost of robot {k + 1} is empty")
    return tuple(out)


def _parse_robot(s: str, err) -> RobotSpec:
    if not s:
        raise err("the robot part is empty (expected a module set or robot name, e.g. IMPROV)")
    collaborative = s.startswith("[")
    if collaborative:
        if not s.endswith("]"):
            raise err("robot list starts with '[' but does not end with ']'")
        items = [x.strip() for x in s[1:-1].split(",")]
        if items == [""]:
            raise err("the robot list is empty")
    else:
        if "," in s or "]" in s:
            raise err("several robots must be written as a list [R1,R2]")
        items = [s]
    refs = []
    for it in items:
        prefix = next((p for p in ("IND-", "M-", "C-") if it.startswith(p)), "")
        name = it[len(prefix):]
        if not name:
            raise err(f"robot {it!r} has a prefix but no name")
        if not _NAME_RE.match(name):
            raise err(f"invalid robot name {it!r} (letters, digits, '_', '.', '-' only)")
        refs.append(RobotRef(name, prefix))
    return RobotSpec(tuple(refs), collaborative)


def _check_task(s: str, err) -> None:
    if not s:
        raise err("the task part is empty (expected a task ID such as simple/PTP_1)")
    for seg in s.split("/"):
        if not seg:
            raise err(f"task ID {s!r} has an empty path segment (leading, trailing or double '/')")
        if seg in (".", "..") or not _SEGMENT_RE.match(seg):
            raise err(f"invalid task ID {s!r} (segments of letters, digits, '_', '.', '-', separated by '/')")


def _lookup(fn, key: str, what: str, bid_text: str):
    try:
        out = fn(key)
    except InputError:
        raise
    except (KeyError, LookupError, FileNotFoundError, ValueError) as e:
        raise InputError(f"benchmark ID {bid_text!r}: unknown {what} {key!r} ({e})") from None
    if out is None:
        raise InputError(f"benchmark ID {bid_text!r}: unknown {what} {key!r}")
    return out


def resolve(bid: BenchmarkID | str, module_set_lookup: Optional[Callable[[str], Any]] = None,
            task_lookup: Optional[Callable[[str], Any]] = None) -> ResolvedBenchmark:
    """Resolve the parts of a benchmark ID.

    ``module_set_lookup(name)`` / ``task_lookup(task_id)`` return the module set (or robot) and the task;
    they may return None or raise ``KeyError``/``FileNotFoundError``/``ValueError`` for unknown names,
    which become :class:`InputError` naming the part. Without a lookup the name itself is returned.
    """
    if isinstance(bid, str):
        bid = BenchmarkID.parse(bid)
    text = str(bid)
    robots = []
    for r in bid.robot.robots:
        what = "module set" if r.kind == "module_set" else "robot"
        robots.append(_lookup(module_set_lookup, r.name, what, text) if module_set_lookup else r.name)
    robot = tuple(robots) if bid.robot.collaborative else robots[0]
    task = _lookup(task_lookup, bid.task, "task", text) if task_lookup else bid.task
    return ResolvedBenchmark(robot, bid.cost, task)
