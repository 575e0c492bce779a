"""The FastAPI application: HTML pages and the JSON API of the benchmark website.

``create_app(db_url, data_dir)`` builds it; ``robodesign serve`` runs it with uvicorn. See docs/website.md.
"""
from __future__ import annotations

import asyncio
import base64
import binascii
import contextlib
import hmac
import json
import logging
import math
import os
import secrets
import time
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence, Tuple
from urllib.parse import quote, unquote_to_bytes

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, JSONResponse, RedirectResponse, Response
from starlette.concurrency import run_in_threadpool
from starlette.datastructures import UploadFile

from robodesign.core.errors import InputError
from robodesign.core.jsonio import loads_json
from robodesign.core.paths import assets_dir
from robodesign.web import pages
from robodesign.web.cache import ByteLRU
from robodesign.web.safefiles import TooLarge, check_name
from robodesign.web.service import (
    Bench,
    Conflict,
    Forbidden,
    Limits,
    NotFound,
    Settings,
    check_token,
    clean_json,
    files_source,
    hash_token,
    solution_summary,
)
from robodesign.web.throttle import Busy, CheckQueue, RateLimiter
from robodesign.web.viewer_pages import ViewerFailed, ViewerPages
from robodesign.web.workers import ProcessChecker, ThreadChecker

log = logging.getLogger("robodesign.web")
MiB = 1 << 20
MAX_FORM_FILES = 256  # files in one multipart body (more: send a zip); the parser stops at the first one beyond
MAX_FORM_FIELDS = 32  # other fields of one form

PAGE_CSP = ("default-src 'self'; img-src 'self' data:; style-src 'self'; script-src 'none'; object-src 'none'; "
            "base-uri 'none'; form-action 'self'; frame-ancestors 'self'; frame-src 'self'")
VIEWER_CSP = ("default-src 'none'; script-src 'unsafe-inline' 'unsafe-eval' blob: data:; style-src 'unsafe-inline'; "
              "img-src data: blob:; font-src data:; connect-src data: blob:; worker-src blob:; base-uri 'none'; "
              "form-action 'none'; frame-ancestors 'self'")


# ------------------------------------------------------------------------------------------------------------
# request size limit (pure ASGI: applies before any parsing)
# ------------------------------------------------------------------------------------------------------------
class _BodyTooLarge(Exception):
    pass


class _BodyTooSlow(Exception):
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
                raise _BodyTooSlow() from None
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > self.limit:
                    raise _BodyTooLarge()
                body_done = not message.get("more_body", False)
            return message

        async def tracking_send(message):
            nonlocal started
            if message["type"] == "http.response.start":
                started = True
            await send(message)

        try:
            await self.app(scope, limited_receive, tracking_send)
        except _BodyTooLarge:
            if started:
                raise
            await self._reject(scope, send)
        except _BodyTooSlow:
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


# ------------------------------------------------------------------------------------------------------------
# helpers
# ------------------------------------------------------------------------------------------------------------
def _is_api(request: Request) -> bool:
    return request.url.path.startswith("/api/")


def _error(request: Request, status: int, message: str) -> Response:
    bench = getattr(request.app.state, "bench", None)
    if bench is not None:  # never show the server's own paths
        message = message.replace(str(bench.data), "<data>")
    if _is_api(request):
        return JSONResponse({"detail": message}, status_code=status)
    return HTMLResponse(pages.error_page(status, message), status_code=status)


def _decode(raw: bytes, name: str) -> str:
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise InputError(f"not UTF-8 text (byte {e.start})", file=name) from None


class Upload:
    """A parsed request body: form fields, uploaded files, or the raw body (JSON / zip)."""

    def __init__(self):
        self.fields: Dict[str, str] = {}
        self.files: Dict[str, List[Tuple[str, bytes]]] = {}
        self.raw: Optional[bytes] = None
        self.content_type = ""

    def file(self, *names) -> Optional[Tuple[str, bytes]]:
        for n in names:
            if self.files.get(n):
                return self.files[n][0]
        return None

    def field(self, name: str, request: Request) -> Optional[str]:
        v = self.fields.get(name)
        if v is None:
            v = request.query_params.get(name)
        return v


async def read_upload(request: Request) -> Upload:
    up = Upload()
    ct = request.headers.get("content-type", "").split(";")[0].strip().lower()
    up.content_type = ct
    if ct in ("multipart/form-data", "application/x-www-form-urlencoded"):
        try:
            form = await request.form(max_files=MAX_FORM_FILES, max_fields=MAX_FORM_FIELDS, max_part_size=4 * MiB)
        except (_BodyTooLarge, _BodyTooSlow):
            raise
        except Exception as e:  # malformed multipart body, or too many parts (stopped at the first beyond)
            if "Too many" in str(e):
                raise TooLarge(f"{str(e).removeprefix('400: ')} (send many files as one zip)") from None
            raise InputError(f"malformed form data ({e})") from None
        for key, value in form.multi_items():
            if isinstance(value, UploadFile):
                data = await value.read()
                up.files.setdefault(key, []).append((value.filename or key, data))
            else:
                up.fields[key] = str(value)
    else:
        up.raw = await request.body()
    return up


def _is_zip(name: str, data: bytes) -> bool:
    return name.lower().endswith(".zip") or data[:4] == b"PK\x03\x04"


def _b64_files(obj, where: str) -> Dict[str, bytes]:
    if obj is None:
        return {}
    if not isinstance(obj, dict):
        raise InputError("expected an object {relative path: base64 content}", path=[where])
    out = {}
    for k, v in obj.items():
        if not isinstance(v, str):
            raise InputError("expected base64 text", path=[where, k])
        try:
            out[k] = base64.b64decode(v, validate=True)
        except (binascii.Error, ValueError):
            raise InputError("not valid base64", path=[where, k]) from None
    return out


def _float_param(request: Request, name: str) -> Optional[float]:
    v = request.query_params.get(name)
    if v is None or v == "":
        return None
    try:
        f = float(v)
    except ValueError:
        raise InputError(f"query parameter {name}: expected a number, got {v!r}") from None
    if not math.isfinite(f):
        raise InputError(f"query parameter {name}: expected a finite number, got {v!r}")
    return f


# ------------------------------------------------------------------------------------------------------------
# the app
# ------------------------------------------------------------------------------------------------------------
ADMIN_TOKEN_ENV = "ROBODESIGN_ADMIN_TOKEN"


def create_app(db_url: Optional[str] = None, data_dir: str | Path = "robodesign_data",
               seed: Sequence[str | Path] = (), seed_builtin: bool = True, max_request_bytes: int = 20 * MiB,
               max_unzipped_bytes: int = 200 * MiB, check_workers: Optional[int] = None, *,
               admin_token: Optional[str] = None, open_registration: bool = False, queue_size: int = 8,
               per_client_queue: int = 2, upload_rate: float = 30.0, read_rate: float = 20.0,
               body_timeout: float = 120.0, viewer_cache_bytes: int = 64 * MiB, big_upload_bytes: int = 2 * MiB,
               limits: Optional[Limits] = None, check_processes: bool = False, viewer_timeout: float = 60.0) -> FastAPI:
    """Build the website (docs/website.md). ``db_url``: SQLAlchemy URL (default SQLite ``<data_dir>/bench.db``;
    ``postgresql://`` uses psycopg 3). ``seed``: extra folders to register tasks/module sets from at startup (after
    the built-in ``assets/`` when ``seed_builtin``).

    Registering tasks and module sets needs ``admin_token`` (default: the ``ROBODESIGN_ADMIN_TOKEN`` environment
    variable) unless ``open_registration``. ``queue_size`` uploads may wait for the ``check_workers`` checker
    threads, at most ``per_client_queue`` per client; uploads larger than ``big_upload_bytes`` use at most all threads
    but one; ``check_processes``: run the checks in as many separate processes (robodesign.web.workers).
    ``upload_rate`` (per minute) and ``read_rate`` (per second) are the per-client rate limits (0 = none);
    ``body_timeout``: seconds a request body may take to arrive; ``limits``: the size caps
    of one solution; ``viewer_timeout``: seconds a viewer page may take to build (robodesign.web.viewer_pages)."""
    settings = Settings(data_dir=Path(data_dir), db_url=db_url, max_request_bytes=int(max_request_bytes),
                        max_unzipped_bytes=int(max_unzipped_bytes), seed_dirs=tuple(Path(s) for s in seed),
                        seed_builtin=seed_builtin, limits=limits or Limits())
    if check_workers:
        settings.check_workers = int(check_workers)
    if admin_token is None:
        admin_token = os.environ.get(ADMIN_TOKEN_ENV) or None
    if admin_token is not None and len(admin_token) < 16:
        raise InputError("the admin token must have at least 16 characters")
    bench = Bench(settings)
    bench.seed(([assets_dir()] if seed_builtin else []) + list(settings.seed_dirs))
    queue = CheckQueue(settings.check_workers, queue_size, per_client_queue)
    checker = ProcessChecker(settings, settings.check_workers) if check_processes else ThreadChecker(bench)

    @contextlib.asynccontextmanager
    async def lifespan(_app):
        resume_pending()
        yield
        queue.close()
        checker.close()
        viewer.close()
        bench.close()

    app = FastAPI(title="robodesign benchmark", version="1", lifespan=lifespan, docs_url=None,
                  redoc_url=None, openapi_url="/api/openapi.json")
    app.state.bench, app.state.queue, app.state.checker = bench, queue, checker
    app.state.viewer_cache = viewer_cache = ByteLRU(viewer_cache_bytes)
    app.state.viewer = viewer = ViewerPages(settings, timeout=viewer_timeout)
    app.add_middleware(BodyLimitMiddleware, limit=settings.max_request_bytes, timeout=body_timeout)
    app.add_middleware(GuardMiddleware, reads=RateLimiter(read_rate, max(1.0, 5 * read_rate)),
                       writes=RateLimiter(upload_rate / 60.0, max(1.0, upload_rate / 3)))
    app.add_middleware(HeadMiddleware)

    def require_admin(request: Request) -> None:
        if open_registration:
            return
        if admin_token is None:
            raise Forbidden("registering tasks and module sets is disabled on this server: start it with an admin "
                            f"token ({ADMIN_TOKEN_ENV} or --admin-token) or with --open-registration")
        auth = request.headers.get("authorization", "")
        given = request.headers.get("x-admin-token") or (auth[7:] if auth.lower().startswith("bearer ") else "")
        if not hmac.compare_digest(given.encode("utf-8", "replace"), admin_token.encode("utf-8")):
            raise Forbidden("registering tasks and module sets is an admin action: send the admin token as "
                            "'Authorization: Bearer <token>' or 'X-Admin-Token'" + (" (the one given is wrong)"
                                                                                    if given else ""))

    # ---------------------------------------------------------------- errors and headers
    @app.exception_handler(TooLarge)
    async def _too_large(request, exc):
        return _error(request, 413, str(exc))

    @app.exception_handler(InputError)
    async def _bad_input(request, exc):
        return _error(request, 400, str(exc))

    @app.exception_handler(RequestValidationError)
    async def _bad_params(request, exc):
        where = "; ".join(f"{'.'.join(str(x) for x in e.get('loc', ()))}: {e.get('msg')}" for e in exc.errors())
        return _error(request, 400, f"bad request ({where})")

    @app.exception_handler(Conflict)
    async def _conflict(request, exc):
        return _error(request, 409, str(exc))

    @app.exception_handler(NotFound)
    async def _not_found(request, exc):
        return _error(request, 404, str(exc))

    @app.exception_handler(Forbidden)
    async def _forbidden(request, exc):
        return _error(request, 403, str(exc))

    @app.exception_handler(ViewerFailed)
    async def _viewer_failed(request, exc):
        resp = _error(request, 503, str(exc))
        resp.headers["Retry-After"] = "60"
        return resp

    @app.exception_handler(Busy)
    async def _busy(request, exc):
        resp = _error(request, 429, str(exc))
        resp.headers["Retry-After"] = str(exc.retry_after)
        return resp

    @app.exception_handler(Exception)
    async def _internal(request, exc):
        log.exception("internal error on %s", request.url.path)
        return _error(request, 500, f"internal error ({type(exc).__name__}); the server keeps running")

    @app.middleware("http")
    async def _headers(request: Request, call_next):
        resp = await call_next(request)
        resp.headers.setdefault("X-Content-Type-Options", "nosniff")
        resp.headers.setdefault("Referrer-Policy", "same-origin")
        if resp.headers.get("content-type", "").startswith("text/html"):
            resp.headers.setdefault("Content-Security-Policy", PAGE_CSP)
        return resp

    # ---------------------------------------------------------------- the check queue
    async def submit(request: Request, read: Callable[[Upload], tuple], durable: bool = False):
        """Read the upload (its body within the body deadline, counted among the bodies being received, never in
        the check queue), then take a place in the check queue (429 when full) and put it in line; parsing,
        validation and the checker run on a checker thread/process (``Bench.check_upload``: 201 / 422 / 400 / 413).
        ``durable`` (async uploads): the upload is committed to the database before this returns, and resumed
        after a restart. → (job, future of {status, body, result}, place in line when it joined, extra answer
        fields)."""
        client = (request.client.host if request.client else "?")
        queue.start_receiving(client)
        try:
            up = await read_upload(request)
        finally:
            queue.done_receiving(client)
        text, fname, meta, token, unwrap = read(up)
        big = len(text) > big_upload_bytes
        job = queue.reserve(client)
        extra: dict = {}
        try:
            if durable:
                if token:
                    check_token(token)
                else:  # the answer tells the token now: the result may be read after a restart
                    token = extra["token"] = secrets.token_urlsafe(24)
                token_hash = await run_in_threadpool(hash_token, token)
                await run_in_threadpool(bench.add_pending, job.id, text, fname, meta, token_hash, unwrap, big)
                kw = {"token_hash": token_hash, "pending": job.id}
                fut = queue.submit(job, lambda: checker.check(text, fname, meta, None, unwrap, **kw), big=big)
            else:
                fut = queue.submit(job, lambda: checker.check(text, fname, meta, token, unwrap), big=big)
        except BaseException:
            queue.release(job)
            raise
        return job, fut, queue.status(job)["position"], extra

    def resume_pending() -> int:
        """Put the async uploads that a stopped server had accepted but not judged back in line."""
        rows = bench.pending_checks()
        for row in rows:
            job = queue.restore(row.job_id)
            args = (row.text, row.fname, json.loads(row.meta_json or "{}"), None, row.unwrap)
            kw = {"token_hash": row.token_hash, "pending": row.job_id}
            queue.submit(job, lambda a=args, k=kw: checker.check(*a, **k), big=row.big)
        if rows:
            log.info("resumed %d pending check(s) of async uploads", len(rows))
        return len(rows)

    def wants_async(request: Request) -> bool:
        return request.query_params.get("async", "") in ("1", "true", "yes") or \
            "respond-async" in request.headers.get("prefer", "")

    # ---------------------------------------------------------------- HTML pages
    @app.get("/static/style.css", include_in_schema=False)
    def css():
        return Response(pages.CSS, media_type="text/css", headers={"Cache-Control": "max-age=3600"})

    @app.get("/api/docs", response_class=HTMLResponse, include_in_schema=False)
    def api_docs():
        return pages.api_docs(app.openapi())

    @app.get("/healthz", include_in_schema=False)
    def healthz():
        return {"ok": True}

    @app.get("/", response_class=HTMLResponse, include_in_schema=False)
    def index():
        return pages.index(bench.tasks(), bench.module_sets(), bench.cost_functions(), bench.benchmarks())

    @app.get("/tasks/{task_id:path}", response_class=HTMLResponse, include_in_schema=False)
    def task_page(task_id: str):
        row = bench.task_row(task_id)
        parsed = bench.parsed_task(task_id)
        warnings = [w.replace(str(bench.data), "<data>") for w in bench.task(task_id).warnings]
        return pages.task_page(row, parsed, bench.module_sets(), bench.cost_functions(),
                               bench.benchmark_counter(task_id), warnings)

    @app.get("/modulesets/{name}", response_class=HTMLResponse, include_in_schema=False)
    def moduleset_page(name: str):
        return pages.moduleset_page(bench.module_set_row(name), bench.module_set(name))

    @app.get("/leaderboard", include_in_schema=False)
    def leaderboard_form(request: Request):
        qp = request.query_params
        ms, cost, task = qp.get("moduleset", ""), qp.get("cost", ""), qp.get("task", "")
        if not (ms and cost and task):
            raise InputError("choose a module set, a cost and a task")
        robots = json.loads(bench.task_row(task).robots or "[]")
        bid = pages.benchmark_id_for(ms, cost, task, len(robots))  # a collaborative task: that set for every robot
        return RedirectResponse(pages.bid_url(bid), status_code=303)

    @app.get("/leaderboard/{bid:path}", response_class=HTMLResponse, include_in_schema=False)
    def leaderboard_page(bid: str):
        board, rows = bench.leaderboard(bid)
        return pages.leaderboard(board, rows)

    @app.get("/solutions/{sid}", response_class=HTMLResponse, include_in_schema=False)
    def solution_page(sid: str):
        row = bench.solution_row(sid)
        ok, note = _viewer_available()
        return pages.solution_page(row, ok, note)

    @app.get("/solutions/{sid}/viewer", response_class=HTMLResponse, include_in_schema=False)
    async def solution_viewer(sid: str):
        ok, note = _viewer_available()
        if not ok:
            raise NotFound(note)
        rid = (await run_in_threadpool(bench.solution_row, sid)).id
        html = viewer_cache.get(rid)
        if html is None:  # built in the viewer process (bounded in time, memory, frames and size), kept as a file
            path = await run_in_threadpool(viewer.get, rid)
            html = await run_in_threadpool(path.read_bytes)
            viewer_cache.put(rid, html)
        return Response(html, media_type="text/html; charset=utf-8",
                        headers={"Content-Security-Policy": VIEWER_CSP, "Cache-Control": "max-age=3600"})

    @app.post("/solutions/{sid}/withdraw", response_class=HTMLResponse, include_in_schema=False)
    async def withdraw_form(sid: str, request: Request):
        up = await read_upload(request)
        res = await run_in_threadpool(bench.withdraw, sid, up.fields.get("token"))
        return HTMLResponse(pages.layout("Withdrawn", f'<div class="card" id="result"><p>Solution #{res["id"]} was '
                                         f'withdrawn from <a href="{pages.e(pages.bid_url(res["benchmark_id"]))}">'
                                         f'{pages.e(res["benchmark_id"])}</a>.</p></div>'))

    @app.get("/upload", response_class=HTMLResponse, include_in_schema=False)
    def upload_page():
        return pages.upload_form()

    def read_form_upload(up: Upload):
        f = up.file("file", "solution")
        if f is None:
            raise InputError("choose a solution file")
        name, data = f
        return _decode(data, name), name, {k: up.fields.get(k) for k in ("author", "email", "affiliation")}, \
            up.fields.get("token"), False

    @app.post("/upload", response_class=HTMLResponse, include_in_schema=False)
    async def upload_submit(request: Request):
        _job, fut, _pos, _extra = await submit(request, read_form_upload)
        out = await asyncio.wrap_future(fut)
        if "result" not in out:
            return _error(request, out["status"], out["body"]["detail"])
        return HTMLResponse(pages.upload_result(out["result"]), status_code=out["status"])

    # ---------------------------------------------------------------- JSON API
    @app.get("/api/tasks")
    def api_tasks():
        out = []
        for t in bench.tasks():
            robots = json.loads(t.robots or "[]")
            out.append({"id": t.task_id, "name": t.name, "tags": json.loads(t.tags or "[]"), "goals": t.n_goals,
                        "obstacles": t.n_obstacles, "assets": [a["path"] for a in json.loads(t.assets or "[]")],
                        "origin": t.origin, "url": pages.task_url(t.task_id), "collaborative": bool(robots),
                        **({"robots": robots} if robots else {})})
        return out

    @app.get("/api/tasks/{task_id:path}")
    def api_task(task_id: str):
        return Response(bench.task_row(task_id, file=True).json, media_type="application/json")

    @app.post("/api/tasks", status_code=201)
    async def api_add_task(request: Request):
        require_admin(request)
        up = await read_upload(request)
        if up.raw is not None:
            if _is_zip("", up.raw) or up.content_type in ("application/zip", "application/x-zip-compressed"):
                created = await run_in_threadpool(bench.add_tasks_from_zip, up.raw, "upload.zip")
            else:
                data = loads_json(_decode(up.raw, "request body"), "request body")
                if isinstance(data, dict) and "task" in data and "header" not in data:
                    files = _b64_files(data.get("files"), "files")
                    text = json.dumps(data["task"])
                else:
                    files, text = {}, _decode(up.raw, "request body")
                created = [await run_in_threadpool(bench.add_task, text, files_source(files), "task.json")]
        else:
            f = up.file("file", "task", "zip")
            if f is None:
                raise InputError("send the task as form field 'task' (JSON file, with asset files in 'files') "
                                 "or 'file' (zip)")
            name, data = f
            if _is_zip(name, data):
                created = await run_in_threadpool(bench.add_tasks_from_zip, data, name)
            else:
                files = {n: d for n, d in up.files.get("files", [])}
                created = [await run_in_threadpool(bench.add_task, _decode(data, name), files_source(files), name)]
        return JSONResponse({"tasks": created}, status_code=201)

    @app.get("/api/modulesets")
    def api_modulesets():
        return [{"name": m.name, "modules": json.loads(m.module_ids or "[]"),
                 "assets": [a["path"] for a in json.loads(m.assets or "[]")], "origin": m.origin,
                 "url": f"/modulesets/{quote(m.name)}"} for m in bench.module_sets()]

    @app.get("/api/modulesets/{name}")
    def api_moduleset(name: str):
        return Response(bench.module_set_row(name, file=True).json, media_type="application/json")

    @app.post("/api/modulesets", status_code=201)
    async def api_add_moduleset(request: Request):
        require_admin(request)
        up = await read_upload(request)
        name = up.field("name", request)
        if name:
            check_name(name)
        if up.raw is not None:
            if _is_zip("", up.raw):
                res = await run_in_threadpool(bench.add_module_set_from_zip, up.raw, "upload.zip", name)
            else:
                data = loads_json(_decode(up.raw, "request body"), "request body")
                if isinstance(data, dict) and "modules" in data and isinstance(data.get("name"), str):
                    name = data["name"]
                    files = _b64_files(data.get("files"), "files")
                    text = json.dumps(data["modules"]) if not isinstance(data["modules"], list) else None
                    if text is None:  # {"name", "modules": [...]} is the modules.json itself plus a name
                        body = {k: v for k, v in data.items() if k not in ("name", "files")}
                        text = json.dumps(body)
                else:
                    files, text = {}, _decode(up.raw, "request body")
                if not name:
                    raise InputError("give the module set a name (query parameter or field 'name')")
                res = await run_in_threadpool(bench.add_module_set, check_name(name), text, files_source(files))
        else:
            f = up.file("file", "modules", "zip")
            if f is None:
                raise InputError("send the module set as form field 'modules' (modules.json, with mesh files in "
                                 "'files') or 'file' (zip)")
            fname, data = f
            if _is_zip(fname, data):
                res = await run_in_threadpool(bench.add_module_set_from_zip, data, fname, name)
            else:
                if not name:
                    raise InputError("give the module set a name (form field 'name')")
                files = {n: d for n, d in up.files.get("files", [])}
                res = await run_in_threadpool(bench.add_module_set, name, _decode(data, fname), files_source(files))
        return JSONResponse(res, status_code=201)

    @app.get("/api/costs")
    def api_costs():
        return [{"name": c.name, "descriptor": c.descriptor, "description": c.description}
                for c in bench.cost_functions()]

    @app.get("/api/benchmarks")
    def api_benchmarks():
        return clean_json(bench.benchmarks())

    def read_api_upload(request: Request):
        def read(up: Upload):
            token = request.headers.get("x-author-token")
            if up.raw is not None:  # the solution, or {"solution": ..., "author": ...} (unwrapped by the checker)
                meta = {k: request.query_params.get(k) for k in ("author", "email", "affiliation")}
                return _decode(up.raw, "request body"), "solution.json", meta, token, True
            f = up.file("file", "solution")
            if f is None:
                raise InputError("send the solution as form field 'file' (a CoBRA solution JSON file)")
            fname, raw = f
            meta = {k: up.fields.get(k) for k in ("author", "email", "affiliation")}
            return _decode(raw, fname), fname, meta, up.fields.get("token") or token, False
        return read

    @app.post("/api/solutions", status_code=201)
    async def api_submit(request: Request):
        is_async = wants_async(request)
        job, fut, position, extra = await submit(request, read_api_upload(request), durable=is_async)
        if is_async:  # stored already: answered only now
            return JSONResponse({**queue.status(job), "status_url": f"/api/checks/{job.id}", **extra},
                                status_code=202, headers={"Location": f"/api/checks/{job.id}"})
        out = await asyncio.wrap_future(fut)
        return JSONResponse({**out["body"], "queue_position": position}, status_code=out["status"])

    @app.get("/api/checks/{job_id}")
    def api_check_status(job_id: str):
        job = queue.get(job_id)
        if job is None:  # an async upload of an earlier run of the server, or one judged over an hour ago
            stored = bench.pending_status(job_id)
            if stored is None:
                raise NotFound("unknown check")
            return clean_json(stored)
        return clean_json(queue.status(job))

    @app.get("/api/queue")
    def api_queue():
        return queue.stats()

    @app.get("/api/solutions")
    def api_solutions(request: Request):
        qp = request.query_params
        collab = qp.get("collaborative", "")
        if collab not in ("", "0", "1", "true", "false"):
            raise InputError(f"query parameter collaborative: expected 1 or 0, got {collab[:40]!r}")
        rows = bench.list_solutions(task=qp.get("task") or None, cost=qp.get("cost") or None,
                                    moduleset=qp.get("moduleset") or None, min_cost=_float_param(request, "min_cost"),
                                    max_cost=_float_param(request, "max_cost"),
                                    collaborative=None if collab == "" else collab in ("1", "true"))
        return [solution_summary(r) for r in rows]

    @app.get("/api/solutions/{sid}")
    def api_solution(sid: str):
        row = bench.solution_row(sid)
        out = solution_summary(row)
        out["email"] = None  # never published
        out["verdict"] = json.loads(row.verdict_json or "{}")
        return clean_json(out)

    @app.get("/api/solutions/{sid}/json")
    def api_solution_json(sid: str):
        return Response(bench.solution_text(sid), media_type="application/json")

    @app.delete("/api/solutions/{sid}")
    async def api_withdraw(sid: str, request: Request):
        return await run_in_threadpool(bench.withdraw, sid, request.headers.get("x-author-token"))

    @app.get("/api/leaderboard/{bid:path}")
    def api_leaderboard(bid: str):
        board, rows = bench.leaderboard(bid)
        entries = []
        for k, r in enumerate(rows):
            s = solution_summary(r)
            s["rank"] = k + 1
            entries.append(s)
        out = {"benchmark_id": board.display, "task": board.task_id, "collaborative": board.collaborative,
               "entries": entries}
        if board.collaborative:  # ordered by totalCost, ties by the cost tuple (docs/collaborative.md)
            key = json.loads(board.robots_key)
            out.update(module_sets=key["sets"], cost_keys=key["costs"], order="totalCost, then the cost tuple")
        else:
            out.update(module_set=board.module_set, cost_key=board.cost_key)
        return out

    return app




def _viewer_available() -> Tuple[bool, str]:
    try:
        from robodesign.viewer import solution_page  # noqa: F401  (only: is it there?)
    except ImportError as e:
        return False, f"The 3D viewer is not available on this server ({e})."
    return True, ""
