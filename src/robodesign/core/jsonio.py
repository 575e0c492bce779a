"""Reading JSON files the way real CoBRA files need it, with errors that name file and field.

* ``Infinity`` / ``-Infinity`` literals are accepted (geometric_primitive_modules uses them);
  ``NaN`` is rejected: it is never a meaningful limit, mass or pose entry. So are numbers beyond the
  float range (``1e400`` would silently become infinite), NUL characters and lone UTF-16 surrogates
  (``"\\ud800"``: not text, no database or file can store it) in strings and keys, and nesting deeper
  than :data:`MAX_DEPTH` levels: every format read through here gets these checks once.
* Referenced files (meshes) are resolved inside a root folder; absolute paths and ``..`` that
  escape the folder are rejected.
"""
from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path
from typing import Any, Dict, List, Sequence, Tuple

from robodesign.core.errors import InputError, PathPart, format_json_path

MAX_DEPTH = 100
"""Deepest nesting of arrays/objects accepted in any file (CoBRA files nest fewer than 10 levels)."""

_BIG_EXPONENT = re.compile(r"[eE]\+?[0-9]{3}")
_SURROGATE_ESCAPE = re.compile(r"\\u[dD][89a-fA-F]")  # a \uD800-\uDFFF escape (a pair is fine, a lone one not)
_SURROGATE = re.compile("[\ud800-\udfff]")
_DIGITS_TO_ZERO = str.maketrans("123456789", "000000000")


def _suspicious(text: str) -> bool:
    """Whether the text may hold a value the checks below reject (then it is parsed the slower way).

    Cheap C-speed scans: a 30 MB trajectory file costs ~0.15 s here against ~0.4 s for json.loads.
    """
    return ("NaN" in text or "\\u0000" in text or _BIG_EXPONENT.search(text) is not None
            or _SURROGATE_ESCAPE.search(text) is not None or _SURROGATE.search(text) is not None
            or "0" * 300 in text.translate(_DIGITS_TO_ZERO))


class _OutOfRange:
    """A number literal beyond the float range (``1e400``, a 400-digit integer), kept for the error message."""
    __slots__ = ("literal",)

    def __init__(self, literal: str):
        self.literal = literal


def _checked_float(s: str):
    v = float(s)
    return _OutOfRange(s) if math.isinf(v) else v


def _checked_int(s: str):
    if len(s) - s.startswith("-") > 309:  # beyond 1.8e308 (and Python's 4300-digit conversion limit)
        return _OutOfRange(s)
    v = int(s)
    try:
        float(v)
    except OverflowError:
        return _OutOfRange(s)
    return v


# out-of-range numbers become markers whose place _problem reports
_CHECKED: Dict[str, Any] = {"parse_float": _checked_float, "parse_int": _checked_int}


def _shown(text: str) -> str:
    text = _SURROGATE.sub(lambda m: f"\\u{ord(m.group()):04x}", text.replace("\0", "\\u0000"))
    return text if len(text) <= 24 else text[:20] + "..."


def _bad_scalar(v):
    tv = type(v)
    if tv is float and v != v:
        return "NaN is not a valid value"
    if tv is _OutOfRange:
        return f"number {_shown(v.literal)} is out of range (beyond 1.8e308)"
    if tv is str:
        if "\0" in v:
            return "NUL character (\\u0000) in a string"
        m = _SURROGATE.search(v)
        if m is not None:
            return f"lone UTF-16 surrogate (\\u{ord(m.group()):04x}) in a string: not text"
    return None


def _problem(root, values: bool):
    """(JSON path, reason) of the first value no robodesign file may hold, else None.

    Always checks the nesting depth; with ``values`` also NaN, out-of-range numbers and NUL characters
    in strings and keys. Iterative, so it cannot itself exceed the recursion limit.
    """
    if type(root) is not dict and type(root) is not list:
        reason = _bad_scalar(root) if values else None
        return ([], reason) if reason else None
    stack: List[Tuple[Any, Tuple[PathPart, ...]]] = [(root, ())]
    while stack:
        node, path = stack.pop()
        if len(path) >= MAX_DEPTH:
            return format_json_path(path[:6]) + "...", f"nested deeper than {MAX_DEPTH} levels"
        children: List[Tuple[Any, Tuple[PathPart, ...]]] = []
        for k, v in (node.items() if type(node) is dict else enumerate(node)):
            if values and type(k) is str:
                if "\0" in k:
                    return list(path) + [_shown(k)], "NUL character (\\u0000) in a key"
                m = _SURROGATE.search(k)
                if m is not None:
                    return list(path) + [_shown(k)], f"lone UTF-16 surrogate (\\u{ord(m.group()):04x}) in a key: not text"
            tv = type(v)
            if tv is dict or tv is list:
                children.append((v, path + (k,)))
            elif values:
                reason = _bad_scalar(v)
                if reason:
                    return list(path) + [k], reason
        stack.extend(reversed(children))
    return None


def _too_deep_position(text: str):
    """(line, column) where the nesting first exceeds MAX_DEPTH, brackets inside strings ignored."""
    depth = 0
    for m in re.finditer(r'"(?:[^"\\]|\\.)*"|[\[\]{}]', text):
        c = m.group()
        if c in "[{":
            depth += 1
            if depth > MAX_DEPTH:
                line = text.count("\n", 0, m.start()) + 1
                return line, m.start() - text.rfind("\n", 0, m.start())
        elif c in "]}":
            depth -= 1
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
    """Parse JSON text; any problem is an :class:`InputError` naming ``display_name`` and the field.

    Rejected besides malformed JSON: nesting deeper than :data:`MAX_DEPTH`, ``NaN``, numbers beyond the
    float range (``1e400``, integers of more than 309 digits), NUL characters and lone surrogates in strings
    or keys.
    """
    values = _suspicious(text)
    try:
        try:
            data = json.loads(text, **(_CHECKED if values else {}))
        except ValueError as e:
            if isinstance(e, json.JSONDecodeError) or values:
                raise
            values = True  # an integer beyond Python's digit limit: parse again to find it
            data = json.loads(text, **_CHECKED)
    except json.JSONDecodeError as e:
        raise InputError(f"malformed JSON at line {e.lineno}, column {e.colno}: {e.msg}",
                         file=display_name) from None
    except RecursionError:
        where = _too_deep_position(text)
        at = f" at line {where[0]}, column {where[1]}" if where else ""
        raise InputError(f"JSON nested deeper than {MAX_DEPTH} levels{at}", file=display_name) from None
    found = _problem(data, values)
    if found is not None:
        raise InputError(found[1], file=display_name, path=found[0])
    return data


def check_values(data: Any, display_name: str) -> Any:
    """The checks of :func:`loads_json` (depth, NaN, NUL) on data read another way (YAML configs)."""
    found = _problem(data, True)
    if found is not None:
        raise InputError(found[1], file=display_name, path=found[0])
    return data


def dumps_json(obj: Any, indent: int | None = 2) -> str:
    """JSON text; infinite floats are written as ``Infinity`` (CoBRA convention), NaN is refused."""
    return json.dumps(obj, indent=indent, allow_nan=True)


def write_json(path: str | Path, obj: Any) -> Path:
    """Write ``obj`` as JSON (:func:`dumps_json`) atomically: a temporary file beside it, then a rename, so a
    reader never sees half a file; creates the parent folder."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    tmp = p.with_suffix(p.suffix + ".tmp")
    tmp.write_text(dumps_json(obj))
    tmp.replace(p)
    return p


def resolve_inside(root: Path, ref: object, file: str, path: Sequence[PathPart], follow_symlinks: bool = False) -> Path:
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
        from robodesign.core.errors import describe_value
        raise InputError(f"expected a number, got {describe_value(value)}", file=file, path=path)
    v = float(value)
    if math.isnan(v) or (not allow_inf and math.isinf(v)):
        raise InputError(f"expected a finite number, got {value}", file=file, path=path)
    return v
