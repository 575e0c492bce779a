"""Warnings collected while reading one input file (task or module set).

Loading never fails for something the reference implementation tolerates (an unknown key it ignores, a
visual mesh that cannot be read): such things are collected here and shown once. A message that occurs
at many places (the same unknown key in every obstacle) is reported once, with the first place and the
number of places.
"""
from __future__ import annotations

import difflib
import re
from typing import Dict, List, Optional, Sequence, Tuple

from robodesign.core.errors import PathPart, format_json_path


class InputWarnings:
    """Ordered, de-duplicated warnings; ``messages`` gives one line per distinct warning."""

    def __init__(self):
        self._items: Dict[str, List] = {}  # dedup key → [file, first path, message, count]

    def add(self, file: Optional[str], path: Sequence[PathPart], message: str, dedup: Optional[str] = None) -> None:
        where = format_json_path(list(path))
        key = dedup if dedup is not None else f"{file}|{where}|{message}"
        if key in self._items:
            self._items[key][3] += 1
        else:
            self._items[key] = [file, where, message, 1]

    def ignored_key(self, file: Optional[str], path: Sequence[PathPart], key, known: Sequence[str] = ()) -> None:
        """An unknown key the reference ignores: dropped from the model, reported once per (kind of place, key)."""
        close = difflib.get_close_matches(str(key), list(known), n=1) if known else []
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        general = re.sub(r"\[\d+\]", "[*]", format_json_path(list(path) + [str(key)]))
        self.add(file, list(path) + [str(key)], f"unknown key {str(key)!r} ignored{hint}", dedup=f"{file}|{general}")

    @property
    def messages(self) -> Tuple[str, ...]:
        out = []
        for file, where, message, count in self._items.values():
            prefix = (f"{file}: " if file else "") + (f"{where}: " if where else "")
            more = f" (and at {count - 1} more place{'s' if count > 2 else ''} like it)" if count > 1 else ""
            out.append(prefix + message + more)
        return tuple(out)
