"""The FastAPI application: HTML pages and the JSON API of the benchmark website.

``create_app(db_url, data_dir)`` builds it; ``robodesign serve`` runs it with uvicorn. See docs/website.md.
"""
from __future__ import annotations

import contextlib
import os
from pathlib import Path
from typing import Optional, Sequence

from fastapi import FastAPI

from robodesign.core.errors import InputError
from robodesign.core.paths import assets_dir
from robodesign.web import routes_pages, routes_registration, routes_solutions
from robodesign.web.cache import ByteLRU
from robodesign.web.middleware import BodyLimitMiddleware, GuardMiddleware, HeadMiddleware
from robodesign.web.routes_errors import add_error_handlers
from robodesign.web.service import Bench, Limits, Settings
from robodesign.web.site import ADMIN_TOKEN_ENV, Site
from robodesign.web.site_settings import MiB
from robodesign.web.throttle import CheckQueue, RateLimiter
from robodesign.web.uploads import MAX_FORM_FIELDS, MAX_FORM_FILES  # noqa: F401 - documented limits
from robodesign.web.viewer_pages import ViewerPages
from robodesign.web.workers import ProcessChecker, ThreadChecker


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
    site = Site(settings, bench, queue, checker, ViewerPages(settings, timeout=viewer_timeout),
                ByteLRU(viewer_cache_bytes), admin_token=admin_token, open_registration=open_registration,
                big_upload_bytes=big_upload_bytes)

    @contextlib.asynccontextmanager
    async def lifespan(_app):
        site.resume_pending()
        yield
        queue.close()
        checker.close()
        site.viewer.close()
        bench.close()

    app = FastAPI(title="robodesign benchmark", version="1", lifespan=lifespan, docs_url=None,
                  redoc_url=None, openapi_url="/api/openapi.json")
    app.state.bench, app.state.queue, app.state.checker = bench, queue, checker
    app.state.viewer_cache, app.state.viewer = site.viewer_cache, site.viewer
    app.add_middleware(BodyLimitMiddleware, limit=settings.max_request_bytes, timeout=body_timeout)
    app.add_middleware(GuardMiddleware, reads=RateLimiter(read_rate, max(1.0, 5 * read_rate)),
                       writes=RateLimiter(upload_rate / 60.0, max(1.0, upload_rate / 3)))
    app.add_middleware(HeadMiddleware)
    add_error_handlers(app)
    routes_pages.add_routes(app, site)
    routes_registration.add_routes(app, site)
    routes_solutions.add_routes(app, site)
    return app
