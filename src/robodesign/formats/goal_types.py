"""The goal-type registry: CoBRA goal ``type`` → the :class:`~robodesign.formats.task_spec.Goal` subclass, its
parser and the JSON it accepts.

The task reader dispatches every goal through this registry (the built-in types register in
``formats/task_io.py``). A goal type from another package registers itself with :func:`register_goal_type`
when it is imported; a package may also name the module that does so under the entry-point group
``robodesign.goal_types``, which is loaded the first time an unknown type is looked up (so a task file using
it reads in any process, worker processes included). The goal class says how the rest of robodesign
handles it (``type_name``, ``solver_kind``, ``target_poses``, ``anchor``); subclassing a built-in goal
inherits the built-in's check, solver handler and view.
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


def register_goal_type(cls: Type[Goal], parse: GoalParser, keys: Sequence[str] = (), schema: Optional[dict] = None,
                       builtin: bool = False) -> GoalType:
    """Register the goal class ``cls`` under its ``type_name`` with its parser. ``keys``: the goal's own JSON
    keys (others are dropped with a warning, as for built-in goals); ``schema``: a JSON Schema the goal
    object must satisfy. Registering the same class again replaces the entry; another class under a taken
    name is an error."""
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
    from importlib.metadata import entry_points
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        ep.load()  # the module registers its goal types when imported


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
    return [gt.name for gt in _TYPES.values()]


def plugin_goal_types() -> List[GoalType]:
    """The registered goal types that are not built in (their JSON is checked by their own schema)."""
    return [gt for gt in _TYPES.values() if not gt.builtin]
