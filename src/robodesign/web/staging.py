"""The data folder's staging area: each server process claims its own folder under ``tmp/`` (held by a lock
for its lifetime), and what servers that are gone left there is removed at start."""
from __future__ import annotations

import fcntl
import os
import secrets
import shutil
import time
from pathlib import Path
from typing import List

STAGING_LOCK = ".lock"


def claim_staging(tmp: Path):
    """A staging folder of this server process under ``tmp``, held by an exclusive lock on ``<folder>.lock``
    for as long as the process lives (the lock dies with the process, even when it is killed)."""
    folder = tmp / f"srv-{os.getpid()}-{secrets.token_hex(4)}"
    lock = open(str(folder) + STAGING_LOCK, "w")
    fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    folder.mkdir()
    return folder, lock


def remove_stale_staging(tmp: Path) -> List[str]:
    """Delete what servers that are gone left in ``tmp``: staging folders whose lock no process holds (and
    anything else there that no lock protects). Folders of servers still running on the same data folder stay."""
    removed = []
    for p in sorted(tmp.iterdir()):
        if p.name.endswith(STAGING_LOCK):
            continue
        lock_path = Path(str(p) + STAGING_LOCK)
        try:
            with open(lock_path, "a") as lock:
                fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)  # free: its server is gone
                if p.is_dir() and not p.is_symlink():
                    shutil.rmtree(p, ignore_errors=True)
                else:
                    p.unlink(missing_ok=True)
                lock_path.unlink(missing_ok=True)
        except BlockingIOError:
            continue  # a running server owns it
        removed.append(p.name)
    for lock_path in tmp.glob("*" + STAGING_LOCK):  # a lock without its folder (not one being set up right now)
        if not Path(str(lock_path)[: -len(STAGING_LOCK)]).exists() and time.time() - lock_path.stat().st_mtime > 60:
            with open(lock_path, "a") as lock:
                try:
                    fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
                    lock_path.unlink(missing_ok=True)
                except BlockingIOError:
                    pass
    return removed
