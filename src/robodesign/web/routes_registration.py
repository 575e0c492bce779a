"""The JSON API of what solutions are judged against: tasks, module sets (listing, files, registration by
the admin) and cost functions."""
from __future__ import annotations

import json
from urllib.parse import quote

from fastapi import FastAPI, Request
from fastapi.responses import JSONResponse, Response
from starlette.concurrency import run_in_threadpool

from robodesign.core.errors import InputError
from robodesign.core.jsonio import loads_json
from robodesign.web import pages
from robodesign.web.safefiles import check_name
from robodesign.web.service import files_source
from robodesign.web.site import Site
from robodesign.web.uploads import b64_files, decode_text, is_zip, read_upload


def add_routes(app: FastAPI, site: Site) -> None:
    """/api/tasks, /api/modulesets, /api/costs."""
    _add_task_routes(app, site)
    _add_moduleset_routes(app, site)
    _add_cost_routes(app, site)


def _add_task_routes(app: FastAPI, site: Site) -> None:
    """/api/tasks: the list, a task's file, registration."""
    bench, require_admin = site.bench, site.require_admin

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
            if is_zip("", up.raw) or up.content_type in ("application/zip", "application/x-zip-compressed"):
                created = await run_in_threadpool(bench.add_tasks_from_zip, up.raw, "upload.zip")
            else:
                data = loads_json(decode_text(up.raw, "request body"), "request body")
                if isinstance(data, dict) and "task" in data and "header" not in data:
                    files = b64_files(data.get("files"), "files")
                    text = json.dumps(data["task"])
                else:
                    files, text = {}, decode_text(up.raw, "request body")
                created = [await run_in_threadpool(bench.add_task, text, files_source(files), "task.json")]
        else:
            f = up.file("file", "task", "zip")
            if f is None:
                raise InputError("send the task as form field 'task' (JSON file, with asset files in 'files') "
                                 "or 'file' (zip)")
            name, data = f
            if is_zip(name, data):
                created = await run_in_threadpool(bench.add_tasks_from_zip, data, name)
            else:
                files = {n: d for n, d in up.files.get("files", [])}
                created = [await run_in_threadpool(bench.add_task, decode_text(data, name), files_source(files), name)]
        return JSONResponse({"tasks": created}, status_code=201)


def _add_moduleset_routes(app: FastAPI, site: Site) -> None:
    """/api/modulesets: the list, a set's file, registration."""
    bench, require_admin = site.bench, site.require_admin

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
            if is_zip("", up.raw):
                res = await run_in_threadpool(bench.add_module_set_from_zip, up.raw, "upload.zip", name)
            else:
                data = loads_json(decode_text(up.raw, "request body"), "request body")
                if isinstance(data, dict) and "modules" in data and isinstance(data.get("name"), str):
                    name = data["name"]
                    files = b64_files(data.get("files"), "files")
                    text = json.dumps(data["modules"]) if not isinstance(data["modules"], list) else None
                    if text is None:  # {"name", "modules": [...]} is the modules.json itself plus a name
                        body = {k: v for k, v in data.items() if k not in ("name", "files")}
                        text = json.dumps(body)
                else:
                    files, text = {}, decode_text(up.raw, "request body")
                if not name:
                    raise InputError("give the module set a name (query parameter or field 'name')")
                res = await run_in_threadpool(bench.add_module_set, check_name(name), text, files_source(files))
        else:
            f = up.file("file", "modules", "zip")
            if f is None:
                raise InputError("send the module set as form field 'modules' (modules.json, with mesh files in "
                                 "'files') or 'file' (zip)")
            fname, data = f
            if is_zip(fname, data):
                res = await run_in_threadpool(bench.add_module_set_from_zip, data, fname, name)
            else:
                if not name:
                    raise InputError("give the module set a name (form field 'name')")
                files = {n: d for n, d in up.files.get("files", [])}
                res = await run_in_threadpool(bench.add_module_set, name, decode_text(data, fname), files_source(files))
        return JSONResponse(res, status_code=201)


def _add_cost_routes(app: FastAPI, site: Site) -> None:
    """/api/costs: the cost functions."""
    bench = site.bench

    @app.get("/api/costs")
    def api_costs():
        return [{"name": c.name, "descriptor": c.descriptor, "description": c.description}
                for c in bench.cost_functions()]
