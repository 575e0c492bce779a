"""The FastAPI application: HTML pages and the JSON API of the benchmark website.

``create_app(db_url, data_dir)`` builds it; ``robodesign serve`` runs it with uvicorn. See docs/website.md.
"""
from __future__ import annotations

import asyncio
import base64
import binascii
import contextlib
import json
import logging
import math
import threading
from collections import OrderedDict
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple
from urllib.parse import quote

from fastapi import FastAPI, Request
from fastapi.responses import HTMLResponse, JSONResponse, RedirectResponse, Response
from starlette.datastructures import UploadFile

from ..errors import InputError
from ..jsonio import loads_json
from ..paths import assets_dir
from . import pages
from .safefiles import TooLarge, check_name
from .service import (Bench, Conflict, Forbidden, NotFound, Settings, SubmitResult, clean_json, files_source,
                      solution_summary)

log = logging.getLogger("robodesign.web")
MiB = 1 << 20

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


class BodyLimitMiddleware:
    def __init__(self, app, limit: int):
        self.app, self.limit = app, limit

    async def _reject(self, scope, send):
        msg = (f"request body too large: the limit is {self.limit} bytes "
               f"({self.limit / MiB:.1f} MiB)")
        resp = (JSONResponse({"detail": msg}, status_code=413) if scope["path"].startswith("/api/")
                else HTMLResponse(pages.error_page(413, msg), status_code=413))
        resp.headers["Connection"] = "close"
        await resp(scope, _noop_receive, send)

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

        async def limited_receive():
            nonlocal received
            message = await receive()
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > self.limit:
                    raise _BodyTooLarge()
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
            form = await request.form(max_files=5000, max_fields=200, max_part_size=4 * MiB)
        except _BodyTooLarge:
            raise
        except Exception as e:  # malformed multipart body
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
    if math.isnan(f):
        raise InputError(f"query parameter {name}: NaN is not allowed")
    return f


# ------------------------------------------------------------------------------------------------------------
# the app
# ------------------------------------------------------------------------------------------------------------
def create_app(db_url: Optional[str] = None, data_dir: str | Path = "robodesign_data",
               seed: Sequence[str | Path] = (), seed_builtin: bool = True, max_request_bytes: int = 20 * MiB,
               max_unzipped_bytes: int = 200 * MiB, check_workers: Optional[int] = None) -> FastAPI:
    """Build the website. ``db_url``: SQLAlchemy URL (default SQLite ``<data_dir>/bench.db``; ``postgresql://``
    uses psycopg 3). ``seed``: extra folders to register tasks/module sets from at startup (after the built-in
    ``assets/`` when ``seed_builtin``)."""
    settings = Settings(data_dir=Path(data_dir), db_url=db_url, max_request_bytes=int(max_request_bytes),
                        max_unzipped_bytes=int(max_unzipped_bytes), seed_dirs=tuple(Path(s) for s in seed),
                        seed_builtin=seed_builtin)
    if check_workers:
        settings.check_workers = int(check_workers)
    bench = Bench(settings)
    bench.seed(([assets_dir()] if seed_builtin else []) + list(settings.seed_dirs))

    @contextlib.asynccontextmanager
    async def lifespan(_app):
        yield
        bench.close()

    app = FastAPI(title="robodesign benchmark", version="1", lifespan=lifespan, docs_url="/api/docs",
                  redoc_url=None, openapi_url="/api/openapi.json")
    app.state.bench = bench
    app.add_middleware(BodyLimitMiddleware, limit=settings.max_request_bytes)

    async def in_pool(fn, *args, **kw):
        return await asyncio.wrap_future(bench.pool.submit(fn, *args, **kw))

    # ---------------------------------------------------------------- errors and headers
    @app.exception_handler(TooLarge)
    async def _too_large(request, exc):
        return _error(request, 413, str(exc))

    @app.exception_handler(InputError)
    async def _bad_input(request, exc):
        return _error(request, 400, str(exc))

    @app.exception_handler(Conflict)
    async def _conflict(request, exc):
        return _error(request, 409, str(exc))

    @app.exception_handler(NotFound)
    async def _not_found(request, exc):
        return _error(request, 404, str(exc))

    @app.exception_handler(Forbidden)
    async def _forbidden(request, exc):
        return _error(request, 403, str(exc))

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

    # ---------------------------------------------------------------- HTML pages
    @app.get("/static/style.css", include_in_schema=False)
    def css():
        return Response(pages.CSS, media_type="text/css", headers={"Cache-Control": "max-age=3600"})

    @app.get("/healthz", include_in_schema=False)
    def healthz():
        return {"ok": True}

    @app.get("/", response_class=HTMLResponse, include_in_schema=False)
    def index():
        return pages.index(bench.tasks(), bench.module_sets(), bench.cost_functions(), bench.benchmarks())

    @app.get("/tasks/{task_id:path}", response_class=HTMLResponse, include_in_schema=False)
    def task_page(task_id: str):
        row = bench.task_row(task_id)
        task = bench.task(task_id)
        warnings = [w.replace(str(bench.data), "<data>") for w in task.warnings]
        return pages.task_page(row, task, bench.module_sets(), bench.cost_functions(),
                               bench.counts_for_task(task_id), warnings)

    @app.get("/modulesets/{name}", response_class=HTMLResponse, include_in_schema=False)
    def moduleset_page(name: str):
        return pages.moduleset_page(bench.module_set_row(name), bench.module_set(name))

    @app.get("/leaderboard", include_in_schema=False)
    def leaderboard_form(request: Request):
        qp = request.query_params
        ms, cost, task = qp.get("moduleset", ""), qp.get("cost", ""), qp.get("task", "")
        if not (ms and cost and task):
            raise InputError("choose a module set, a cost and a task")
        bid = f"M-{ms}:{cost}:{task}"
        return RedirectResponse(pages.bid_url(bid), status_code=303)

    @app.get("/leaderboard/{bid:path}", response_class=HTMLResponse, include_in_schema=False)
    def leaderboard_page(bid: str):
        display, ms, _key, tid, rows = bench.leaderboard(bid)
        return pages.leaderboard(display, ms, tid, rows)

    @app.get("/solutions/{sid}", response_class=HTMLResponse, include_in_schema=False)
    def solution_page(sid: int):
        row = bench.solution_row(sid)
        ok, note = _viewer_available()
        return pages.solution_page(row, ok, note)

    viewer_cache: "OrderedDict[int, str]" = OrderedDict()
    viewer_lock = threading.Lock()

    @app.get("/solutions/{sid}/viewer", response_class=HTMLResponse, include_in_schema=False)
    def solution_viewer(sid: int):
        ok, note = _viewer_available()
        if not ok:
            raise NotFound(note)
        with viewer_lock:
            html = viewer_cache.get(sid)
        if html is None:
            from ..viewer import solution_page as render
            row = bench.solution_row(sid)
            html = render(bench.task(row.task_id), bench.solution(sid), bench.module_set(row.module_set),
                          verdict=json.loads(row.verdict_json or "{}") or None)
            with viewer_lock:
                viewer_cache[sid] = html
                while len(viewer_cache) > 16:
                    viewer_cache.popitem(last=False)
        return HTMLResponse(html, headers={"Content-Security-Policy": VIEWER_CSP})

    @app.post("/solutions/{sid}/withdraw", response_class=HTMLResponse, include_in_schema=False)
    async def withdraw_form(sid: int, request: Request):
        up = await read_upload(request)
        res = await in_pool(bench.withdraw, sid, up.fields.get("token"))
        return HTMLResponse(pages.layout("Withdrawn", f'<div class="card" id="result"><p>Solution #{sid} was '
                                         f'withdrawn from <a href="{pages.e(pages.bid_url(res["benchmark_id"]))}">'
                                         f'{pages.e(res["benchmark_id"])}</a>.</p></div>'))

    @app.get("/upload", response_class=HTMLResponse, include_in_schema=False)
    def upload_page():
        return pages.upload_form()

    @app.post("/upload", response_class=HTMLResponse, include_in_schema=False)
    async def upload_submit(request: Request):
        up = await read_upload(request)
        f = up.file("file", "solution")
        if f is None:
            raise InputError("choose a solution file")
        name, data = f
        res: SubmitResult = await in_pool(bench.submit_solution, _decode(data, name), name,
                                          up.fields.get("author"), up.fields.get("email"),
                                          up.fields.get("affiliation"), up.fields.get("token") or None)
        return HTMLResponse(pages.upload_result(res), status_code=201 if res.valid else 422)

    # ---------------------------------------------------------------- JSON API
    @app.get("/api/tasks")
    def api_tasks():
        return [{"id": t.task_id, "name": t.name, "tags": json.loads(t.tags or "[]"), "goals": t.n_goals,
                 "obstacles": t.n_obstacles, "assets": [a["path"] for a in json.loads(t.assets or "[]")],
                 "origin": t.origin, "url": pages.task_url(t.task_id)} for t in bench.tasks()]

    @app.get("/api/tasks/{task_id:path}")
    def api_task(task_id: str):
        return Response(bench.task_row(task_id).json, media_type="application/json")

    @app.post("/api/tasks", status_code=201)
    async def api_add_task(request: Request):
        up = await read_upload(request)
        if up.raw is not None:
            if _is_zip("", up.raw) or up.content_type in ("application/zip", "application/x-zip-compressed"):
                created = await in_pool(bench.add_tasks_from_zip, up.raw, "upload.zip")
            else:
                data = loads_json(_decode(up.raw, "request body"), "request body")
                if isinstance(data, dict) and "task" in data and "header" not in data:
                    files = _b64_files(data.get("files"), "files")
                    text = json.dumps(data["task"])
                else:
                    files, text = {}, _decode(up.raw, "request body")
                created = [await in_pool(bench.add_task, text, files_source(files), "task.json")]
        else:
            f = up.file("file", "task", "zip")
            if f is None:
                raise InputError("send the task as form field 'task' (JSON file, with asset files in 'files') "
                                 "or 'file' (zip)")
            name, data = f
            if _is_zip(name, data):
                created = await in_pool(bench.add_tasks_from_zip, data, name)
            else:
                files = {n: d for n, d in up.files.get("files", [])}
                created = [await in_pool(bench.add_task, _decode(data, name), files_source(files), name)]
        return JSONResponse({"tasks": created}, status_code=201)

    @app.get("/api/modulesets")
    def api_modulesets():
        return [{"name": m.name, "modules": json.loads(m.module_ids or "[]"),
                 "assets": [a["path"] for a in json.loads(m.assets or "[]")], "origin": m.origin,
                 "url": f"/modulesets/{quote(m.name)}"} for m in bench.module_sets()]

    @app.get("/api/modulesets/{name}")
    def api_moduleset(name: str):
        return Response(bench.module_set_row(name).json, media_type="application/json")

    @app.post("/api/modulesets", status_code=201)
    async def api_add_moduleset(request: Request):
        up = await read_upload(request)
        name = up.field("name", request)
        if name:
            check_name(name)
        if up.raw is not None:
            if _is_zip("", up.raw):
                res = await in_pool(bench.add_module_set_from_zip, up.raw, "upload.zip", name)
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
                res = await in_pool(bench.add_module_set, check_name(name), text, files_source(files))
        else:
            f = up.file("file", "modules", "zip")
            if f is None:
                raise InputError("send the module set as form field 'modules' (modules.json, with mesh files in "
                                 "'files') or 'file' (zip)")
            fname, data = f
            if _is_zip(fname, data):
                res = await in_pool(bench.add_module_set_from_zip, data, fname, name)
            else:
                if not name:
                    raise InputError("give the module set a name (form field 'name')")
                files = {n: d for n, d in up.files.get("files", [])}
                res = await in_pool(bench.add_module_set, name, _decode(data, fname), files_source(files))
        return JSONResponse(res, status_code=201)

    @app.get("/api/costs")
    def api_costs():
        return [{"name": c.name, "descriptor": c.descriptor, "description": c.description}
                for c in bench.cost_functions()]

    @app.get("/api/benchmarks")
    def api_benchmarks():
        return clean_json(bench.benchmarks())

    @app.post("/api/solutions", status_code=201)
    async def api_submit(request: Request):
        up = await read_upload(request)
        token = request.headers.get("x-author-token")
        if up.raw is not None:
            text = _decode(up.raw, "request body")
            fname = "solution.json"
            meta = {k: request.query_params.get(k) for k in ("author", "email", "affiliation")}
            data = loads_json(text, fname)
            if isinstance(data, dict) and "solution" in data and "taskID" not in data:
                sol = data["solution"]
                text = sol if isinstance(sol, str) else json.dumps(sol)
                for k in ("author", "email", "affiliation"):
                    if data.get(k) is not None:
                        if not isinstance(data[k], str):
                            raise InputError("expected a string", file="request body", path=[k])
                        meta[k] = data[k]
                if data.get("token") is not None:
                    token = str(data["token"])
        else:
            f = up.file("file", "solution")
            if f is None:
                raise InputError("send the solution as form field 'file' (a CoBRA solution JSON file)")
            fname, raw = f
            text = _decode(raw, fname)
            meta = {k: up.fields.get(k) for k in ("author", "email", "affiliation")}
            token = up.fields.get("token") or token
        res: SubmitResult = await in_pool(bench.submit_solution, text, fname, meta["author"], meta["email"],
                                          meta["affiliation"], token or None)
        return JSONResponse(res.to_json(), status_code=201 if res.valid else 422)

    @app.get("/api/solutions")
    def api_solutions(request: Request):
        qp = request.query_params
        rows = bench.list_solutions(task=qp.get("task") or None, cost=qp.get("cost") or None,
                                    moduleset=qp.get("moduleset") or None, min_cost=_float_param(request, "min_cost"),
                                    max_cost=_float_param(request, "max_cost"))
        return [solution_summary(r) for r in rows]

    @app.get("/api/solutions/{sid}")
    def api_solution(sid: int):
        row = bench.solution_row(sid)
        out = solution_summary(row)
        out["email"] = None  # never published
        out["verdict"] = json.loads(row.verdict_json or "{}")
        return clean_json(out)

    @app.get("/api/solutions/{sid}/json")
    def api_solution_json(sid: int):
        return Response(bench.solution_row(sid).solution_json, media_type="application/json")

    @app.delete("/api/solutions/{sid}")
    async def api_withdraw(sid: int, request: Request):
        return await in_pool(bench.withdraw, sid, request.headers.get("x-author-token"))

    @app.get("/api/leaderboard/{bid:path}")
    def api_leaderboard(bid: str):
        display, ms, key, tid, rows = bench.leaderboard(bid)
        entries = []
        for k, r in enumerate(rows):
            s = solution_summary(r)
            s["rank"] = k + 1
            entries.append(s)
        return {"benchmark_id": display, "task": tid, "module_set": ms, "cost_key": key, "entries": entries}

    return app




def _viewer_available() -> Tuple[bool, str]:
    try:
        from ..viewer import solution_page  # noqa: F401  (only: is it there?)
    except ImportError as e:
        return False, f"The 3D viewer is not available on this server ({e})."
    return True, ""
