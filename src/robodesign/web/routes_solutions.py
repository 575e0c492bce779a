"""The JSON API of solutions: uploads (synchronous or async with a status URL), the check queue, solution
lists and files, withdrawal, benchmarks and leaderboards."""
from __future__ import annotations

import asyncio
import json

from fastapi import FastAPI, Request
from fastapi.responses import JSONResponse, Response
from starlette.concurrency import run_in_threadpool

from robodesign.core.errors import InputError
from robodesign.web.service import (
    NotFound,
    clean_json,
    solution_summary,
)
from robodesign.web.site import Site
from robodesign.web.uploads import Upload, decode_text, float_param


def add_routes(app: FastAPI, site: Site) -> None:
    """/api/solutions, /api/checks, /api/queue, /api/benchmarks, /api/leaderboard."""
    _add_upload_routes(app, site)
    _add_solution_routes(app, site)
    _add_leaderboard_routes(app, site)


def _add_upload_routes(app: FastAPI, site: Site) -> None:
    """/api/benchmarks, uploads (synchronous or async), their status and the check queue."""
    bench, queue, submit, wants_async = site.bench, site.queue, site.submit, site.wants_async

    @app.get("/api/benchmarks")
    def api_benchmarks():
        return clean_json(bench.benchmarks())

    def read_api_upload(request: Request):
        def read(up: Upload):
            token = request.headers.get("x-author-token")
            if up.raw is not None:  # the solution, or {"solution": ..., "author": ...} (unwrapped by the checker)
                meta = {k: request.query_params.get(k) for k in ("author", "email", "affiliation")}
                return decode_text(up.raw, "request body"), "solution.json", meta, token, True
            f = up.file("file", "solution")
            if f is None:
                raise InputError("send the solution as form field 'file' (a CoBRA solution JSON file)")
            fname, raw = f
            meta = {k: up.fields.get(k) for k in ("author", "email", "affiliation")}
            return decode_text(raw, fname), fname, meta, up.fields.get("token") or token, False
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


def _add_solution_routes(app: FastAPI, site: Site) -> None:
    """/api/solutions: lists, one solution, its file, withdrawal."""
    bench = site.bench

    @app.get("/api/solutions")
    def api_solutions(request: Request):
        qp = request.query_params
        collab = qp.get("collaborative", "")
        if collab not in ("", "0", "1", "true", "false"):
            raise InputError(f"query parameter collaborative: expected 1 or 0, got {collab[:40]!r}")
        rows = bench.list_solutions(task=qp.get("task") or None, cost=qp.get("cost") or None,
                                    moduleset=qp.get("moduleset") or None, min_cost=float_param(request, "min_cost"),
                                    max_cost=float_param(request, "max_cost"),
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


def _add_leaderboard_routes(app: FastAPI, site: Site) -> None:
    """/api/leaderboard: a benchmark's ranked entries."""
    bench = site.bench

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
