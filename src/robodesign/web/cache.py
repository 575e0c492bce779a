"""A thread-safe least-recently-used cache bounded by the total size of its values in bytes (not by count)."""
from __future__ import annotations

import threading
from collections import OrderedDict
from typing import Hashable, Optional


class ByteLRU:
    """Keeps ``str``/``bytes`` values while their total UTF-8 size stays ≤ ``max_bytes``; a value larger than
    ``max_bytes`` on its own is not kept at all."""

    def __init__(self, max_bytes: int):
        self.max_bytes = int(max_bytes)
        self.bytes = 0
        self._items: "OrderedDict[Hashable, tuple]" = OrderedDict()
        self._lock = threading.Lock()

    @staticmethod
    def size_of(value) -> int:
        return len(value) if isinstance(value, (bytes, bytearray)) else len(value.encode("utf-8"))

    def get(self, key: Hashable) -> Optional[object]:
        with self._lock:
            item = self._items.get(key)
            if item is None:
                return None
            self._items.move_to_end(key)
            return item[0]

    def put(self, key: Hashable, value) -> None:
        size = self.size_of(value)
        with self._lock:
            old = self._items.pop(key, None)
            if old is not None:
                self.bytes -= old[1]
            if size > self.max_bytes:
                return
            self._items[key] = (value, size)
            self.bytes += size
            while self.bytes > self.max_bytes:
                _k, (_v, s) = self._items.popitem(last=False)
                self.bytes -= s

    def __len__(self) -> int:
        return len(self._items)

    def __contains__(self, key) -> bool:
        return key in self._items
