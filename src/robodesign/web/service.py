"""The benchmark's business logic, independent of HTTP: registering tasks / module sets / cost functions,
judging and storing solutions, leaderboards, queries and withdrawal.

Everything here is synchronous; the web layer runs it in a thread pool. Bad input raises
:class:`~robodesign.core.errors.InputError` (HTTP 400; :class:`TooLarge` 413), :class:`Conflict` (409),
:class:`NotFound` (404), :class:`Forbidden` (403).
"""
from __future__ import annotations

import contextlib
import fcntl
import hashlib
import hmac
import json
import logging
import math
import os
import secrets
import shutil
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple, Union

from sqlalchemy import func, select, update
from sqlalchemy.exc import IntegrityError

from robodesign.collab.core import (
    CollabSolution,
    CollabTask,
    check_collab,
    is_collaborative,
    parse_collab_solution,
    parse_collab_task,
    shared_cell_json,
)
from robodesign.core.errors import InputError, RobodesignError
from robodesign.core.jsonio import loads_json
from robodesign.core.schema import validate
from robodesign.formats.benchmark_id import BenchmarkID, RobotRef, RobotSpec
from robodesign.formats.costs import known_costs, parse_cost
from robodesign.formats.module_io import parse_module_set
from robodesign.formats.module_spec import ModuleSet
from robodesign.formats.solution import Solution, parse_solution
from robodesign.formats.task_io import parse_task, validate_task_json
from robodesign.formats.task_spec import Task
from robodesign.judge.checker import Verdict, check
from robodesign.web import db
from robodesign.web.safefiles import (
    DictSource,
    FileSource,
    FolderSource,
    TooLarge,
    ZipSource,
    assert_no_symlinks,
    check_mesh_refs,
    check_name,
    dangerous_name,
    safe_relpath,
    task_id_segments,
    write_new_file,
)

log = logging.getLogger("robodesign.web")

MiB = 1 << 20


class Conflict(RobodesignError):
    pass


class NotFound(RobodesignError):
    pass


class Forbidden(RobodesignError):
    pass


class AlreadyJudged(Exception):
    """An async upload's job was finished by another server process (it stays stored once)."""


@dataclass
class Limits:
    """What one uploaded solution may hold (docs/website.md, "Limits"). Beyond them: 413 naming the field."""
    notes_chars: int = 16_384  # ``notes``
    text_chars: int = 1_000  # every other free-text field: version, publication, processorName, date, list entries
    list_items: int = 100  # entries of author / email / affiliation / tags
    trajectory_values: int = 500_000  # samples × joints of the trajectory (of all robots together)
    modules: int = 1_000  # entries of moduleOrder / moduleConnection
    robots: int = 16  # robots of a collaborative task or solution
    robot_id_chars: int = 100  # a robot's ID in a collaborative task


@dataclass
class Settings:
    data_dir: Path
    db_url: Optional[str] = None
    max_request_bytes: int = 20 * MiB
    max_unzipped_bytes: int = 200 * MiB
    max_zip_entries: int = 5000
    check_workers: int = max(2, min(8, os.cpu_count() or 2))
    seed_dirs: Sequence[Path] = ()
    seed_builtin: bool = True
    limits: Limits = field(default_factory=Limits)


@dataclass
class SubmitResult:
    valid: bool
    benchmark_id: str
    verdict: dict
    cost: Optional[float]
    id: Optional[int] = None
    token: Optional[str] = None
    task_id: str = ""
    module_set: str = ""
    costs: Optional[list] = None  # a collaborative solution's cost tuple (``cost`` is then totalCost, their sum)

    @property
    def collaborative(self) -> bool:
        return self.costs is not None

    def to_json(self) -> dict:
        out = {"id": self.id, "valid": self.valid, "cost": self.cost, "benchmark_id": self.benchmark_id}
        if self.collaborative:
            out.update(collaborative=True, costs=self.costs, totalCost=self.cost)
        if self.valid and self.token is not None:  # (an async upload got its token with the 202 answer)
            out["token"] = self.token
        else:
            out["violations"] = self.verdict.get("violations", [])
            out["verdict"] = self.verdict
            first = out["violations"][0] if out["violations"] else {}
            robot = f" robot {first['robot']}:" if first.get("robot") else ""
            out["detail"] = (f"the solution is invalid: {len(out['violations'])} violation(s)"
                             + (f", first{robot} [{first.get('constraint')}] {first.get('message')}" if first else ""))
        return out


def clean_json(obj):
    """Replace non-finite floats (not representable in strict JSON) by None."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: clean_json(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [clean_json(v) for v in obj]
    return obj


# --------------------------------------------------------------------------------------------------------
# tokens
# --------------------------------------------------------------------------------------------------------
_ITERATIONS = 20_000


def hash_token(token: str) -> str:
    salt = secrets.token_bytes(16)
    h = hashlib.pbkdf2_hmac("sha256", token.encode(), salt, _ITERATIONS)
    return f"pbkdf2_sha256${_ITERATIONS}${salt.hex()}${h.hex()}"


def verify_token(token: Optional[str], stored: str) -> bool:
    if not token:
        return False
    try:
        algo, it, salt, h = stored.split("$")
        if algo != "pbkdf2_sha256":
            return False
        got = hashlib.pbkdf2_hmac("sha256", token.encode(), bytes.fromhex(salt), int(it))
    except (ValueError, TypeError):
        return False
    return hmac.compare_digest(got.hex(), h)


def canonical_benchmark(module_set: str, cost_text: str, task_id: str) -> Tuple[str, str]:
    """(display ID ``M-<set>:<cost>:<task>``, matching key with the cost as its canonical descriptor)."""
    cost = parse_cost(cost_text)
    if cost.is_empty:
        raise InputError("the cost function is empty; a benchmark needs a cost (e.g. cyc, Liu2, mechEnergy)",
                         path=["costFunction"])
    bid = BenchmarkID(RobotSpec((RobotRef(module_set, "M-"),)), cost, task_id)
    BenchmarkID.parse(str(bid))  # validates the set name and task ID grammar
    return str(bid), cost.descriptor()


def collab_benchmark_key(bid: BenchmarkID) -> str:
    """The matching key of a collaborative benchmark: its module sets and per-robot cost descriptors in robot
    order (``Liu2`` and ``cyc_0.2,mechEnergy`` mean the same cost; ``cyc`` for all is ``[cyc,cyc]``)."""
    return json.dumps({"sets": list(bid.robot.names), "costs": [c.descriptor() for c in bid.costs]})


MAX_BENCHMARK_ID = 600  # the solutions.benchmark_id column


@dataclass(frozen=True)
class Board:
    """A leaderboard's benchmark: single-robot ``M-<set>:<cost>:<task>`` or collaborative
    ``[M-<set1>,M-<set2>]:[C1,C2]:<task>`` (canonical ``display``)."""
    display: str
    task_id: str
    module_sets: Tuple[str, ...]  # one per robot (one for a single-robot benchmark)
    cost_key: str  # single-robot: the canonical descriptor; collaborative: "" (see robots_key)
    robots_key: str = ""  # collaborative: collab_benchmark_key

    @property
    def collaborative(self) -> bool:
        return bool(self.robots_key)

    @property
    def module_set(self) -> str:
        return self.module_sets[0]


def parse_benchmark(text: str) -> Board:
    """A benchmark ID from a URL. Bare robot names mean ``M-``."""
    if len(text) > MAX_BENCHMARK_ID:
        raise InputError(f"benchmark ID of {len(text)} characters (at most {MAX_BENCHMARK_ID})")
    bid = BenchmarkID.parse(text)
    for r in bid.robot.robots:
        if r.kind != "module_set":
            raise NotFound(f"benchmark ID {text!r}: only module-set benchmarks (M-<set>) are hosted here")
    if bid.robot.collaborative:
        if any(c.is_empty for c in bid.costs):
            raise InputError(f"benchmark ID {text!r}: a robot's cost is empty")
        canon = BenchmarkID(RobotSpec(tuple(RobotRef(n, "M-") for n in bid.robot.names), True), bid.cost, bid.task,
                            bid.costs)
        return Board(str(canon), bid.task, bid.robot.names, "", collab_benchmark_key(bid))
    r = bid.robot.robots[0]
    display, key = canonical_benchmark(r.name, bid.cost.name or bid.cost.descriptor(), bid.task)
    return Board(display, bid.task, (r.name,), key)


def collab_rank_key(row) -> tuple:
    """The order of a collaborative leaderboard (docs/collaborative.md): ``totalCost`` ascending, ties broken by the
    cost tuple compared element by element, then the earlier upload."""
    costs = json.loads(row.cost_tuple or "[]")
    return (row.cost is None, row.cost if row.cost is not None else 0.0,
            tuple(math.inf if c is None else c for c in costs), row.created, row.id)


class Bench:
    """One benchmark site: database + data folder + caches of parsed tasks and module sets."""

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

    # ----------------------------------------------------------------------------------------------------
    # seeding
    # ----------------------------------------------------------------------------------------------------
    def seed(self, dirs: Sequence[Path]) -> None:
        self.seed_costs()
        for d in dirs:
            self.seed_folder(Path(d))

    def seed_costs(self) -> None:
        with self.Session() as s:
            have = set(s.scalars(select(db.CostFunctionRow.name)))
            for name, desc in known_costs().items():
                if name in have:
                    continue
                s.add(db.CostFunctionRow(name=name, descriptor=parse_cost(name).descriptor(), description=desc))
            try:
                s.commit()
            except IntegrityError:  # another instance seeded them concurrently
                s.rollback()

    def _note(self, msg: str) -> None:
        self.seed_log.append(msg)
        log.info(msg)

    def seed_folder(self, d: Path) -> None:
        d = d.resolve()
        if not d.is_dir():
            self._note(f"seed folder {d} does not exist; skipped")
            return
        max_file = self.settings.max_unzipped_bytes
        set_dirs: List[Path] = []
        if (d / "modules").is_dir():
            set_dirs = [p for p in sorted((d / "modules").iterdir()) if (p / "modules.json").is_file()]
        elif (d / "modules.json").is_file():
            set_dirs = [d]
        for p in set_dirs:
            if self._has_module_set(p.name):
                continue
            try:
                text = (p / "modules.json").read_text(encoding="utf-8")
                self.add_module_set(p.name, text, FolderSource(p, max_file), origin="seed")
                self._note(f"seeded module set {p.name} from {p}")
            except (InputError, Conflict, OSError, UnicodeDecodeError) as e:
                self._note(f"seed: module set {p}: skipped: {e}")
        task_root = d / "tasks" if (d / "tasks").is_dir() else (None if set_dirs else d)
        if task_root is None:
            return
        for f in sorted(task_root.rglob("*.json")):
            if f.name == "modules.json" or not f.is_file():
                continue
            try:
                text = f.read_text(encoding="utf-8")
                data = loads_json(text, f.name)
                if not (isinstance(data, dict) and isinstance(data.get("header"), dict) and "ID" in data["header"]):
                    continue
                tid = str(data["header"]["ID"])
                if self._has_task(tid):
                    continue
                root = f.resolve().parent
                for _ in range(tid.count("/")):
                    root = root.parent
                if root != task_root.resolve() and task_root.resolve() not in root.parents:
                    raise InputError(f"task ID {tid!r} does not match the file's place in {task_root}", file=f.name)
                self.add_task(text, FolderSource(root, max_file), fname=f.name, origin="seed")
                self._note(f"seeded task {tid} from {f}")
            except (InputError, Conflict, OSError, UnicodeDecodeError) as e:
                self._note(f"seed: task {f}: skipped: {e}")

    def _has_task(self, tid: str) -> bool:
        with self.Session() as s:
            return s.scalar(select(db.TaskRow.id).where(db.TaskRow.task_id == tid)) is not None

    def _has_module_set(self, name: str) -> bool:
        with self.Session() as s:
            return s.scalar(select(db.ModuleSetRow.id).where(db.ModuleSetRow.name == name)) is not None

    # ----------------------------------------------------------------------------------------------------
    # registering tasks and module sets
    # ----------------------------------------------------------------------------------------------------
    def _staging(self) -> Path:
        p = self.tmp / secrets.token_hex(8)
        p.mkdir(parents=True)
        return p

    def _commit_new(self, row: db.Base, folder: Path, taken: str) -> None:
        """Insert ``row`` whose files were just moved to ``folder``; on any failure the folder goes too."""
        with self.Session() as s:
            s.add(row)
            try:
                s.commit()
            except BaseException as e:
                s.rollback()
                shutil.rmtree(self.data / folder, ignore_errors=True)
                if isinstance(e, IntegrityError):
                    raise Conflict(taken) from None
                raise

    def _store_refs(self, refs: Dict[str, list], source: FileSource, dest: Path) -> List[dict]:
        assets, total = [], 0
        for rel in sorted(refs):
            content = source.get(rel)
            if content is None:
                continue  # the parser reports a missing collision mesh; a missing visual is a warning
            total += len(content)
            if total > self.settings.max_unzipped_bytes:
                raise TooLarge(f"the referenced files exceed {self.settings.max_unzipped_bytes} bytes")
            write_new_file(dest, rel, content)
            assets.append({"path": rel, "size": len(content), "sha256": hashlib.sha256(content).hexdigest()})
        return assets

    def add_task(self, text: str, source: FileSource, fname: str = "task.json", origin: str = "upload") -> dict:
        """Validate (schema first), store the task file and its referenced meshes, register it. A collaborative task
        (a ``robots`` list, docs/collaborative.md) is validated as its shared cell plus its robots."""
        raw = loads_json(text, fname)
        collab = is_collaborative(raw)
        if collab:
            self._check_robot_ids(raw["robots"], fname)
        data = validate_task_json(shared_cell_json(raw) if collab else raw, fname)
        tid = str(data["header"]["ID"])
        segs = task_id_segments(tid, fname)
        header = data["header"]
        row = db.TaskRow(task_id=tid, name=str(header.get("taskName") or segs[-1]), json=text, folder="",
                         origin=origin)
        db.check_row(row, {"task_id": "header.ID", "name": "header.taskName"}, fname)
        if self._has_task(tid):
            raise Conflict(f"task {tid!r} is already registered (task IDs are immutable; use a new ID or version)")
        stage = self._staging()
        try:
            pkg = stage / "pkg"
            pkg.mkdir()
            refs = check_mesh_refs(data, pkg, fname)
            assets = self._store_refs(refs, source, pkg)
            task_file = pkg.joinpath(*segs[:-1], segs[-1] + ".json")
            write_new_file(pkg, "/".join(segs) + ".json", text.encode("utf-8"))
            parsed = parse_task_file(loads_json(text, fname), task_file)  # the file as written: its warnings too
            task = parsed.task if collab else parsed
            assert_no_symlinks(pkg)
            folder = Path("tasks") / f"{segs[-1]}-{secrets.token_hex(6)}"
            os.replace(pkg, self.data / folder)
        except BaseException:
            shutil.rmtree(stage, ignore_errors=True)
            raise
        shutil.rmtree(stage, ignore_errors=True)
        row.tags, row.folder, row.assets = json.dumps(list(task.header.tags)), folder.as_posix(), json.dumps(assets)
        row.n_goals, row.n_obstacles = len(task.goals), len(task.obstacles)
        robots = [{"ID": rid, "name": parsed.robot_names[rid]} for rid in parsed.robot_ids] if collab else []
        row.robots = json.dumps(robots)
        self._commit_new(row, folder, f"task {tid!r} is already registered")
        out = {"id": tid, "name": row.name, "assets": [a["path"] for a in assets], "warnings": list(task.warnings),
               "url": f"/tasks/{tid}", "collaborative": collab}
        if collab:
            out["robots"] = robots
            out["goals"] = {g: r or "any" for g, r in parsed.assignment.items()}
        return out

    def _check_robot_ids(self, robots: list, fname: str) -> None:
        """The caps of a collaborative task's ``robots`` (the rest is checked by parse_collab_task)."""
        lim = self.settings.limits
        if len(robots) > lim.robots:
            raise TooLarge(f"at most {lim.robots} robots are allowed (got {len(robots)})", file=fname, path=["robots"])
        for i, r in enumerate(robots):
            for key, n in (("ID", lim.robot_id_chars), ("name", db.TaskRow.name.type.length)):
                v = r.get(key) if isinstance(r, dict) else None
                v = str(v) if isinstance(v, int) and not isinstance(v, bool) else v  # an ID may be an integer
                if isinstance(v, str) and len(v) > n:
                    raise InputError(f"at most {n} characters are allowed (got {len(v)})", file=fname,
                                     path=["robots", i, key])

    def add_module_set(self, name: str, text: str, source: FileSource, origin: str = "upload") -> dict:
        check_name(name)
        fname = f"{name}/modules.json"
        data = loads_json(text, fname)
        validate(data, "modules", fname)
        db.check_row(db.ModuleSetRow(name=name, json=text, folder=""), {"json": "modules.json"}, fname)
        if self._has_module_set(name):
            raise Conflict(f"module set {name!r} is already registered")
        stage = self._staging()
        try:
            root = stage / name
            root.mkdir()
            refs = check_mesh_refs(data, root, fname)
            assets = self._store_refs(refs, source, root)
            write_new_file(root, "modules.json", text.encode("utf-8"))
            ms = parse_module_set(data, root / "modules.json", name=name)
            assert_no_symlinks(root)
            folder = Path("modulesets") / f"{name}-{secrets.token_hex(6)}"
            os.replace(root, self.data / folder)
        except BaseException:
            shutil.rmtree(stage, ignore_errors=True)
            raise
        shutil.rmtree(stage, ignore_errors=True)
        self._commit_new(db.ModuleSetRow(name=name, json=text, folder=folder.as_posix(), assets=json.dumps(assets),
                                         module_ids=json.dumps(list(ms.modules)), origin=origin),
                         folder, f"module set {name!r} is already registered")
        return {"name": name, "modules": len(ms.modules), "assets": [a["path"] for a in assets],
                "url": f"/modulesets/{name}"}

    def add_tasks_from_zip(self, blob: bytes, display: str) -> List[dict]:
        z = ZipSource(blob, display, self.settings.max_unzipped_bytes, self.settings.max_zip_entries)
        found = []
        for rel in z.names():
            if not rel.lower().endswith(".json") or rel.rsplit("/", 1)[-1] == "modules.json":
                continue
            raw = z.get(rel)
            try:
                text = raw.decode("utf-8")
            except UnicodeDecodeError:
                raise InputError("not UTF-8 text", file=rel) from None
            data = loads_json(text, rel)
            if isinstance(data, dict) and "header" in data:
                found.append((rel, text, data))
        if not found:
            raise InputError("the archive holds no task file (a JSON object with a 'header')", file=display)
        out = []
        for rel, text, data in found:
            tid = str((data.get("header") or {}).get("ID", "")) if isinstance(data.get("header"), dict) else ""
            # package root: the prefix before "<ID>.json" if the entry sits at its ID path, else its folder
            if tid and rel == tid + ".json":
                prefix = ""
            elif tid and rel.endswith("/" + tid + ".json"):
                prefix = rel[: -len(tid + ".json")]
            else:
                prefix = rel.rsplit("/", 1)[0] + "/" if "/" in rel else ""
            out.append(self.add_task(text, _Prefixed(z, prefix), fname=rel.rsplit("/", 1)[-1]))
        return out

    def add_module_set_from_zip(self, blob: bytes, display: str, name: Optional[str]) -> dict:
        z = ZipSource(blob, display, self.settings.max_unzipped_bytes, self.settings.max_zip_entries)
        cands = [r for r in z.names() if r == "modules.json" or r.endswith("/modules.json")]
        if len(cands) != 1:
            raise InputError(f"the archive must hold exactly one modules.json, found {len(cands)}", file=display)
        rel = cands[0]
        prefix = rel[: -len("modules.json")]
        if not name:
            name = prefix.rstrip("/").rsplit("/", 1)[-1] if prefix else ""
            if not name:
                raise InputError("give the module set a name (form field 'name')", file=display)
        raw = z.get(rel)
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError:
            raise InputError("not UTF-8 text", file=rel) from None
        return self.add_module_set(name, text, _Prefixed(z, prefix))

    # ----------------------------------------------------------------------------------------------------
    # lookups
    # ----------------------------------------------------------------------------------------------------
    def task_row(self, tid: str, file: bool = False) -> db.TaskRow:
        """The task's row; its file (``json``) only when ``file``."""
        cols = db.TASK_LIST_COLUMNS + ((db.TaskRow.json,) if file else ())
        with self.Session() as s:
            row = s.scalar(select(db.TaskRow).options(db.only(cols)).where(db.TaskRow.task_id == tid))
        if row is None:
            raise NotFound(f"unknown task {tid!r}")
        return row

    def module_set_row(self, name: str, file: bool = False) -> db.ModuleSetRow:
        """The module set's row; its file (``json``) only when ``file``."""
        cols = db.MODULE_SET_LIST_COLUMNS + ((db.ModuleSetRow.json,) if file else ())
        with self.Session() as s:
            row = s.scalar(select(db.ModuleSetRow).options(db.only(cols)).where(db.ModuleSetRow.name == name))
        if row is None:
            raise NotFound(f"unknown module set {name!r}")
        return row

    def parsed_task(self, tid: str) -> Union[Task, CollabTask]:
        """The task (a CollabTask when it is collaborative), parsed once."""
        with self._lock:
            if tid in self._tasks:
                return self._tasks[tid]
        row = self.task_row(tid, file=True)
        segs = tid.split("/")
        f = (self.data / row.folder).joinpath(*segs[:-1], segs[-1] + ".json")
        task = parse_task_file(loads_json(row.json, f.name), f)
        with self._lock:
            self._tasks[tid] = task
        return task

    def task(self, tid: str) -> Task:
        """The task; of a collaborative task its shared cell (every goal, the task-level constraints)."""
        t = self.parsed_task(tid)
        return t.task if isinstance(t, CollabTask) else t

    def collab_task(self, tid: str) -> CollabTask:
        t = self.parsed_task(tid)
        if not isinstance(t, CollabTask):
            raise InputError(f"task {tid!r} is a single-robot task, not collaborative")
        return t

    def module_set(self, name: str) -> ModuleSet:
        with self._lock:
            if name in self._msets:
                return self._msets[name]
        row = self.module_set_row(name, file=True)
        f = self.data / row.folder / "modules.json"
        ms = parse_module_set(loads_json(row.json, f"{name}/modules.json"), f, name=name)
        with self._lock:
            self._msets[name] = ms
        return ms

    def tasks(self) -> List[db.TaskRow]:
        """Every task, without its file (``json`` is not loaded)."""
        with self.Session() as s:
            return list(s.scalars(select(db.TaskRow).options(db.only(db.TASK_LIST_COLUMNS))
                                  .order_by(db.TaskRow.task_id)))

    def module_sets(self) -> List[db.ModuleSetRow]:
        """Every module set, without its file (``json`` is not loaded)."""
        with self.Session() as s:
            return list(s.scalars(select(db.ModuleSetRow).options(db.only(db.MODULE_SET_LIST_COLUMNS))
                                  .order_by(db.ModuleSetRow.name)))

    def cost_functions(self) -> List[db.CostFunctionRow]:
        with self.Session() as s:
            return list(s.scalars(select(db.CostFunctionRow).order_by(db.CostFunctionRow.id)))

    # ----------------------------------------------------------------------------------------------------
    # solutions
    # ----------------------------------------------------------------------------------------------------
    def prepare_solution(self, text: str, fname: str, data=None) -> Tuple[Solution, Task, ModuleSet, str, str]:
        """A single-robot solution → (solution, task, module set, display benchmark ID, cost key)."""
        data = loads_json(text, fname) if data is None else data
        sol = parse_solution(data, fname)  # schema validation first
        check_solution_size(data, sol, self.settings.limits, fname)
        display, key, ms = self._benchmark_part(sol, fname, [])
        task = self._registered_task(sol.task_id, fname)
        if isinstance(task, CollabTask):
            raise InputError(f"task {sol.task_id!r} is collaborative (robots {', '.join(task.robot_ids)}): upload one "
                             "trajectory per robot in a 'robots' list (docs/collaborative.md)", file=fname,
                             path=["taskID"])
        return sol, task, ms, display, key

    def _benchmark_part(self, sol: Solution, fname: str, where: list) -> Tuple[str, str, ModuleSet]:
        """One robot's part of the benchmark ID: lengths, set name and cost grammar, the registered module set
        (``where``: the JSON path of the robot's solution) → (single-robot display ID, cost key, module set)."""
        if not sol.module_set:
            raise InputError("the solution names no moduleSet", file=fname, path=where + ["moduleSet"])
        S = db.SolutionRow
        for key, value, col in (("taskID", sol.task_id, S.task_id), ("moduleSet", sol.module_set, S.module_set),
                                ("costFunction", sol.cost_function, S.cost_function)):
            n = col.type.length  # the database column's; checked before the cost is even parsed
            if len(value) > n:
                raise InputError(f"at most {n} characters are allowed (got {len(value)})", file=fname,
                                 path=(["taskID"] if key == "taskID" else where + [key]))
        try:
            display, key = canonical_benchmark(sol.module_set, sol.cost_function, sol.task_id)
        except InputError as e:
            raise InputError(e.reason, file=fname, path=where + list(e.json_path or ["costFunction"])) from None
        try:
            ms = self.module_set(sol.module_set)
        except NotFound:
            raise InputError(f"unknown module set {sol.module_set!r} (registered: "
                             f"{self._some(self.module_sets(), 'name')})", file=fname,
                             path=where + ["moduleSet"]) from None
        return display, key, ms

    def _registered_task(self, tid: str, fname: str) -> Union[Task, CollabTask]:
        try:
            return self.parsed_task(tid)
        except NotFound:
            raise InputError(f"unknown task {tid!r} (registered: {self._some(self.tasks(), 'task_id')})",
                             file=fname, path=["taskID"]) from None

    def prepare_collab(self, data: dict, fname: str) -> Tuple[CollabSolution, CollabTask, Dict[str, ModuleSet], str,
                                                               str]:
        """A collaborative solution (docs/collaborative.md) → (solution, task, module set of every robot, display
        benchmark ID ``[M-s1,M-s2]:[C1,C2]:task`` in the task's robot order, matching key). Its robots must be the
        task's robots (count and IDs: 400 naming the field); each robot's ``moduleSet`` is looked up among the
        registered sets, as ``robodesign check`` takes each robot's own ``moduleSet``."""
        lim = self.settings.limits
        if len(data["robots"]) > lim.robots:
            raise TooLarge(f"at most {lim.robots} robots are allowed (got {len(data['robots'])})", file=fname,
                           path=["robots"])
        csol = parse_collab_solution(data, fname)  # every robot's solution schema-validated
        check_text_sizes(data, lim, fname, [])
        n_values = 0
        for i, (rid, sol) in enumerate(csol.robots):
            check_solution_size(data["robots"][i], sol, lim, fname, ["robots", i])
            n_values += int(sol.trajectory.q.size)
        if n_values > lim.trajectory_values:
            raise TooLarge(f"{n_values} trajectory values (samples × joints of all robots); at most "
                           f"{lim.trajectory_values} are allowed", file=fname, path=["robots"])
        msets = {rid: self._benchmark_part(sol, fname, ["robots", i])[2] for i, (rid, sol) in enumerate(csol.robots)}
        ctask = self._registered_task(csol.task_id, fname)
        if not isinstance(ctask, CollabTask):
            raise InputError(f"task {csol.task_id!r} is a single-robot task: upload a CoBRA solution without a "
                             "'robots' list", file=fname, path=["taskID"])
        ids = [rid for rid, _ in csol.robots]
        if len(ids) != len(ctask.robot_ids):
            raise InputError(f"the task has {len(ctask.robot_ids)} robots ({', '.join(ctask.robot_ids)}), the solution "
                             f"gives {len(ids)}", file=fname, path=["robots"])
        for i, rid in enumerate(ids):
            if rid not in ctask.robot_ids:
                raise InputError(f"the task has no robot {rid[:100]!r} (robots: {', '.join(ctask.robot_ids)})",
                                 file=fname, path=["robots", i, "ID"])
        display = csol.benchmark_id(ctask.robot_ids)
        return csol, ctask, msets, display, collab_benchmark_key(BenchmarkID.parse(display))

    @staticmethod
    def _some(rows, attr, n=10) -> str:
        names = [getattr(r, attr) for r in rows]
        return ", ".join(names[:n]) + (", ..." if len(names) > n else "") if names else "none"

    def prepare_submission(self, text: str, fname: str = "solution.json", author: Optional[str] = None,
                           email: Optional[str] = None, affiliation: Optional[str] = None,
                           token: Optional[str] = None) -> "Submission":
        """Everything that can be refused without running the checker: JSON, schema, sizes, lengths, the task,
        module set and cost; the row to store is built and checked against the database's column rules. A solution
        with a ``robots`` list is collaborative (:meth:`prepare_collab`)."""
        data = loads_json(text, fname)
        if is_collaborative(data):
            sol, task, ms, display, robots_key = self.prepare_collab(data, fname)
            robot_sols = [s for _, s in sol.robots]
            row = db.SolutionRow(module_set="", cost_function=display.split(":")[1], cost_key="", collaborative=True,
                                 robots_key=robots_key, n_modules=sum(len(s.module_order) for s in robot_sols))
        else:
            sol, task, ms, display, key = self.prepare_solution(text, fname, data)
            robot_sols = [sol]
            row = db.SolutionRow(module_set=sol.module_set, cost_function=sol.cost_function, cost_key=key,
                                 n_modules=len(sol.module_order))

        def first(attr):
            return next((getattr(s, attr)[0] for s in robot_sols if getattr(s, attr)), "")
        author = (author or "").strip() or first("author")
        if not author:
            raise InputError("the author name is required (form field 'author' or the solution's 'author')")
        email = (email or "").strip() or first("email")
        affiliation = (affiliation or "").strip() or first("affiliation")
        if token is not None and token != "":
            check_token(token)
        row.benchmark_id, row.task_id, row.solution_json, row.token_hash, row.valid = \
            display, sol.task_id, text, "", True
        row.author_name, row.author_email, row.author_affiliation = author, email, affiliation
        db.check_row(row, {"author_name": "author", "author_email": "email", "author_affiliation": "affiliation",
                           "cost_key": "costFunction", "cost_function": "costFunction", "benchmark_id": "benchmark ID"})
        return Submission(sol, task, ms, row, token or None)

    def judge(self, sub: "Submission", token_hash: Optional[str] = None, pending: Optional[str] = None) -> SubmitResult:
        """Run the checker on a prepared submission; store it when valid. A collaborative solution is judged by
        :func:`robodesign.collab.core.check_collab`, the judge of ``robodesign check``; its ``cost`` is totalCost.
        ``token_hash``: the stored hash of the token given with an async upload (when the file names none);
        ``pending``: that upload's job ID, whose row is marked done in the same transaction that stores the
        solution (so a server killed in between neither loses nor doubles it)."""
        sol, row = sub.solution, sub.row
        if isinstance(sol, CollabSolution):
            cverdict = check_collab(sub.task, sol, sub.module_set)
            vj = clean_json(cverdict.to_json())
            cost, costs, valid = vj.get("totalCost"), vj.get("costs"), cverdict.valid
            all_costs = {rid: v.get("costs", {}) for rid, v in vj.get("robots", {}).items()}
            dof = sum(int(v.costs.get("numJ", 0) or 0) for v in cverdict.robots.values())
        else:
            verdict: Verdict = check(sub.task, sol, sub.module_set)
            vj = clean_json(verdict.to_json())
            cost, costs, valid = vj.get("cost"), None, verdict.valid
            all_costs, dof = vj.get("costs", {}), int(verdict.costs.get("numJ", 0) or 0)
        if not valid:
            return SubmitResult(False, row.benchmark_id, vj, cost, task_id=sol.task_id, module_set=row.module_set,
                                costs=costs)
        token = sub.token or (None if token_hash else secrets.token_urlsafe(24))
        row.token_hash, row.cost, row.dof = (hash_token(token) if token else token_hash), cost, dof
        row.costs_json, row.verdict_json = json.dumps(all_costs), json.dumps(vj)
        if costs is not None:
            row.cost_tuple = json.dumps(costs)
        with self.Session() as s:
            s.add(row)
            s.flush()
            rid = row.id
            res = SubmitResult(True, row.benchmark_id, vj, cost, id=rid, token=token, task_id=sol.task_id,
                               module_set=row.module_set, costs=costs)
            if pending is not None and not self._finish_pending(s, pending, 201, res.to_json()):
                s.rollback()  # judged meanwhile by another server process that resumed it too: stored once
                raise AlreadyJudged(pending)
            s.commit()
        return res

    # ----------------------------------------------------------------------------------------------------
    # async uploads: stored before the 202 answer, resumed at start-up
    # ----------------------------------------------------------------------------------------------------
    def add_pending(self, job_id: str, text: str, fname: str, meta: Dict[str, Optional[str]],
                    token_hash: Optional[str], unwrap: bool, big: bool) -> None:
        """Store an accepted async upload (committed when this returns)."""
        row = db.PendingRow(job_id=job_id, text=text, fname=fname[:300], meta_json=json.dumps(meta),
                            token_hash=token_hash, unwrap=unwrap, big=big, state="queued")
        db.check_row(row, {"text": "request body", "fname": "file name", "meta_json": "author/email/affiliation"})
        with self.Session() as s:
            s.add(row)
            s.commit()

    def pending_checks(self) -> List[db.PendingRow]:
        """Async uploads not judged yet, oldest first."""
        with self.Session() as s:
            return list(s.scalars(select(db.PendingRow).where(db.PendingRow.state == "queued")
                                  .order_by(db.PendingRow.id)))

    def pending_status(self, job_id: str) -> Optional[dict]:
        """The stored state of an async upload (``{"job", "state", "status", "result"}``), or None."""
        if len(job_id) > 40:
            return None
        cols = [db.PendingRow.job_id, db.PendingRow.state, db.PendingRow.status, db.PendingRow.result_json]
        with self.Session() as s:
            row = s.execute(select(*cols).where(db.PendingRow.job_id == job_id)).first()
        if row is None:
            return None
        out = {"job": row.job_id, "state": row.state if row.state == "done" else "queued"}
        if row.state == "done":
            out.update(status=row.status, result=json.loads(row.result_json or "null"))
        return out

    @staticmethod
    def _finish_pending(s, job_id: str, status: int, body: dict) -> bool:
        """Mark the job done in session ``s`` → False when it was done already (the row lock of the UPDATE makes a
        second process that judged the same job wait, then find it done)."""
        P = db.PendingRow
        res = s.execute(update(P).where(P.job_id == job_id, P.state == "queued")
                        .values(state="done", status=int(status), result_json=json.dumps(clean_json(body)), text="",
                                finished=db.utcnow()))
        return res.rowcount == 1

    def finish_pending(self, job_id: str, status: int, body: dict) -> None:
        with self.Session() as s:
            self._finish_pending(s, job_id, status, body)
            s.commit()

    def submit_solution(self, text: str, fname: str = "solution.json", author: Optional[str] = None,
                        email: Optional[str] = None, affiliation: Optional[str] = None,
                        token: Optional[str] = None, token_hash: Optional[str] = None,
                        pending: Optional[str] = None) -> SubmitResult:
        """Prepare, check and (when valid) store one solution, in the calling thread (``token_hash``, ``pending``:
        see :meth:`judge`)."""
        sub = self.prepare_submission(text, fname, author, email, affiliation, token)
        if token_hash is None and pending is None:
            return self.judge(sub)
        return self.judge(sub, token_hash=token_hash, pending=pending)

    def check_upload(self, text: str, fname: str, meta: Dict[str, Optional[str]], token: Optional[str],
                     unwrap: bool = False, token_hash: Optional[str] = None, pending: Optional[str] = None) -> dict:
        """One upload from start to end, as the website answers it: ``{"status": 201 | 422 | 400 | 413, "body":
        JSON answer, "result": SubmitResult (201/422 only)}``. ``unwrap``: ``text`` may be the JSON wrapper
        ``{"solution": ..., "author", "email", "affiliation", "token"}`` (its fields win over ``meta``/``token``).
        This is the CPU-heavy part (parsing, schema, checker): the site runs it on a checker thread or process."""
        try:
            if unwrap:
                text, meta, token = unwrap_upload(text, fname, meta, token)
            res = self.submit_solution(text, fname, meta.get("author"), meta.get("email"), meta.get("affiliation"),
                                       token or None, token_hash=None if token else token_hash, pending=pending)
        except TooLarge as e:
            out = {"status": 413, "body": {"detail": self.public(str(e))}}
        except InputError as e:
            out = {"status": 400, "body": {"detail": self.public(str(e))}}
        except AlreadyJudged:
            return {"status": 200, "body": self.pending_status(pending) or {}}
        except Exception as e:
            if pending is not None:  # never resumed again: it would fail the same way at every start
                self.finish_pending(pending, 500, {"detail": f"internal error ({type(e).__name__})"})
            raise
        else:
            out = {"status": 201 if res.valid else 422, "body": res.to_json(), "result": res}
            if res.valid:
                return out  # (a pending row was finished with the solution's own transaction)
        if pending is not None:
            self.finish_pending(pending, out["status"], out["body"])
        return out

    def public(self, message: str) -> str:
        """A message without the server's own paths."""
        return message.replace(str(self.data), "<data>")

    def solution_row(self, sid: int) -> db.SolutionRow:
        """The row shown on a solution page (not the solution file itself)."""
        with self.Session() as s:
            row = s.scalar(select(db.SolutionRow).options(db.only(db.SOLUTION_PAGE_COLUMNS))
                           .where(db.SolutionRow.id == solution_id(sid)))
        if row is None:
            raise NotFound(f"unknown solution {sid}")
        return row

    def solution_text(self, sid: int) -> str:
        """The solution file as uploaded."""
        with self.Session() as s:
            text = s.scalar(select(db.SolutionRow.solution_json).where(db.SolutionRow.id == solution_id(sid)))
        if text is None:
            raise NotFound(f"unknown solution {sid}")
        return text

    def solution(self, sid: int) -> Union[Solution, CollabSolution]:
        """The stored solution, parsed (a CollabSolution when it is collaborative)."""
        name = f"solution-{sid}.json"
        data = loads_json(self.solution_text(sid), name)
        return parse_collab_solution(data, name) if is_collaborative(data) else parse_solution(data, name)

    def withdraw(self, sid: int, token: Optional[str]) -> dict:
        with self.Session() as s:
            cols = db.SOLUTION_LIST_COLUMNS + (db.SolutionRow.token_hash, db.SolutionRow.withdrawn_at)
            row = s.scalar(select(db.SolutionRow).options(db.only(cols)).where(db.SolutionRow.id == solution_id(sid)))
            if row is None:
                raise NotFound(f"unknown solution {sid}")
            if not verify_token(token, row.token_hash):
                raise Forbidden("wrong or missing token: only the uploader's token (header X-Author-Token) "
                                "withdraws a solution")
            if not row.withdrawn:
                row.withdrawn = True
                row.withdrawn_at = db.utcnow()
                s.commit()
            return {"id": row.id, "withdrawn": True, "benchmark_id": row.benchmark_id}

    def list_solutions(self, task: Optional[str] = None, cost: Optional[str] = None, moduleset: Optional[str] = None,
                       min_cost: Optional[float] = None, max_cost: Optional[float] = None,
                       limit: int = 1000, collaborative: Optional[bool] = None) -> List[db.SolutionRow]:
        """Valid, non-withdrawn solutions, cheapest first (a collaborative one by its totalCost). ``moduleset`` and
        ``cost`` match single-robot solutions only; ``collaborative``: only (True) or no (False) collaborative ones."""
        q = (select(db.SolutionRow).options(db.only(db.SOLUTION_LIST_COLUMNS))
             .where(db.SolutionRow.withdrawn.is_(False), db.SolutionRow.valid.is_(True)))
        if collaborative is not None:
            q = q.where(db.SolutionRow.collaborative.is_(bool(collaborative)))
        if task:
            q = q.where(db.SolutionRow.task_id == task)
        if moduleset:
            name = moduleset[2:] if moduleset.startswith("M-") else moduleset
            q = q.where(db.SolutionRow.module_set == name)
        if cost:
            c = parse_cost(cost, path=["cost"])
            q = q.where(db.SolutionRow.cost_key == c.descriptor())
        if min_cost is not None:
            q = q.where(db.SolutionRow.cost >= min_cost)
        if max_cost is not None:
            q = q.where(db.SolutionRow.cost <= max_cost)
        q = q.order_by(db.SolutionRow.cost.asc().nulls_last(), db.SolutionRow.created.asc(), db.SolutionRow.id.asc())
        with self.Session() as s:
            return list(s.scalars(q.limit(limit)))

    def leaderboard(self, bid_text: str) -> Tuple[Board, List[db.SolutionRow]]:
        """The valid, non-withdrawn solutions of a benchmark, best first: single-robot by cost; collaborative by
        totalCost, ties broken by the cost tuple (:func:`collab_rank_key`). A single-robot ID never lists
        collaborative solutions and vice versa (400 when the ID does not fit the task)."""
        board = parse_benchmark(bid_text)
        tid = board.task_id
        if not self._has_task(tid):
            raise NotFound(f"benchmark {board.display!r}: unknown task {tid!r}")
        for ms in dict.fromkeys(board.module_sets):
            if not self._has_module_set(ms):
                raise NotFound(f"benchmark {board.display!r}: unknown module set {ms!r}")
        robots = json.loads(self.task_row(tid).robots or "[]")
        if board.collaborative and len(robots) != len(board.module_sets):
            what = (f"{len(robots)} robots ({', '.join(r['ID'] for r in robots)})" if robots
                    else "one robot (it is not collaborative)")
            raise InputError(f"benchmark {board.display!r}: task {tid!r} has {what}, the ID lists "
                             f"{len(board.module_sets)}")
        if not board.collaborative and robots:
            raise InputError(f"benchmark {board.display!r}: task {tid!r} is collaborative ({len(robots)} robots: "
                             f"{', '.join(r['ID'] for r in robots)}); its benchmark IDs list one module set per robot, "
                             f"e.g. [{','.join('M-' + board.module_set for _ in robots)}]:"
                             f"{board.display.split(':')[1]}:{tid}")
        S = db.SolutionRow
        q = (select(S).options(db.only(db.SOLUTION_LIST_COLUMNS))
             .where(S.withdrawn.is_(False), S.valid.is_(True), S.task_id == tid,
                    S.collaborative.is_(board.collaborative)))
        if board.collaborative:
            q = q.where(S.robots_key == board.robots_key)
        else:
            q = q.where(S.module_set == board.module_set, S.cost_key == board.cost_key)
        with self.Session() as s:
            rows = list(s.scalars(q))
        rows.sort(key=collab_rank_key)  # single-robot rows have an empty tuple: by cost, then upload
        return board, rows

    def benchmarks(self) -> List[dict]:
        """Benchmarks with at least one (non-withdrawn) solution: ID, count, best cost. Solutions whose cost is
        written differently but means the same (``Liu2`` / ``cyc_0.2,mechEnergy``) count for one benchmark."""
        S = db.SolutionRow
        q = (select(func.min(S.benchmark_id), S.task_id, S.module_set, S.cost_key, S.robots_key, func.count(S.id),
                    func.min(S.cost))
             .where(S.withdrawn.is_(False), S.valid.is_(True))
             .group_by(S.task_id, S.module_set, S.cost_key, S.robots_key)
             .order_by(S.task_id, S.module_set, S.cost_key, S.robots_key))
        with self.Session() as s:
            out = []
            for b, t, m, _k, rk, n, c in s.execute(q):
                sets = json.loads(rk)["sets"] if rk else [m]
                out.append({"benchmark_id": b, "task": t, "module_set": m, "module_sets": sets, "solutions": n,
                            "best_cost": c, "collaborative": bool(rk)})
            return out

    def benchmark_counter(self, tid: str):
        """``count(benchmark ID) → number of solutions`` of task ``tid`` (IDs that mean the same count together)."""
        counts = self.counts_for_task(tid)

        def count(bid: str) -> int:
            b = parse_benchmark(bid)
            return counts.get(("", b.robots_key) if b.collaborative else (b.module_set, b.cost_key), 0)
        return count

    def counts_for_task(self, tid: str) -> Dict[Tuple[str, str], int]:
        """(module set, cost key) → number of solutions of task ``tid``; of a collaborative task ("", robots key)."""
        S = db.SolutionRow
        q = (select(S.module_set, S.cost_key, S.robots_key, func.count(S.id))
             .where(S.withdrawn.is_(False), S.valid.is_(True), S.task_id == tid)
             .group_by(S.module_set, S.cost_key, S.robots_key))
        with self.Session() as s:
            return {(m, rk or k): n for m, k, rk, n in s.execute(q)}


@dataclass
class Submission:
    """A solution that passed every check but the checker itself: what :meth:`Bench.judge` needs (collaborative: a
    CollabSolution, its CollabTask and the module set of every robot by robot ID)."""
    solution: Union[Solution, CollabSolution]
    task: Union[Task, CollabTask]
    module_set: Union[ModuleSet, Dict[str, ModuleSet]]
    row: db.SolutionRow
    token: Optional[str]


def unwrap_upload(text: str, fname: str, meta: Dict[str, Optional[str]], token: Optional[str]):
    """``{"solution": {...} | "<json text>", "author": ..., "token": ...}`` → (solution text, meta, token); any other
    JSON is the solution itself."""
    data = loads_json(text, fname)
    if not (isinstance(data, dict) and "solution" in data and "taskID" not in data):
        return text, meta, token
    sol = data["solution"]
    meta = dict(meta)
    for k in ("author", "email", "affiliation"):
        if data.get(k) is not None:
            if not isinstance(data[k], str):
                raise InputError("expected a string", file="request body", path=[k])
            meta[k] = data[k]
    if data.get("token") is not None:
        token = str(data["token"])
    return (sol if isinstance(sol, str) else json.dumps(sol)), meta, token


def check_token(token: str) -> str:
    """A token chosen by the uploader: 8 to 200 characters, no NUL (else InputError)."""
    if not (8 <= len(token) <= 200):
        raise InputError("a chosen token must have 8 to 200 characters (or leave it empty to get a random one)")
    if "\x00" in token:
        raise InputError("the token contains a NUL character")
    return token


def parse_task_file(data, file: Path) -> Union[Task, CollabTask]:
    """A task file's JSON → Task, or CollabTask when it has a ``robots`` list."""
    return parse_collab_task(data, file) if is_collaborative(data) else parse_task(data, file)


def solution_id(sid) -> int:
    """A solution ID from a URL: a decimal integer the database can hold, else :class:`NotFound`."""
    text = str(sid)
    if not (text.isascii() and text.isdigit()) or len(text) > 19 or int(text) > db.MAX_ID:
        raise NotFound(f"unknown solution {text[:40]!r}")
    return int(text)


def check_text_sizes(data: dict, limits: Limits, fname: str, where: list) -> None:
    """The caps of :class:`Limits` on the free text of a solution (``where``: its JSON path; 413 naming the field)."""
    notes = data.get("notes")
    if isinstance(notes, str) and len(notes) > limits.notes_chars:
        raise TooLarge(f"at most {limits.notes_chars} characters are allowed (got {len(notes)})",
                       file=fname, path=where + ["notes"])
    for key in ("version", "publication", "processorName", "date"):
        v = data.get(key)
        if isinstance(v, str) and len(v) > limits.text_chars:
            raise TooLarge(f"at most {limits.text_chars} characters are allowed (got {len(v)})", file=fname,
                           path=where + [key])
    for key in ("author", "email", "affiliation", "tags"):
        v = data.get(key)
        v = [v] if isinstance(v, str) else (v if isinstance(v, list) else [])
        if len(v) > limits.list_items:
            raise TooLarge(f"at most {limits.list_items} entries are allowed (got {len(v)})", file=fname,
                           path=where + [key])
        for i, x in enumerate(v):
            if isinstance(x, str) and len(x) > limits.text_chars:
                raise TooLarge(f"at most {limits.text_chars} characters are allowed (got {len(x)})", file=fname,
                               path=where + [key, i])


def check_solution_size(data: dict, sol: Solution, limits: Limits, fname: str, where: list = ()) -> None:
    """The size caps of :class:`Limits` on one robot's solution (``where``: its JSON path; 413 naming the field)."""
    where = list(where)
    check_text_sizes(data, limits, fname, where)
    for key in ("moduleOrder", "moduleConnection"):
        v = data.get(key) or []
        if len(v) > limits.modules:
            raise TooLarge(f"at most {limits.modules} entries are allowed (got {len(v)})", file=fname,
                           path=where + [key])
    n = int(sol.trajectory.q.size)  # samples × joints
    if n > limits.trajectory_values:
        raise TooLarge(f"{len(sol.trajectory.q)} samples × {n // max(1, len(sol.trajectory.q))} joints = {n} values; "
                       f"at most {limits.trajectory_values} are allowed", file=fname, path=where + ["trajectory"])


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


class _Prefixed(FileSource):
    def __init__(self, inner: FileSource, prefix: str):
        self.inner, self.prefix = inner, prefix

    def get(self, rel):
        return self.inner.get(self.prefix + rel)


def solution_summary(row: db.SolutionRow) -> dict:
    """A solution's public summary; a collaborative one adds ``costs`` (the tuple, in the task's robot order; its
    ``cost`` is totalCost) and ``module_sets`` (one per robot)."""
    out = {
        "id": row.id, "benchmark_id": row.benchmark_id, "task": row.task_id, "module_set": row.module_set,
        "cost_function": row.cost_function, "cost": row.cost, "valid": row.valid, "author": row.author_name,
        "affiliation": row.author_affiliation, "created": row.created.isoformat() + "Z",
        "withdrawn": row.withdrawn, "modules": row.n_modules, "url": f"/solutions/{row.id}",
        "collaborative": bool(row.collaborative),
    }
    if row.collaborative:
        out.update(costs=json.loads(row.cost_tuple or "[]"), totalCost=row.cost,
                   module_sets=json.loads(row.robots_key)["sets"], viewer=f"/solutions/{row.id}/viewer")
    return clean_json(out)


def files_source(files: Dict[str, bytes]) -> DictSource:
    """Multipart asset files keyed by their (client-given) relative names; unsafe names are dropped."""
    out = {}
    for name, content in files.items():
        bad = dangerous_name(name)
        if bad:
            raise InputError(f"uploaded file name {name!r} {bad}; the upload is rejected")
        rel = safe_relpath(name)
        if rel is not None:
            out[rel] = content
    return DictSource(out)
