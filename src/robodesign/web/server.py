"""The HTTP server as ``robodesign serve`` runs the site: uvicorn (h11) with the timeouts and limits it lacks.

uvicorn bounds neither the time a client may take to send a request's headers nor the number of open connections,
and every failed ``accept()`` (out of file descriptors) logs a traceback. Here:

* :class:`GuardedH11Protocol`: a connection must deliver a request's complete headers within ``header_timeout``
  seconds of being opened (and the next request's within that time of the previous answer: an idle keep-alive
  connection is closed after ``keep_alive`` seconds as before); at most ``max_connections`` connections are open
  at once (a connection beyond is closed at once, before it costs anything but its socket). The body's deadline is
  the application's (``--body-timeout``, :class:`robodesign.web.app.BodyLimitMiddleware`).
* :class:`RateLimitFilter` on the server's loggers: a repeated log line (the same text from the same logger) is
  written at most ``burst`` times per ``window`` seconds, its traceback only once; the next one shown says how many
  were dropped.
* :func:`raise_fd_limit`: the soft limit of open files raised to the hard one (at most 65,536).

docs/website.md ("Production") says how to run the site behind a reverse proxy as well.
"""
from __future__ import annotations

import gc
import logging
import threading
import time
from typing import Dict, Optional, Tuple

from uvicorn.protocols.http.h11_impl import H11Protocol

log = logging.getLogger("robodesign.web")

LOGGERS = ("asyncio", "uvicorn", "uvicorn.error", "uvicorn.access", "robodesign.web")


class RateLimitFilter(logging.Filter):
    """Let through at most ``burst`` records of one kind (logger, message and its arguments, exception type) per
    ``window`` seconds (so distinct access-log lines all pass); only the first of a window keeps its traceback. The
    first record of a kind after suppressed ones says how many were dropped."""

    def __init__(self, burst: int = 5, window: float = 10.0, clock=time.monotonic, max_kinds: int = 1000):
        super().__init__()
        self.burst, self.window, self.clock, self.max_kinds = int(burst), float(window), clock, max_kinds
        self._seen: Dict[Tuple, list] = {}  # kind → [window start, count in window, suppressed since last shown]
        self._lock = threading.Lock()

    def filter(self, record: logging.LogRecord) -> bool:
        exc = record.exc_info[0].__name__ if record.exc_info and record.exc_info[0] else ""
        kind = (record.name, str(record.msg)[:200], str(record.args)[:200], exc)  # access lines differ by args
        now = self.clock()
        with self._lock:
            st = self._seen.get(kind)
            if st is None:
                if len(self._seen) >= self.max_kinds:
                    self._seen.clear()
                st = self._seen[kind] = [now, 0, 0]
            if now - st[0] >= self.window:
                st[0], st[1] = now, 0
            st[1] += 1
            if st[1] > self.burst:
                st[2] += 1
                return False
            dropped, st[2] = st[2], 0
        if st[1] > 1 and record.exc_info:  # one traceback per window is enough
            record.exc_info, record.exc_text = None, None
        if dropped:
            record.msg = f"{record.msg} [{dropped} more like this suppressed]"
        return True


_installed: Dict[str, RateLimitFilter] = {}


def install_log_limits(burst: int = 5, window: float = 10.0) -> RateLimitFilter:
    """Put one :class:`RateLimitFilter` on the loggers of the server (:data:`LOGGERS`), once."""
    f = _installed.get("filter")
    if f is None:
        f = _installed["filter"] = RateLimitFilter(burst, window)
        for name in LOGGERS:
            logging.getLogger(name).addFilter(f)
    return f


def raise_fd_limit(want: int = 65536) -> int:
    """Raise the soft limit of open file descriptors towards ``want`` (never above the hard limit) → the limit."""
    try:
        import resource
        soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
        target = want if hard == resource.RLIM_INFINITY else min(want, hard)
        if soft != resource.RLIM_INFINITY and soft < target:
            resource.setrlimit(resource.RLIMIT_NOFILE, (target, hard))
            soft = target
        return int(soft)
    except (ImportError, ValueError, OSError):
        return -1


class GuardedH11Protocol(H11Protocol):
    """uvicorn's h11 protocol with a header deadline and a connection cap (set by :func:`guarded_protocol`)."""

    header_timeout: float = 10.0
    max_connections: int = 1000
    refused = 0  # connections closed at once because of the cap (all servers of the class)
    timed_out = 0  # connections closed because their headers did not arrive in time

    def connection_made(self, transport) -> None:  # type: ignore[override]
        self._header_timer: Optional[object] = None
        self._refused = len(self.connections) >= self.max_connections
        if self._refused:
            type(self).refused += 1
            log.warning("connection limit (%d) reached: closing new connections", self.max_connections)
            self.transport = transport
            transport.abort()
            return
        super().connection_made(transport)
        self._arm_header_timer()

    def _arm_header_timer(self) -> None:
        self._cancel_header_timer()
        self._cycle_at_arm = self.cycle
        self._header_timer = self.loop.call_later(self.header_timeout, self._header_deadline)

    def _cancel_header_timer(self) -> None:
        timer = getattr(self, "_header_timer", None)
        if timer is not None:
            timer.cancel()
            self._header_timer = None

    def _header_deadline(self) -> None:
        self._header_timer = None
        if self.cycle is self._cycle_at_arm and not self.transport.is_closing():
            type(self).timed_out += 1
            log.info("closing a connection whose request headers did not arrive within %g s", self.header_timeout)
            self.transport.close()

    def data_received(self, data: bytes) -> None:
        super().data_received(data)
        if self._header_timer is not None and self.cycle is not self._cycle_at_arm:
            self._cancel_header_timer()  # a request's headers have arrived

    def on_response_complete(self) -> None:
        super().on_response_complete()
        if not self.transport.is_closing():
            self._arm_header_timer()  # the next request's headers have the same deadline

    def connection_lost(self, exc) -> None:
        self._cancel_header_timer()
        if getattr(self, "_refused", False):
            return  # refused at once: uvicorn never set it up
        super().connection_lost(exc)


def guarded_protocol(header_timeout: float = 10.0, max_connections: int = 1000) -> type:
    """A :class:`GuardedH11Protocol` class with these settings (its own counters)."""
    return type("GuardedH11Protocol", (GuardedH11Protocol,),
                {"header_timeout": float(header_timeout), "max_connections": int(max_connections),
                 "refused": 0, "timed_out": 0})


def server_config(app, host: str = "127.0.0.1", port: int = 8000, *, header_timeout: float = 10.0,
                  keep_alive: float = 5.0, max_connections: int = 1000, log_level: str = "info"):
    """The uvicorn configuration ``robodesign serve`` runs ``app`` with (docs/website.md, "Production")."""
    import uvicorn
    return uvicorn.Config(app, host=host, port=port, log_level=log_level, http=guarded_protocol(header_timeout,
                                                                                                 max_connections),
                          limit_concurrency=max_connections + 1, backlog=2048, h11_max_incomplete_event_size=16 * 1024,
                          server_header=False,
                          timeout_keep_alive=keep_alive)  # type: ignore[arg-type]  # uvicorn says int; float seconds work


def freeze_startup_objects() -> int:
    """Move what the server process holds at start-up (the libraries, the app and its seeded site: ~130,000
    objects) out of the cyclic garbage collector's reach: they live as long as the process, and each full pass
    over them took 88–193 ms, a page-latency spike every few hundred requests (docs/benchmarks.md). A decision
    for the serving process, not for the app (an app built in a test process must not freeze its objects).
    Returns how many objects are frozen."""
    gc.collect()
    gc.freeze()
    return gc.get_freeze_count()


def serve(app, host: str, port: int, **settings) -> None:
    """Run ``app`` until stopped (Ctrl-C / SIGTERM), with :func:`server_config` ``settings``."""
    import uvicorn
    raise_fd_limit()
    config = server_config(app, host, port, **settings)
    config.load()  # uvicorn configures its loggers here: the filters go on after
    install_log_limits()
    freeze_startup_objects()
    try:
        uvicorn.Server(config).run()
    except KeyboardInterrupt:  # uvicorn re-raises the Ctrl-C it shut down on: a requested stop, exit 0
        pass
