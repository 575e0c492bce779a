"""The benchmark's business logic, independent of HTTP: registering tasks / module sets / cost functions,
judging and storing solutions, leaderboards, queries and withdrawal.

Everything here is synchronous; the web layer runs it in a thread pool. Bad input raises
:class:`~robodesign.errors.InputError` (HTTP 400; :class:`TooLarge` 413), :class:`Conflict` (409),
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
from typing import Dict, List, Optional, Sequence, Tuple

from sqlalchemy import func, select
from sqlalchemy.exc import IntegrityError

from ..benchmark_id import BenchmarkID, RobotRef, RobotSpec
from ..checker import Verdict, check
from ..costs import known_costs, parse_cost
from ..errors import InputError, RobodesignError
from ..jsonio import loads_json
from ..module_io import parse_module_set
from ..module_spec import ModuleSet
from ..schema import validate
from ..solution import Solution, parse_solution
from ..task_io import parse_task, validate_task_json
from ..task_spec import Task
from . import db
from .safefiles import (dangerous_name, DictSource, FileSource, FolderSource, TooLarge, ZipSource, assert_no_symlinks,
                        check_mesh_refs, check_name, safe_relpath, task_id_segments, write_new_file)

log = logging.getLogger("robodesign.web")

MiB = 1 << 20


class Conflict(RobodesignError):
    pass


class NotFound(RobodesignError):
    pass


class Forbidden(RobodesignError):
    pass


@dataclass
class Limits:
    """What one uploaded solution may hold (docs/website.md, "Limits"). Beyond them: 413 naming the field."""
    notes_chars: int = 16_384  # ``notes``
    text_chars: int = 1_000  # every other free-text field: version, publication, processorName, date, list entries
    list_items: int = 100  # entries of author / email / affiliation / tags
    trajectory_values: int = 500_000  # samples × joints of the trajectory
    modules: int = 1_000  # entries of moduleOrder / moduleConnection


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

    def to_json(self) -> dict:
        out = {"id": self.id, "valid": self.valid, "cost": self.cost, "benchmark_id": self.benchmark_id}
        if self.valid:
            out["token"] = self.token
        else:
            out["violations"] = self.verdict.get("violations", [])
            out["verdict"] = self.verdict
            first = out["violations"][0] if out["violations"] else {}
            out["detail"] = (f"the solution is invalid: {len(out['violations'])} violation(s)"
                             + (f", first [{first.get('constraint')}] {first.get('message')}" if first else ""))
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


MAX_BENCHMARK_ID = 600  # the solutions.benchmark_id column


def parse_benchmark(text: str) -> Tuple[str, str, str, str]:
    """→ (display ID, module set, cost key, task ID). Bare robot names mean ``M-``."""
    if len(text) > MAX_BENCHMARK_ID:
        raise InputError(f"benchmark ID of {len(text)} characters (at most {MAX_BENCHMARK_ID})")
    bid = BenchmarkID.parse(text)
    if bid.robot.collaborative or len(bid.robot.robots) != 1:
        raise InputError(f"benchmark ID {text!r}: collaborative (multi-robot) benchmarks are not hosted")
    r = bid.robot.robots[0]
    if r.kind != "module_set":
        raise NotFound(f"benchmark ID {text!r}: only module-set benchmarks (M-<set>) are hosted here")
    display, key = canonical_benchmark(r.name, bid.cost.name or bid.cost.descriptor(), bid.task)
    return display, r.name, key, bid.task


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
        self._tasks: Dict[str, Task] = {}
        self._msets: Dict[str, ModuleSet] = {}

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
        """Validate (schema first), store the task file and its referenced meshes, register it."""
        data = validate_task_json(loads_json(text, fname), fname)
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
            task = parse_task(loads_json(text, fname), task_file)  # the file as written: its warnings too
            assert_no_symlinks(pkg)
            folder = Path("tasks") / f"{segs[-1]}-{secrets.token_hex(6)}"
            os.replace(pkg, self.data / folder)
        except BaseException:
            shutil.rmtree(stage, ignore_errors=True)
            raise
        shutil.rmtree(stage, ignore_errors=True)
        row.tags, row.folder, row.assets = json.dumps(list(task.header.tags)), folder.as_posix(), json.dumps(assets)
        row.n_goals, row.n_obstacles = len(task.goals), len(task.obstacles)
        self._commit_new(row, folder, f"task {tid!r} is already registered")
        return {"id": tid, "name": row.name, "assets": [a["path"] for a in assets], "warnings": list(task.warnings),
                "url": f"/tasks/{tid}"}

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

    def task(self, tid: str) -> Task:
        with self._lock:
            if tid in self._tasks:
                return self._tasks[tid]
        row = self.task_row(tid, file=True)
        segs = tid.split("/")
        f = (self.data / row.folder).joinpath(*segs[:-1], segs[-1] + ".json")
        task = parse_task(loads_json(row.json, f.name), f)
        with self._lock:
            self._tasks[tid] = task
        return task

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
    def prepare_solution(self, text: str, fname: str) -> Tuple[Solution, Task, ModuleSet, str, str]:
        data = loads_json(text, fname)
        sol = parse_solution(data, fname)  # schema validation first
        check_solution_size(data, sol, self.settings.limits, fname)
        if not sol.module_set:
            raise InputError("the solution names no moduleSet", file=fname, path=["moduleSet"])
        S = db.SolutionRow
        for key, value, col in (("taskID", sol.task_id, S.task_id), ("moduleSet", sol.module_set, S.module_set),
                                ("costFunction", sol.cost_function, S.cost_function)):
            n = col.type.length  # the database column's; checked before the cost is even parsed
            if len(value) > n:
                raise InputError(f"at most {n} characters are allowed (got {len(value)})", file=fname, path=[key])
        try:
            display, key = canonical_benchmark(sol.module_set, sol.cost_function, sol.task_id)
        except InputError as e:
            raise InputError(e.reason, file=fname, path=e.json_path or ["costFunction"]) from None
        try:
            task = self.task(sol.task_id)
        except NotFound:
            raise InputError(f"unknown task {sol.task_id!r} (registered: {self._some(self.tasks(), 'task_id')})",
                             file=fname, path=["taskID"]) from None
        try:
            ms = self.module_set(sol.module_set)
        except NotFound:
            raise InputError(f"unknown module set {sol.module_set!r} (registered: "
                             f"{self._some(self.module_sets(), 'name')})", file=fname, path=["moduleSet"]) from None
        return sol, task, ms, display, key

    @staticmethod
    def _some(rows, attr, n=10) -> str:
        names = [getattr(r, attr) for r in rows]
        return ", ".join(names[:n]) + (", ..." if len(names) > n else "") if names else "none"

    def prepare_submission(self, text: str, fname: str = "solution.json", author: Optional[str] = None,
                           email: Optional[str] = None, affiliation: Optional[str] = None,
                           token: Optional[str] = None) -> "Submission":
        """Everything that can be refused without running the checker: JSON, schema, sizes, lengths, the task,
        module set and cost; the row to store is built and checked against the database's column rules."""
        sol, task, ms, display, key = self.prepare_solution(text, fname)
        author = (author or "").strip() or (sol.author[0] if sol.author else "")
        if not author:
            raise InputError("the author name is required (form field 'author' or the solution's 'author')")
        email = (email or "").strip() or (sol.email[0] if sol.email else "")
        affiliation = (affiliation or "").strip() or (sol.affiliation[0] if sol.affiliation else "")
        if token is not None and token != "" and not (8 <= len(token) <= 200):
            raise InputError("a chosen token must have 8 to 200 characters (or leave it empty to get a random one)")
        row = db.SolutionRow(benchmark_id=display, task_id=sol.task_id, module_set=sol.module_set,
                             cost_function=sol.cost_function, cost_key=key, author_name=author, author_email=email,
                             author_affiliation=affiliation, token_hash="", valid=True, solution_json=text,
                             n_modules=len(sol.module_order))
        db.check_row(row, {"author_name": "author", "author_email": "email", "author_affiliation": "affiliation",
                           "cost_key": "costFunction", "benchmark_id": "benchmark ID"})
        if token and "\x00" in token:
            raise InputError("the token contains a NUL character")
        return Submission(sol, task, ms, row, token or None)

    def judge(self, sub: "Submission") -> SubmitResult:
        """Run the checker on a prepared submission; store it when valid."""
        sol, row = sub.solution, sub.row
        verdict: Verdict = check(sub.task, sol, sub.module_set)
        vj = clean_json(verdict.to_json())
        cost = vj.get("cost")
        if not verdict.valid:
            return SubmitResult(False, row.benchmark_id, vj, cost, task_id=sol.task_id, module_set=sol.module_set)
        token = sub.token or secrets.token_urlsafe(24)
        row.token_hash, row.cost = hash_token(token), cost
        row.costs_json, row.verdict_json = json.dumps(vj.get("costs", {})), json.dumps(vj)
        row.dof = int(verdict.costs.get("numJ", 0) or 0)
        with self.Session() as s:
            s.add(row)
            s.commit()
            rid = row.id
        return SubmitResult(True, row.benchmark_id, vj, cost, id=rid, token=token, task_id=sol.task_id,
                            module_set=sol.module_set)

    def submit_solution(self, text: str, fname: str = "solution.json", author: Optional[str] = None,
                        email: Optional[str] = None, affiliation: Optional[str] = None,
                        token: Optional[str] = None) -> SubmitResult:
        """Prepare, check and (when valid) store one solution, in the calling thread."""
        return self.judge(self.prepare_submission(text, fname, author, email, affiliation, token))

    def check_upload(self, text: str, fname: str, meta: Dict[str, Optional[str]], token: Optional[str],
                     unwrap: bool = False) -> dict:
        """One upload from start to end, as the website answers it: ``{"status": 201 | 422 | 400 | 413, "body":
        JSON answer, "result": SubmitResult (201/422 only)}``. ``unwrap``: ``text`` may be the JSON wrapper
        ``{"solution": ..., "author", "email", "affiliation", "token"}`` (its fields win over ``meta``/``token``).
        This is the CPU-heavy part (parsing, schema, checker): the site runs it on a checker thread or process."""
        try:
            if unwrap:
                text, meta, token = unwrap_upload(text, fname, meta, token)
            res = self.submit_solution(text, fname, meta.get("author"), meta.get("email"), meta.get("affiliation"),
                                       token or None)
        except TooLarge as e:
            return {"status": 413, "body": {"detail": self.public(str(e))}}
        except InputError as e:
            return {"status": 400, "body": {"detail": self.public(str(e))}}
        return {"status": 201 if res.valid else 422, "body": res.to_json(), "result": res}

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

    def solution(self, sid: int) -> Solution:
        return parse_solution(loads_json(self.solution_text(sid), f"solution-{sid}.json"), f"solution-{sid}.json")

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
                       limit: int = 1000) -> List[db.SolutionRow]:
        q = (select(db.SolutionRow).options(db.only(db.SOLUTION_LIST_COLUMNS))
             .where(db.SolutionRow.withdrawn.is_(False), db.SolutionRow.valid.is_(True)))
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

    def leaderboard(self, bid_text: str) -> Tuple[str, str, str, str, List[db.SolutionRow]]:
        display, ms, key, tid = parse_benchmark(bid_text)
        if not self._has_task(tid):
            raise NotFound(f"benchmark {display!r}: unknown task {tid!r}")
        if not self._has_module_set(ms):
            raise NotFound(f"benchmark {display!r}: unknown module set {ms!r}")
        q = (select(db.SolutionRow).options(db.only(db.SOLUTION_LIST_COLUMNS))
             .where(db.SolutionRow.withdrawn.is_(False), db.SolutionRow.valid.is_(True),
                    db.SolutionRow.task_id == tid, db.SolutionRow.module_set == ms, db.SolutionRow.cost_key == key)
             .order_by(db.SolutionRow.cost.asc().nulls_last(), db.SolutionRow.created.asc(), db.SolutionRow.id.asc()))
        with self.Session() as s:
            rows = list(s.scalars(q))
        return display, ms, key, tid, rows

    def benchmarks(self) -> List[dict]:
        """Benchmarks with at least one (non-withdrawn) solution: ID, count, best cost. Solutions whose cost is
        written differently but means the same (``Liu2`` / ``cyc_0.2,mechEnergy``) count for one benchmark."""
        S = db.SolutionRow
        q = (select(func.min(S.benchmark_id), S.task_id, S.module_set, S.cost_key, func.count(S.id), func.min(S.cost))
             .where(S.withdrawn.is_(False), S.valid.is_(True))
             .group_by(S.task_id, S.module_set, S.cost_key)
             .order_by(S.task_id, S.module_set, S.cost_key))
        with self.Session() as s:
            return [{"benchmark_id": b, "task": t, "module_set": m, "solutions": n, "best_cost": c}
                    for b, t, m, _k, n, c in s.execute(q)]

    def counts_for_task(self, tid: str) -> Dict[Tuple[str, str], int]:
        """(module set, cost key) → number of solutions of task ``tid``."""
        S = db.SolutionRow
        q = (select(S.module_set, S.cost_key, func.count(S.id))
             .where(S.withdrawn.is_(False), S.valid.is_(True), S.task_id == tid)
             .group_by(S.module_set, S.cost_key))
        with self.Session() as s:
            return {(m, k): n for m, k, n in s.execute(q)}


@dataclass
class Submission:
    """A solution that passed every check but the checker itself: what :meth:`Bench.judge` needs."""
    solution: Solution
    task: Task
    module_set: ModuleSet
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


def solution_id(sid) -> int:
    """A solution ID from a URL: a decimal integer the database can hold, else :class:`NotFound`."""
    text = str(sid)
    if not (text.isascii() and text.isdigit()) or len(text) > 19 or int(text) > db.MAX_ID:
        raise NotFound(f"unknown solution {text[:40]!r}")
    return int(text)


def check_solution_size(data: dict, sol: Solution, limits: Limits, fname: str) -> None:
    """The size caps of :class:`Limits` (413 naming the field)."""
    if len(sol.notes) > limits.notes_chars:
        raise TooLarge(f"at most {limits.notes_chars} characters are allowed (got {len(sol.notes)})",
                       file=fname, path=["notes"])
    for key in ("version", "publication", "processorName", "date"):
        v = data.get(key)
        if isinstance(v, str) and len(v) > limits.text_chars:
            raise TooLarge(f"at most {limits.text_chars} characters are allowed (got {len(v)})", file=fname,
                           path=[key])
    for key in ("author", "email", "affiliation", "tags"):
        v = data.get(key)
        v = [v] if isinstance(v, str) else (v or [])
        if len(v) > limits.list_items:
            raise TooLarge(f"at most {limits.list_items} entries are allowed (got {len(v)})", file=fname, path=[key])
        for i, x in enumerate(v):
            if isinstance(x, str) and len(x) > limits.text_chars:
                raise TooLarge(f"at most {limits.text_chars} characters are allowed (got {len(x)})", file=fname,
                               path=[key, i])
    for key in ("moduleOrder", "moduleConnection"):
        v = data.get(key) or []
        if len(v) > limits.modules:
            raise TooLarge(f"at most {limits.modules} entries are allowed (got {len(v)})", file=fname, path=[key])
    n = int(sol.trajectory.q.size)  # samples × joints
    if n > limits.trajectory_values:
        raise TooLarge(f"{len(sol.trajectory.q)} samples × {n // max(1, len(sol.trajectory.q))} joints = {n} values; "
                       f"at most {limits.trajectory_values} are allowed", file=fname, path=["trajectory"])


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
    return clean_json({
        "id": row.id, "benchmark_id": row.benchmark_id, "task": row.task_id, "module_set": row.module_set,
        "cost_function": row.cost_function, "cost": row.cost, "valid": row.valid, "author": row.author_name,
        "affiliation": row.author_affiliation, "created": row.created.isoformat() + "Z",
        "withdrawn": row.withdrawn, "modules": row.n_modules, "url": f"/solutions/{row.id}",
    })


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
