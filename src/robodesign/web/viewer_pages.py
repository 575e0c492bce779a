"""Viewer pages (``/solutions/<id>/viewer``) built off the web process, bounded and cached.

A stored solution may hold up to ``Limits.trajectory_values`` values (e.g. 83,000 samples): rendering all of them in
the web process took 26 s and 1.8 GB per request. Here a page is built

* in a separate process (one, spawned on first use; it dies with the server, runs at ``nice`` +10 and under an
  address-space limit of ``memory_mb``; a build taking longer than ``timeout`` seconds kills it: 503);
* from a trajectory decimated to at most ``max_samples`` samples (evenly in index, plus the first, last and every
  goal's sample): the animation then has at most ``max_frames`` frames (``fps`` lowered for long motions), the plots
  at most ``max_samples`` points;
* at most ``max_page_bytes`` large (a bigger page is replaced by a short page saying so);
* once: written to ``<data>/viewer/<id>.html`` (kept across restarts; a stored solution never changes) and served
  from there; concurrent requests for one page wait for the same build; at most ``max_waiting`` builds wait.
"""
from __future__ import annotations

import concurrent.futures as cf
import json
import logging
import multiprocessing
import os
import threading
from pathlib import Path
from typing import Dict, Optional

import numpy as np

from robodesign.collab.core import parse_collab_solution
from robodesign.core.jsonio import loads_json
from robodesign.experiment.executors import ignore_sigint
from robodesign.formats.solution import parse_solution
from robodesign.web import pages
from robodesign.web.service import Bench, Settings
from robodesign.web.throttle import Busy
from robodesign.web.workers import CHECKER_NICE, die_with_parent

log = logging.getLogger("robodesign.web")

MiB = 1 << 20

_bench: Optional[Bench] = None


class ViewerFailed(Exception):
    """The page could not be built (too slow, out of memory): HTTP 503."""


def decimate_indices(t: np.ndarray, max_samples: int, goal_times=()) -> np.ndarray:
    """Indices of at most ``max_samples`` (+ goals) samples: evenly spaced in index, with the first, the last and
    the sample nearest to each goal time."""
    n = len(t)
    if n <= max_samples:
        return np.arange(n)
    idx = np.unique(np.round(np.linspace(0, n - 1, max(2, int(max_samples)))).astype(int))
    goals = [int(np.clip(np.searchsorted(t, g), 0, n - 1)) for g in goal_times if np.isfinite(g)]
    return np.unique(np.concatenate([idx, np.asarray(goals, dtype=int)]))


def decimate_json(data, max_samples: int):
    """The stored solution's JSON (single-robot or collaborative) with every trajectory list cut to the samples of
    :func:`decimate_indices`, *before* it is parsed: schema validation of 83,000 samples alone takes minutes. The
    stored file was validated when it was uploaded; a malformed one is left as it is (the parser reports it)."""
    def cut(tr):
        if not isinstance(tr, dict) or not isinstance(tr.get("t"), list):
            return tr
        try:
            t = np.asarray(tr["t"], dtype=float)
            g2t = [float(v) for v in (tr.get("goal2time") or {}).values()]
        except (TypeError, ValueError):
            return tr
        if t.ndim != 1:
            return tr
        idx = decimate_indices(t, max_samples, g2t)
        if len(idx) == len(t):
            return tr
        return {k: ([v[i] for i in idx] if k in ("t", "q", "dq", "ddq") and isinstance(v, list) and len(v) == len(t)
                    else v) for k, v in tr.items()}
    if not isinstance(data, dict):
        return data
    out = dict(data)
    if isinstance(out.get("trajectory"), dict):
        out["trajectory"] = cut(out["trajectory"])
    if isinstance(out.get("robots"), list):
        out["robots"] = [dict(r, trajectory=cut(r["trajectory"])) if isinstance(r, dict) and "trajectory" in r else r
                         for r in out["robots"]]
    return out


def _init(settings: Settings, memory_mb: int) -> None:
    global _bench
    ignore_sigint()  # Ctrl-C on `robodesign serve` reaches the process group: the server shuts the pool down
    die_with_parent()
    try:
        os.nice(CHECKER_NICE)
    except OSError:
        pass
    if memory_mb > 0:
        try:
            import resource
            limit = int(memory_mb) * MiB
            resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
        except (ImportError, ValueError, OSError):
            pass
    _bench = Bench(settings, staging=False)


def _fps(duration: float, max_frames: int) -> float:
    return float(min(25.0, max(0.01, max_frames / max(duration, 1e-9))))


def _build(sid: int, out: str, max_samples: int, max_frames: int, max_page_bytes: int) -> int:
    """In the viewer process: render solution ``sid`` into the file ``out`` → its size in bytes."""
    b = _bench
    assert b is not None, "_init made it (the pool initializer)"
    row = b.solution_row(sid)
    verdict = json.loads(row.verdict_json or "{}") or None
    name = f"solution-{row.id}.json"
    data = decimate_json(loads_json(b.solution_text(row.id), name), max_samples)
    if row.collaborative:
        from robodesign.viewer import collab_page
        csol = parse_collab_solution(data, name)
        t = csol.robots[0][1].trajectory.t
        html = collab_page(b.collab_task(row.task_id), csol, {rid: b.module_set(s.module_set) for rid, s in csol.robots},
                           verdict=pages.collab_viewer_verdict(verdict), fps=_fps(float(t[-1] - t[0]), max_frames))
    else:
        from robodesign.viewer import solution_page
        sol = parse_solution(data, name)
        t = sol.trajectory.t
        html = solution_page(b.task(row.task_id), sol, b.module_set(row.module_set), verdict=verdict,
                             fps=_fps(float(t[-1] - t[0]), max_frames))
    data = html.encode("utf-8")
    if len(data) > max_page_bytes:
        data = pages.error_page(413, f"the viewer page of solution #{sid} would be {len(data) / MiB:.1f} MiB "
                                     f"(at most {max_page_bytes / MiB:.0f} MiB are served)").encode("utf-8")
    tmp = f"{out}.{os.getpid()}.tmp"
    with open(tmp, "wb") as f:
        f.write(data)
    os.replace(tmp, out)
    return len(data)


class ViewerPages:
    """Builds and caches viewer pages in one worker process (see the module docstring)."""

    def __init__(self, settings: Settings, *, timeout: float = 60.0, memory_mb: int = 3072, max_samples: int = 4000,
                 max_frames: int = 2000, max_page_bytes: int = 16 * MiB, max_waiting: int = 8):
        self.settings = settings
        self.folder = Path(settings.data_dir).resolve() / "viewer"
        self.folder.mkdir(parents=True, exist_ok=True)
        self.timeout, self.memory_mb = float(timeout), int(memory_mb)
        self.max_samples, self.max_frames = int(max_samples), int(max_frames)
        self.max_page_bytes, self.max_waiting = int(max_page_bytes), int(max_waiting)
        self._pool: Optional[cf.ProcessPoolExecutor] = None
        self._lock = threading.Lock()
        self._building: Dict[int, cf.Future] = {}
        self.builds = 0  # pages built (not served from the files)

    def path(self, sid: int) -> Path:
        return self.folder / f"{int(sid)}.html"

    def _get_pool(self) -> cf.ProcessPoolExecutor:
        if self._pool is None:
            self._pool = cf.ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"), initializer=_init,
                                                initargs=(self.settings, self.memory_mb))
        return self._pool

    def _kill_pool(self, pool: cf.ProcessPoolExecutor) -> None:
        procs = list(getattr(pool, "_processes", {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for p in procs:
            p.kill()
        with self._lock:
            if self._pool is pool:
                self._pool = None

    def get(self, sid: int) -> Path:
        """The page file of solution ``sid`` (built now if it is not there yet). Blocks: call it from a thread."""
        p = self.path(sid)
        if p.is_file():
            return p
        with self._lock:
            fut = self._building.get(sid)
            owner = fut is None
            if fut is None:
                if len(self._building) >= self.max_waiting:
                    raise Busy(f"{len(self._building)} viewer pages are being built; try again later", 10)
                pool = self._get_pool()
                fut = pool.submit(_build, int(sid), str(p), self.max_samples, self.max_frames, self.max_page_bytes)
                self._building[sid] = fut
                self.builds += 1
        try:
            fut.result(timeout=self.timeout)
        except cf.TimeoutError:
            if owner:
                log.warning("the viewer page of solution %s took longer than %g s: stopped", sid, self.timeout)
                self._kill_pool(pool)
            raise ViewerFailed(f"the viewer page took longer than {self.timeout:g} s to build") from None
        except cf.process.BrokenProcessPool:
            if owner:
                self._kill_pool(pool)
            raise ViewerFailed("building the viewer page failed (out of memory?)") from None
        except MemoryError:
            raise ViewerFailed("building the viewer page ran out of memory") from None
        except cf.CancelledError:
            raise ViewerFailed("building the viewer page was stopped; try again") from None
        finally:
            if owner:
                with self._lock:
                    self._building.pop(sid, None)
        return p

    def close(self) -> None:
        with self._lock:
            pool = self._pool
        if pool is not None:
            self._kill_pool(pool)
