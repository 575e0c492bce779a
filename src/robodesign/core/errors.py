"""Errors raised for bad user input.

Every error about a file names the file and the JSON path of the offending field, e.g.
``modules.json: modules[3].joints[0].limits.positionLower: expected a number, got "abc"``.
The CLI turns :class:`InputError` into a one-line message and exit code 2, never a traceback.
"""
from __future__ import annotations

from pathlib import Path
from typing import Iterable, Sequence, Union

PathPart = Union[str, int]


def format_json_path(parts: Iterable[PathPart]) -> str:
    """``["modules", 3, "joints", 0, "limits"]`` → ``modules[3].joints[0].limits``."""
    out = ""
    for p in parts:
        if isinstance(p, int):
            out += f"[{p}]"
        else:
            out += ("." if out else "") + str(p)
    return out


class RobodesignError(Exception):
    """Base class of all errors robodesign raises on purpose."""


class InputError(RobodesignError, ValueError):
    """Bad input: a file, a field, a CLI argument. ``str(e)`` is the full user-facing message."""

    def __init__(self, message: str, file: Union[str, Path, None] = None,
                 path: Sequence[PathPart] | str | None = None):
        self.file = str(file) if file is not None else None
        if isinstance(path, str):
            self.json_path = path
        else:
            self.json_path = format_json_path(path) if path else ""
        self.reason = message
        prefix = ""
        if self.file:
            prefix += f"{self.file}: "
        if self.json_path:
            prefix += f"{self.json_path}: "
        super().__init__(prefix + message)


class AssemblyError(InputError):
    """A module order or connection graph that cannot be assembled."""


class InfeasibleError(RobodesignError):
    """The design cannot do what is asked (a path no timing satisfies, ipopt finds no trajectory, no pose
    inside a tolerance is found): the solve pipeline reports it as the failing stage. Never bad input and
    never a bug, so it is neither an :class:`InputError` nor caught as a plain ``Exception``."""


def describe_value(v) -> str:
    """Short, JSON-ish rendering of a value for error messages."""
    import json
    try:
        s = json.dumps(v)
    except (TypeError, ValueError):
        s = repr(v)
    return s if len(s) <= 60 else s[:57] + "..."
