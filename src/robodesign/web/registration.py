"""Registering what solutions are judged against: seeding the site from folders, tasks and module sets uploaded
as files or zips (written through the server's staging folder), cost functions, and reading them back
(:class:`Registration`, part of :class:`~robodesign.web.service.Bench`)."""
from __future__ import annotations

import hashlib
import json
import logging
import os
import secrets
import shutil
from contextlib import contextmanager
from pathlib import Path
from typing import Dict, Iterator, List, Optional, Sequence, Type, TypeVar, Union

from sqlalchemy import select
from sqlalchemy.exc import IntegrityError

from robodesign.collab.core import (
    CollabTask,
    is_collaborative,
    parse_collab_task,
    shared_cell_json,
)
from robodesign.core.errors import InputError
from robodesign.core.jsonio import loads_json
from robodesign.core.schema import validate
from robodesign.formats.costs import known_costs, parse_cost
from robodesign.formats.module_io import parse_module_set
from robodesign.formats.module_spec import ModuleSet
from robodesign.formats.task_io import parse_task, validate_task_json
from robodesign.formats.task_spec import Task
from robodesign.web import db
from robodesign.web.bench_base import BenchBase
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
from robodesign.web.site_errors import Conflict, NotFound

log = logging.getLogger("robodesign.web")
_Row = TypeVar("_Row", db.TaskRow, db.ModuleSetRow)  # a registered task or module set


def parse_task_file(data, file: Path) -> Union[Task, CollabTask]:
    """A task file's JSON → Task, or CollabTask when it has a ``robots`` list."""
    return parse_collab_task(data, file) if is_collaborative(data) else parse_task(data, file)


class _Prefixed(FileSource):
    def __init__(self, inner: FileSource, prefix: str):
        self.inner, self.prefix = inner, prefix

    def get(self, rel):
        return self.inner.get(self.prefix + rel)


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


class Registration(BenchBase):
    """Seeding, task and module-set registration (files and zips), and the registered objects, parsed once and cached."""

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

    def _staging(self) -> Path:
        if self.tmp is None:
            raise RuntimeError("a checker process of the site (staging=False) registers nothing")
        p = self.tmp / secrets.token_hex(8)
        p.mkdir(parents=True)
        return p

    @contextmanager
    def _stage(self) -> Iterator[Path]:
        """A fresh staging folder (:meth:`_staging`), removed on leaving, whether or not what it held was moved."""
        stage = self._staging()
        try:
            yield stage
        finally:
            shutil.rmtree(stage, ignore_errors=True)

    def _move_in(self, pkg: Path, kind: str, name: str) -> Path:
        """Move the checked package folder ``pkg`` into the data folder as ``<kind>/<name>-<random>``; that folder,
        relative to the data folder."""
        assert_no_symlinks(pkg)
        folder = Path(kind) / f"{name}-{secrets.token_hex(6)}"
        os.replace(pkg, self.data / folder)
        return folder

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
        with self._stage() as stage:
            pkg = stage / "pkg"
            pkg.mkdir()
            refs = check_mesh_refs(data, pkg, fname)
            assets = self._store_refs(refs, source, pkg)
            task_file = pkg.joinpath(*segs[:-1], segs[-1] + ".json")
            write_new_file(pkg, "/".join(segs) + ".json", text.encode("utf-8"))
            parsed = parse_task_file(loads_json(text, fname), task_file)  # the file as written: its warnings too
            task = parsed.task if isinstance(parsed, CollabTask) else parsed
            folder = self._move_in(pkg, "tasks", segs[-1])
        row.tags, row.folder, row.assets = json.dumps(list(task.header.tags)), folder.as_posix(), json.dumps(assets)
        row.n_goals, row.n_obstacles = len(task.goals), len(task.obstacles)
        robots = ([{"ID": rid, "name": parsed.robot_names[rid]} for rid in parsed.robot_ids]
                  if isinstance(parsed, CollabTask) else [])
        row.robots = json.dumps(robots)
        self._commit_new(row, folder, f"task {tid!r} is already registered")
        out = {"id": tid, "name": row.name, "assets": [a["path"] for a in assets], "warnings": list(task.warnings),
               "url": f"/tasks/{tid}", "collaborative": collab}
        if isinstance(parsed, CollabTask):
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
        with self._stage() as stage:
            root = stage / name
            root.mkdir()
            refs = check_mesh_refs(data, root, fname)
            assets = self._store_refs(refs, source, root)
            write_new_file(root, "modules.json", text.encode("utf-8"))
            ms = parse_module_set(data, root / "modules.json", name=name)
            folder = self._move_in(root, "modulesets", name)
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

    def _row(self, table: Type[_Row], columns: tuple, key_column, key: str, what: str, file: bool) -> _Row:
        """The row of ``table`` whose ``key_column`` is ``key``, with the listing ``columns`` and its file (``json``)
        only when ``file``; NotFound (``unknown <what> <key>``) when there is none."""
        cols = columns + ((table.json,) if file else ())
        with self.Session() as s:
            row = s.scalar(select(table).options(db.only(cols)).where(key_column == key))
        if row is None:
            raise NotFound(f"unknown {what} {key!r}")
        return row

    def task_row(self, tid: str, file: bool = False) -> db.TaskRow:
        """The task's row; its file (``json``) only when ``file``."""
        return self._row(db.TaskRow, db.TASK_LIST_COLUMNS, db.TaskRow.task_id, tid, "task", file)

    def module_set_row(self, name: str, file: bool = False) -> db.ModuleSetRow:
        """The module set's row; its file (``json``) only when ``file``."""
        return self._row(db.ModuleSetRow, db.MODULE_SET_LIST_COLUMNS, db.ModuleSetRow.name, name, "module set", file)

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

    def _rows(self, table: Type[_Row], columns: tuple, key_column) -> List[_Row]:
        """Every row of ``table`` by ``key_column``, with the listing ``columns`` only."""
        with self.Session() as s:
            return list(s.scalars(select(table).options(db.only(columns)).order_by(key_column)))

    def tasks(self) -> List[db.TaskRow]:
        """Every task, without its file (``json`` is not loaded)."""
        return self._rows(db.TaskRow, db.TASK_LIST_COLUMNS, db.TaskRow.task_id)

    def module_sets(self) -> List[db.ModuleSetRow]:
        """Every module set, without its file (``json`` is not loaded)."""
        return self._rows(db.ModuleSetRow, db.MODULE_SET_LIST_COLUMNS, db.ModuleSetRow.name)

    def cost_functions(self) -> List[db.CostFunctionRow]:
        with self.Session() as s:
            return list(s.scalars(select(db.CostFunctionRow).order_by(db.CostFunctionRow.id)))
