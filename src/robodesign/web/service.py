"""The benchmark's business logic, independent of HTTP: registering tasks / module sets / cost functions,
judging and storing solutions, leaderboards, queries and withdrawal.

Everything here is synchronous; the web layer runs it in a thread pool. Bad input raises
:class:`~robodesign.core.errors.InputError` (HTTP 400; :class:`TooLarge` 413), :class:`Conflict` (409),
:class:`NotFound` (404), :class:`Forbidden` (403).
"""
from __future__ import annotations

import contextlib
import json
import os
import shutil
import threading
from pathlib import Path
from typing import Dict, List, Union

from sqlalchemy import select

from robodesign.collab.core import CollabTask, is_collaborative
from robodesign.core.errors import InputError
from robodesign.core.jsonio import loads_json
from robodesign.formats.module_spec import ModuleSet
from robodesign.formats.task_spec import Task
from robodesign.web import db
from robodesign.web.boards import (  # noqa: F401 - re-exported: the site's API of this module
    MAX_BENCHMARK_ID,
    Board,
    Leaderboards,
    canonical_benchmark,
    clean_json,
    collab_benchmark_key,
    collab_rank_key,
    parse_benchmark,
    solution_id,
    solution_summary,
)
from robodesign.web.judging import (  # noqa: F401
    Judging,
    Submission,
    SubmitResult,
    check_solution_size,
    check_text_sizes,
    unwrap_upload,
)
from robodesign.web.registration import Registration, files_source, parse_task_file  # noqa: F401
from robodesign.web.site_errors import AlreadyJudged, Conflict, Forbidden, NotFound  # noqa: F401
from robodesign.web.site_settings import Limits, MiB, Settings  # noqa: F401
from robodesign.web.staging import STAGING_LOCK, claim_staging, remove_stale_staging
from robodesign.web.tokens import check_token, hash_token, verify_token  # noqa: F401


class Bench(Registration, Judging, Leaderboards):
    """One benchmark site: database + data folder + caches of parsed tasks and module sets. Its jobs live in
    their own modules: registration (seeding, tasks, module sets, zips, staging), judging (uploads, the
    checker, pending checks) and boards (solutions, leaderboards, withdrawal)."""

    def __init__(self, settings: Settings, staging: bool = True):
        """``staging=False``: a checker process of a site, which only reads tasks and module sets and stores
        solutions (it neither cleans nor claims a staging folder)."""
        self.settings = settings
        self.data = Path(settings.data_dir).resolve()
        for sub in ("tasks", "modulesets", "tmp"):
            (self.data / sub).mkdir(parents=True, exist_ok=True)
        self.seed_log: List[str] = []
        self.removed_staging = remove_stale_staging(self.data / "tmp") if staging else []
        for name in self.removed_staging:
            self._note(f"removed the staging folder tmp/{name} left by a server that stopped mid-upload")
        self.tmp, self._tmp_lock = claim_staging(self.data / "tmp") if staging else (None, None)
        self.db_url = db.normalize_url(settings.db_url, self.data)
        self.engine = db.make_engine(self.db_url)
        self.Session = db.make_sessionmaker(self.engine)
        self._lock = threading.RLock()
        self._tasks: Dict[str, Union[Task, CollabTask]] = {}
        self._msets: Dict[str, ModuleSet] = {}
        if staging:
            self._fill_task_robots()

    def _fill_task_robots(self) -> None:
        """Task rows of an older version (before collaborative tasks) get their ``robots`` column."""
        with self.Session() as s:
            rows = list(s.scalars(select(db.TaskRow).where(db.TaskRow.robots.is_(None))))
            for row in rows:
                try:
                    data = loads_json(row.json, "task.json")
                except InputError:
                    data = None
                robots = data.get("robots") if is_collaborative(data) else []
                row.robots = json.dumps([{"ID": str(r.get("ID")), "name": str(r.get("name") or r.get("ID"))}
                                         for r in robots if isinstance(r, dict)])
            if rows:
                s.commit()

    def close(self):
        self.engine.dispose()
        if self.tmp is not None:
            shutil.rmtree(self.tmp, ignore_errors=True)
            with contextlib.suppress(OSError):
                os.unlink(str(self.tmp) + STAGING_LOCK)
            self._tmp_lock.close()
