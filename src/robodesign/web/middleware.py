"""ASGI middleware of the website: the request-body cap and deadline (before any parsing), the per-client
rate limits and the bodies-being-received guard, HEAD answered as GET."""
from __future__ import annotations

import asyncio
import math
import time
from typing import Dict, Optional
from urllib.parse import unquote_to_bytes

from fastapi.responses import HTMLResponse, JSONResponse

from robodesign.web import pages
from robodesign.web.site_settings import MiB
from robodesign.web.throttle import RateLimiter


# ------------------------------------------------------------------------------------------------------------
# request size limit (pure ASGI: applies before any parsing)
# ------------------------------------------------------------------------------------------------------------
class BodyTooLarge(Exception):
    pass


class BodyTooSlow(Exception):
    pass


class BodyLimitMiddleware:
    """Caps every request body at ``limit`` bytes (by Content-Length, and counted while it streams in) and at
    ``timeout`` seconds to arrive: a huge upload is cut off at the limit, a slow one gets 408."""

    def __init__(self, app, limit: int, timeout: float = 120.0):
        self.app, self.limit, self.timeout = app, limit, timeout

    async def _reject(self, scope, send):
        await _plain_error(scope, send, 413, f"request body too large: the limit is {self.limit} bytes "
                                             f"({self.limit / MiB:.1f} MiB)")

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        for k, v in scope.get("headers", []):
            if k == b"content-length":
                try:
                    if int(v) > self.limit:
                        return await self._reject(scope, send)
                except ValueError:
                    resp = JSONResponse({"detail": "bad Content-Length header"}, status_code=400)
                    return await resp(scope, receive, send)
        received = 0
        started = False
        body_done = False
        deadline = time.monotonic() + self.timeout

        async def limited_receive():
            nonlocal received, body_done
            if body_done:
                return await receive()
            try:
                message = await asyncio.wait_for(receive(), max(0.0, deadline - time.monotonic()))
            except asyncio.TimeoutError:
                raise BodyTooSlow() from None
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > self.limit:
                    raise BodyTooLarge()
                body_done = not message.get("more_body", False)
            return message

        async def tracking_send(message):
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
            await send(message)

        try:
            await self.app(scope, limited_receive, tracking_send)
        except BodyTooLarge:
            if started:
                raise
            await self._reject(scope, send)
        except BodyTooSlow:
            if started:
                raise
            msg = f"the request body did not arrive within {self.timeout:g} s"
            await _plain_error(scope, send, 408, msg)


async def _plain_error(scope, send, status: int, msg: str, headers: Optional[Dict[str, str]] = None):
    resp = (JSONResponse({"detail": msg}, status_code=status) if scope["path"].startswith("/api/")
            else HTMLResponse(pages.error_page(status, msg), status_code=status))
    for k, v in (headers or {}).items():
        resp.headers[k] = v
    resp.headers["Connection"] = "close"
    await resp(scope, _noop_receive, send)


class GuardMiddleware:
    """Before anything else: a NUL character anywhere in the path or query is 400, and each client (its address;
    behind a reverse proxy on 127.0.0.1 uvicorn takes it from X-Forwarded-For) has two token buckets, one for
    reading (GET/HEAD) and one for writing (uploads, withdrawals, registrations): an empty bucket is 429 with
    Retry-After. ``/healthz`` and ``/static/`` are not limited."""

    def __init__(self, app, reads: RateLimiter, writes: RateLimiter):
        self.app, self.reads, self.writes = app, reads, writes

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        path = scope.get("path", "")
        if "\x00" in path or b"\x00" in scope.get("query_string", b"") \
                or b"\x00" in unquote_to_bytes(scope.get("query_string", b"")):
            return await _plain_error(scope, send, 400, "the URL contains a NUL character")
        if path != "/healthz" and not path.startswith("/static/"):
            client = (scope.get("client") or ("?", 0))[0]
            write = scope.get("method", "GET") not in ("GET", "HEAD", "OPTIONS")
            wait = (self.writes if write else self.reads).wait_time(client)
            if wait > 0:
                retry = max(1, math.ceil(wait))
                what = "uploads/changes" if write else "requests"
                return await _plain_error(scope, send, 429, f"too many {what} from your address; retry in {retry} s",
                                          {"Retry-After": str(retry)})
        return await self.app(scope, receive, send)


class HeadMiddleware:
    """``HEAD`` on every page and API route: answered as ``GET`` without the body (same status and headers)."""

    def __init__(self, app):
        self.app = app

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http" or scope.get("method") != "HEAD":
            return await self.app(scope, receive, send)

        async def no_body(message):
            if message["type"] == "http.response.body":
                if message.get("more_body", False):
                    return
                message = {"type": "http.response.body", "body": b"", "more_body": False}
            await send(message)

        return await self.app({**scope, "method": "GET"}, receive, no_body)


async def _noop_receive():
    return {"type": "http.disconnect"}


