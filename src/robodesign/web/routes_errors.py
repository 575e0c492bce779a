"""How errors answer (status codes by error kind; an internal error is a 500, never a verdict) and the
security headers of every answer."""
from __future__ import annotations

import logging

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError

from robodesign.core.errors import InputError
from robodesign.web.safefiles import TooLarge
from robodesign.web.service import (
    Conflict,
    Forbidden,
    NotFound,
)
from robodesign.web.throttle import Busy
from robodesign.web.uploads import error_response
from robodesign.web.viewer_pages import ViewerFailed

log = logging.getLogger("robodesign.web")
PAGE_CSP = ("default-src 'self'; img-src 'self' data:; style-src 'self'; script-src 'none'; object-src 'none'; "
            "base-uri 'none'; form-action 'self'; frame-ancestors 'self'; frame-src 'self'")


def add_error_handlers(app: FastAPI) -> None:
    """Bad input 400 (TooLarge 413), Conflict 409, NotFound 404, Forbidden 403, a viewer that failed 503, a
    full queue 429 (with Retry-After), anything else 500; and the headers middleware."""
    def answer(status: int):
        async def handler(request, exc):
            return error_response(request, status, str(exc))
        return handler

    for kind, status in ((TooLarge, 413), (InputError, 400), (Conflict, 409), (NotFound, 404), (Forbidden, 403)):
        app.add_exception_handler(kind, answer(status))

    @app.exception_handler(RequestValidationError)
    async def _bad_params(request, exc):
        where = "; ".join(f"{'.'.join(str(x) for x in e.get('loc', ()))}: {e.get('msg')}" for e in exc.errors())
        return error_response(request, 400, f"bad request ({where})")

    @app.exception_handler(ViewerFailed)
    async def _viewer_failed(request, exc):
        resp = error_response(request, 503, str(exc))
        resp.headers["Retry-After"] = "60"
        return resp

    @app.exception_handler(Busy)
    async def _busy(request, exc):
        resp = error_response(request, 429, str(exc))
        resp.headers["Retry-After"] = str(exc.retry_after)
        return resp

    @app.exception_handler(Exception)
    async def _internal(request, exc):
        log.exception("internal error on %s", request.url.path)
        return error_response(request, 500, f"internal error ({type(exc).__name__}); the server keeps running")

    @app.middleware("http")
    async def _headers(request: Request, call_next):
        resp = await call_next(request)
        resp.headers.setdefault("X-Content-Type-Options", "nosniff")
        resp.headers.setdefault("Referrer-Policy", "same-origin")
        if resp.headers.get("content-type", "").startswith("text/html"):
            resp.headers.setdefault("Content-Security-Policy", PAGE_CSP)
        return resp
