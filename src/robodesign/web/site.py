"""The running site's parts shared by its routes: the benchmark (:class:`~robodesign.web.service.Bench`), the
check queue and checker, the viewer pages and their cache, and the admin rule."""
from __future__ import annotations

import functools
import hmac
import json
import logging
import secrets
from dataclasses import dataclass
from typing import Callable, Optional, Union

from fastapi import Request
from starlette.concurrency import run_in_threadpool

from robodesign.web.cache import ByteLRU
from robodesign.web.service import (
    Bench,
    Forbidden,
    Settings,
    check_token,
    hash_token,
)
from robodesign.web.site_settings import MiB
from robodesign.web.throttle import CheckQueue
from robodesign.web.uploads import Upload, read_upload
from robodesign.web.viewer_pages import ViewerPages
from robodesign.web.workers import ProcessChecker, ThreadChecker

log = logging.getLogger("robodesign.web")
ADMIN_TOKEN_ENV = "ROBODESIGN_ADMIN_TOKEN"


@dataclass
class Site:
    """What the routes of one site share (built by :func:`robodesign.web.app.create_app`)."""
    settings: Settings
    bench: Bench
    queue: CheckQueue
    checker: Union[ProcessChecker, ThreadChecker]
    viewer: ViewerPages
    viewer_cache: ByteLRU
    admin_token: Optional[str] = None
    open_registration: bool = False
    big_upload_bytes: int = 2 * MiB

    def require_admin(self, request: Request) -> None:
        if self.open_registration:
            return
        if self.admin_token is None:
            raise Forbidden("registering tasks and module sets is disabled on this server: start it with an admin "
                            f"token ({ADMIN_TOKEN_ENV} or --admin-token) or with --open-registration")
        auth = request.headers.get("authorization", "")
        given = request.headers.get("x-admin-token") or (auth[7:] if auth.lower().startswith("bearer ") else "")
        if not hmac.compare_digest(given.encode("utf-8", "replace"), self.admin_token.encode("utf-8")):
            raise Forbidden("registering tasks and module sets is an admin action: send the admin token as "
                            "'Authorization: Bearer <token>' or 'X-Admin-Token'" + (" (the one given is wrong)"
                                                                                    if given else ""))

    async def submit(self, request: Request, read: Callable[[Upload], tuple], durable: bool = False):
        """Read the upload (its body within the body deadline, counted among the bodies being received, never in
        the check queue), then take a place in the check queue (429 when full) and put it in line; parsing,
        validation and the checker run on a checker thread/process (``Bench.check_upload``: 201 / 422 / 400 / 413).
        ``durable`` (async uploads): the upload is committed to the database before this returns, and resumed
        after a restart. → (job, future of {status, body, result}, place in line when it joined, extra answer
        fields)."""
        client = (request.client.host if request.client else "?")
        self.queue.start_receiving(client)
        try:
            up = await read_upload(request)
        finally:
            self.queue.done_receiving(client)
        text, fname, meta, token, unwrap = read(up)
        big = len(text) > self.big_upload_bytes
        job = self.queue.reserve(client)
        extra: dict = {}
        try:
            if durable:
                if token:
                    check_token(token)
                else:  # the answer tells the token now: the result may be read after a restart
                    token = extra["token"] = secrets.token_urlsafe(24)
                token_hash = await run_in_threadpool(hash_token, token)
                await run_in_threadpool(self.bench.add_pending, job.id, text, fname, meta, token_hash, unwrap, big)
                kw = {"token_hash": token_hash, "pending": job.id}
                fut = self.queue.submit(job, lambda: self.checker.check(text, fname, meta, None, unwrap, **kw), big=big)
            else:
                fut = self.queue.submit(job, lambda: self.checker.check(text, fname, meta, token, unwrap), big=big)
        except BaseException:
            self.queue.release(job)
            raise
        return job, fut, self.queue.status(job)["position"], extra

    def resume_pending(self) -> int:
        """Put the async uploads that a stopped server had accepted but not judged back in line."""
        rows = self.bench.pending_checks()
        for row in rows:
            job = self.queue.restore(row.job_id)
            args = (row.text, row.fname, json.loads(row.meta_json or "{}"), None, row.unwrap)
            kw = {"token_hash": row.token_hash, "pending": row.job_id}
            self.queue.submit(job, functools.partial(self.checker.check, *args, **kw), big=row.big)
        if rows:
            log.info("resumed %d pending check(s) of async uploads", len(rows))
        return len(rows)

    @staticmethod
    def wants_async(request: Request) -> bool:
        return request.query_params.get("async", "") in ("1", "true", "yes") or \
            "respond-async" in request.headers.get("prefer", "")
