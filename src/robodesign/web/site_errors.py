"""What the benchmark site's logic raises besides InputError (HTTP 400; TooLarge 413): Conflict (409),
NotFound (404), Forbidden (403), and AlreadyJudged (an upload whose judging another process finished)."""
from __future__ import annotations

from robodesign.core.errors import RobodesignError


class Conflict(RobodesignError):
    pass


class NotFound(RobodesignError):
    pass


class Forbidden(RobodesignError):
    pass


class AlreadyJudged(Exception):
    """An async upload's job was finished by another server process (it stays stored once)."""
