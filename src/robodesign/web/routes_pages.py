"""The website's HTML pages: index, task, module set, leaderboard, solution (and its 3D viewer), upload and
withdrawal forms."""
from __future__ import annotations

import asyncio
import json
from typing import Tuple

from fastapi import FastAPI, Request
from fastapi.responses import HTMLResponse, RedirectResponse, Response
from starlette.concurrency import run_in_threadpool

from robodesign.core.errors import InputError
from robodesign.web import pages
from robodesign.web.service import NotFound
from robodesign.web.site import Site
from robodesign.web.uploads import Upload, decode_text, error_response, read_upload

VIEWER_CSP = ("default-src 'none'; script-src 'unsafe-inline' 'unsafe-eval' blob: data:; style-src 'unsafe-inline'; "
              "img-src data: blob:; font-src data:; connect-src data: blob:; worker-src blob:; base-uri 'none'; "
              "form-action 'none'; frame-ancestors 'self'")


def add_routes(app: FastAPI, site: Site) -> None:
    """The HTML pages (and the stylesheet, the API docs page, the health check)."""
    _add_site_routes(app, site)
    _add_catalog_pages(app, site)
    _add_solution_pages(app, site)
    _add_upload_pages(app, site)


def _add_site_routes(app: FastAPI, site: Site) -> None:
    """The stylesheet, the API docs page, the health check and the index."""
    bench = site.bench

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


def _add_catalog_pages(app: FastAPI, site: Site) -> None:
    """The task, module set and leaderboard pages."""
    bench = site.bench

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


def _add_solution_pages(app: FastAPI, site: Site) -> None:
    """A solution's page, its 3D viewer and the withdrawal form."""
    bench, viewer, viewer_cache = site.bench, site.viewer, site.viewer_cache

    @app.get("/solutions/{sid}", response_class=HTMLResponse, include_in_schema=False)
    def solution_page(sid: str):
        row = bench.solution_row(sid)
        ok, note = viewer_available()
        return pages.solution_page(row, ok, note)

    @app.get("/solutions/{sid}/viewer", response_class=HTMLResponse, include_in_schema=False)
    async def solution_viewer(sid: str):
        ok, note = viewer_available()
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


def _add_upload_pages(app: FastAPI, site: Site) -> None:
    """The upload form and its submission."""
    submit = site.submit

    @app.get("/upload", response_class=HTMLResponse, include_in_schema=False)
    def upload_page():
        return pages.upload_form()

    def read_form_upload(up: Upload):
        f = up.file("file", "solution")
        if f is None:
            raise InputError("choose a solution file")
        name, data = f
        return decode_text(data, name), name, {k: up.fields.get(k) for k in ("author", "email", "affiliation")}, \
            up.fields.get("token"), False

    @app.post("/upload", response_class=HTMLResponse, include_in_schema=False)
    async def upload_submit(request: Request):
        _job, fut, _pos, _extra = await submit(request, read_form_upload)
        out = await asyncio.wrap_future(fut)
        if "result" not in out:
            return error_response(request, out["status"], out["body"]["detail"])
        return HTMLResponse(pages.upload_result(out["result"]), status_code=out["status"])


def viewer_available() -> Tuple[bool, str]:
    try:
        from robodesign.viewer import solution_page  # noqa: F401  (only: is it there?)
    except ImportError as e:
        return False, f"The 3D viewer is not available on this server ({e})."
    return True, ""
