"""The goal-type registry: CoBRA goal ``type`` → the :class:`~robodesign.formats.task_spec.Goal` class, its
parser and the JSON it accepts.

The task reader dispatches every goal through this registry (the built-in types register in
``formats/task_io.py``). Goal types from other packages are found like optimizers: through the entry-point
group ``robodesign.goal_types`` (the entry point names a ``Goal`` class, registered with its ``from_json``,
``json_keys`` and ``json_schema``, or a module that calls :func:`register_goal_type` when imported). The
group is read the first time an unknown type is looked up or the registered types are listed, in every
process (spawned workers included), so a task file using such a type reads anywhere. A package may also call
:func:`register_goal_type` itself. The goal class says how the rest of robodesign handles it: ``type_name``,
``solver_kind``, ``target_poses``, ``anchor``, and for the judge ``time_window``, ``check``,
``external_wrench`` and ``referenced_goals`` (docs/architecture.md, "Where to add what").
"""
from __future__ import annotations

import difflib
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Type

from robodesign.core.errors import InputError, PathPart
from robodesign.formats.task_spec import Goal, TaskConstraint

ENTRY_POINT_GROUP = "robodesign.goal_types"


@dataclass
class GoalContext:
    """What a goal parser gets besides the goal's JSON object: its ID and constraints (already parsed),
    where it is (file name and JSON path, for errors), the task's frame resolver and package folder (for
    tolerated poses and mesh files), and case-insensitive key lookup."""
    id: str
    constraints: Tuple[TaskConstraint, ...]
    file: str
    path: List[PathPart]
    resolver: Any
    root: Any
    data: Mapping[str, Any] = field(default_factory=dict)

    def key(self, name: str) -> Tuple[str, Any]:
        """(the key as written, its value) of ``name`` matched case-insensitively; (name, None) if absent."""
        for k, v in self.data.items():
            if str(k).lower() == name.lower():
                return k, v
        return name, None

    def fail(self, message: str, *subpath: PathPart) -> InputError:
        """An :class:`InputError` naming the file and the goal's field ``subpath``."""
        return InputError(message, file=self.file, path=[*self.path, *subpath])


GoalParser = Callable[[Mapping[str, Any], GoalContext], Goal]


@dataclass(frozen=True)
class GoalType:
    name: str                      # the CoBRA type as written in files ("returnTo")
    cls: Type[Goal]
    parse: GoalParser
    keys: Tuple[str, ...] = ()     # JSON keys of the goal besides ID, type and constraints
    schema: Optional[dict] = None  # JSON Schema of the goal object (plugin types; built-ins are in task.schema.json)
    builtin: bool = False


_TYPES: Dict[str, GoalType] = {}
_entry_points_loaded = False


def register_goal_type(cls: Type[Goal], parse: Optional[GoalParser] = None, keys: Optional[Sequence[str]] = None,
                       schema: Optional[dict] = None, builtin: bool = False) -> GoalType:
    """Register the goal class ``cls`` under its ``type_name`` with its parser (default: the class's
    ``from_json(data, ctx)``). ``keys``: the goal's own JSON keys (others are dropped with a warning, as for
    built-in goals; default: the class's ``json_keys``); ``schema``: a JSON Schema the goal object must
    satisfy (default: the class's ``json_schema``). Registering the same class again replaces the entry;
    another class under a taken name is an error."""
    if not (isinstance(cls, type) and issubclass(cls, Goal)):
        raise ValueError(f"{cls!r} is not a Goal class")
    parse = parse or getattr(cls, "from_json", None)
    if parse is None:
        raise ValueError(f"{cls.__name__} has no parser: pass parse= or define the classmethod from_json(data, ctx)")
    keys = tuple(getattr(cls, "json_keys", ()) if keys is None else keys)
    schema = getattr(cls, "json_schema", None) if schema is None else schema
    name = cls.type_name
    if not name:
        raise ValueError(f"{cls.__name__}.type_name is empty")
    if not cls.solver_kind:
        raise ValueError(f"{cls.__name__}.solver_kind is empty")
    old = _TYPES.get(name.lower())
    if old is not None and old.cls is not cls and old.cls.__qualname__ != cls.__qualname__:
        raise ValueError(f"goal type {name!r} is already registered by {old.cls.__module__}.{old.cls.__qualname__}")
    gt = GoalType(name, cls, parse, tuple(keys), schema, builtin)
    _TYPES[name.lower()] = gt
    return gt


def _load_entry_points() -> None:
    global _entry_points_loaded
    if _entry_points_loaded:
        return
    _entry_points_loaded = True
    from importlib import metadata
    for ep in metadata.entry_points(group=ENTRY_POINT_GROUP):
        obj = ep.load()  # a module registers its goal types when imported
        if isinstance(obj, type) and issubclass(obj, Goal):
            register_goal_type(obj)


def goal_type(name: str, file: Optional[str] = None, path: Sequence[PathPart] = ()) -> GoalType:
    """The registered goal type ``name`` (case-insensitive); an unknown name is an InputError naming the file
    and field and suggesting the closest known type."""
    key = str(name).lower()
    if key not in _TYPES:
        _load_entry_points()
    if key not in _TYPES:
        names = known_goal_types()
        close = difflib.get_close_matches(str(name), names, n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise InputError(f"unknown goal type {name!r}{hint} ({', '.join(names)})", file=file, path=list(path))
    return _TYPES[key]


def find_goal_type(name: str) -> Optional[GoalType]:
    """The registered goal type ``name`` (case-insensitive), or None."""
    try:
        return goal_type(name)
    except InputError:
        return None


def known_goal_types() -> List[str]:
    """The names of the registered goal types, the entry-point group's included."""
    _load_entry_points()
    return [gt.name for gt in _TYPES.values()]


def plugin_goal_types() -> List[GoalType]:
    """The registered goal types that are not built in (their JSON is checked by their own schema), the
    entry-point group's included."""
    _load_entry_points()
    return [gt for gt in _TYPES.values() if not gt.builtin]
