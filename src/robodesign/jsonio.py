"""Reading JSON files the way real CoBRA files need it, with errors that name file and field.

* ``Infinity`` / ``-Infinity`` literals are accepted (geometric_primitive_modules uses them);
  ``NaN`` is rejected: it is never a meaningful limit, mass or pose entry.
* Referenced files (meshes) are resolved inside a root folder; absolute paths and ``..`` that
  escape the folder are rejected.
"""
from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any, Sequence

from .errors import InputError, PathPart


def _find_nan(obj, path):
    if isinstance(obj, float) and math.isnan(obj):
        return path
    if isinstance(obj, dict):
        items = obj.items()
    elif isinstance(obj, list):
        items = enumerate(obj)
    else:
        return None
    for k, v in items:
        found = _find_nan(v, path + [k])
        if found is not None:
            return found
    return None


def load_json(path: str | Path, display_name: str | None = None) -> Any:
    """Parse a JSON file. Raises :class:`InputError` naming the file (and line/column) on any problem."""
    path = Path(path)
    name = display_name or str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError("file not found", file=name) from None
    except IsADirectoryError:
        raise InputError("is a folder, expected a JSON file", file=name) from None
    except (OSError, UnicodeDecodeError) as e:
        raise InputError(f"cannot read file ({e})", file=name) from None
    return loads_json(text, name)


def loads_json(text: str, display_name: str = "<string>") -> Any:
    try:
        data = json.loads(text)
    except json.JSONDecodeError as e:
        raise InputError(f"malformed JSON at line {e.lineno}, column {e.colno}: {e.msg}",
                         file=display_name) from None
    if "NaN" in text:
        where = _find_nan(data, [])
        if where is not None:
            raise InputError("NaN is not a valid value", file=display_name, path=where)
    return data


def dumps_json(obj: Any, indent: int | None = 2) -> str:
    """JSON text; infinite floats are written as ``Infinity`` (CoBRA convention), NaN is refused."""
    return json.dumps(obj, indent=indent, allow_nan=True)


def resolve_inside(root: Path, ref: str, file: str, path: Sequence[PathPart], follow_symlinks: bool = False) -> Path:
    """Resolve a file reference from a JSON file relative to ``root``; it must stay inside ``root``.

    ``package://`` prefixes are stripped (as the reference does). Absolute paths, ``..`` escapes
    are rejected with an :class:`InputError` naming the field. The check is lexical by default (a
    symlinked mesh folder is allowed for local use); ``follow_symlinks=True`` also rejects symlinks
    that lead outside (what a server handling uploads must use).
    """
    if not isinstance(ref, str) or not ref:
        raise InputError(f"expected a relative file path, got {ref!r}", file=file, path=path)
    r = ref[len("package://"):] if ref.startswith("package://") else ref
    if r.startswith(("/", "\\")) or (len(r) > 1 and r[1] == ":") or Path(r).is_absolute():
        raise InputError(f"absolute file paths are not allowed ({ref!r}); give a path relative to {root}",
                         file=file, path=path)
    root_res = root.resolve() if follow_symlinks else Path(os.path.abspath(root))
    target = (root_res / r).resolve() if follow_symlinks else Path(os.path.normpath(root_res / r))
    try:
        target.relative_to(root_res)
    except ValueError:
        raise InputError(f"file reference {ref!r} escapes its folder {root}", file=file, path=path) from None
    return target


def check_finite(value: float, file: str, path: Sequence[PathPart], allow_inf: bool = False) -> float:
    if value is None or isinstance(value, bool) or not isinstance(value, (int, float)):
        from .errors import describe_value
        raise InputError(f"expected a number, got {describe_value(value)}", file=file, path=path)
    v = float(value)
    if math.isnan(v) or (not allow_inf and math.isinf(v)):
        raise InputError(f"expected a finite number, got {value}", file=file, path=path)
    return v
