"""What the three parts of :class:`~robodesign.web.service.Bench` (registration, judging, boards) share: the
attributes ``Bench.__init__`` sets and the registration methods the other two call, declared once so a type
checker can follow one part into another (annotations only: nothing here exists at run time)."""
from __future__ import annotations

import threading
from pathlib import Path
from typing import IO, TYPE_CHECKING, Dict, List, Optional, Union

from sqlalchemy.orm import sessionmaker

from robodesign.collab.core import CollabTask
from robodesign.formats.module_spec import ModuleSet
from robodesign.formats.task_spec import Task
from robodesign.web import db
from robodesign.web.site_settings import Settings


class BenchBase:
    """The state of a site, set by ``Bench.__init__``."""

    settings: Settings
    data: Path
    seed_log: List[str]
    tmp: Optional[Path]
    _tmp_lock: Optional[IO[str]]
    Session: sessionmaker
    _lock: threading.RLock
    _tasks: Dict[str, Union[Task, CollabTask]]
    _msets: Dict[str, ModuleSet]

    if TYPE_CHECKING:  # defined by Registration, called by Judging and Leaderboards
        def _has_task(self, tid: str) -> bool: ...

        def _has_module_set(self, name: str) -> bool: ...

        def task_row(self, tid: str, file: bool = False) -> db.TaskRow: ...

        def parsed_task(self, tid: str) -> Union[Task, CollabTask]: ...

        def module_set(self, name: str) -> ModuleSet: ...

        def tasks(self) -> List[db.TaskRow]: ...

        def module_sets(self) -> List[db.ModuleSetRow]: ...
