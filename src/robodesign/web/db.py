"""Database schema and engine of the benchmark website (SQLAlchemy 2; SQLite by default, PostgreSQL by URL).

Tables: ``tasks``, ``module_sets``, ``cost_functions``, ``solutions``, ``pending_checks`` (async uploads until
judged). Task and module-set *files* (JSON and meshes) live in the data folder; the rows hold the JSON text, the
folder (relative to the data folder) and a list of the stored assets with their SHA-256.
"""
from __future__ import annotations

import datetime as _dt
from pathlib import Path
from typing import Dict, Optional, Sequence

from sqlalchemy import (
    Boolean,
    DateTime,
    DefaultClause,
    Float,
    Index,
    Integer,
    String,
    Text,
    create_engine,
    event,
    false,
    inspect,
    text,
)
from sqlalchemy.engine import Engine, make_url
from sqlalchemy.exc import DBAPIError
from sqlalchemy.orm import DeclarativeBase, Mapped, load_only, mapped_column, sessionmaker
from sqlalchemy.orm.interfaces import LoaderOption

from robodesign.core.errors import InputError

MAX_ID = 2 ** 31 - 1  # the largest row ID of the Integer key columns on every backend (32 bits on PostgreSQL)


def utcnow() -> _dt.datetime:
    return _dt.datetime.now(_dt.timezone.utc).replace(tzinfo=None)


class Base(DeclarativeBase):
    pass


class TaskRow(Base):
    __tablename__ = "tasks"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    task_id: Mapped[str] = mapped_column(String(200), unique=True, index=True)  # CoBRA ID, e.g. simple/PTP_1
    name: Mapped[str] = mapped_column(String(200), default="")
    tags: Mapped[str] = mapped_column(Text, default="[]")  # JSON list
    json: Mapped[str] = mapped_column(Text)  # the task file as uploaded
    folder: Mapped[str] = mapped_column(String(300))  # package folder, relative to the data folder
    assets: Mapped[str] = mapped_column(Text, default="[]")  # JSON [{path, size, sha256}]
    n_goals: Mapped[int] = mapped_column(Integer, default=0)
    n_obstacles: Mapped[int] = mapped_column(Integer, default=0)
    # collaborative task: JSON [{"ID", "name"}] of its robots; "[]" single-robot; NULL: not yet known (a row of an
    # older version, filled in by the site at startup)
    robots: Mapped[Optional[str]] = mapped_column(Text, nullable=True)
    origin: Mapped[str] = mapped_column(String(20), default="upload")  # seed | upload
    created: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow)


class ModuleSetRow(Base):
    __tablename__ = "module_sets"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(100), unique=True, index=True)
    json: Mapped[str] = mapped_column(Text)  # modules.json as uploaded
    folder: Mapped[str] = mapped_column(String(300))
    assets: Mapped[str] = mapped_column(Text, default="[]")
    module_ids: Mapped[str] = mapped_column(Text, default="[]")  # JSON list
    origin: Mapped[str] = mapped_column(String(20), default="upload")
    created: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow)


class CostFunctionRow(Base):
    __tablename__ = "cost_functions"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(100), unique=True)
    descriptor: Mapped[str] = mapped_column(String(300))  # canonical CoBRA descriptor, e.g. cyc_0.2,mechEnergy
    description: Mapped[str] = mapped_column(Text, default="")
    created: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow)


class SolutionRow(Base):
    __tablename__ = "solutions"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    benchmark_id: Mapped[str] = mapped_column(String(600), index=True)  # canonical M-<set>:<cost>:<task>
    task_id: Mapped[str] = mapped_column(String(200), index=True)
    module_set: Mapped[str] = mapped_column(String(100))  # "" for a collaborative solution (see robots_key)
    cost_function: Mapped[str] = mapped_column(String(300))  # as written (collaborative: the ID's cost part)
    cost_key: Mapped[str] = mapped_column(String(300))  # canonical descriptor (matching key); "" collaborative
    # collaborative solutions ([M-s1,M-s2]:[C1,C2]:task): the matching key {"sets": [...], "costs": [descriptors]}
    # in the task's robot order, and the cost tuple (``cost`` holds totalCost, their sum)
    collaborative: Mapped[bool] = mapped_column(Boolean, default=False, server_default=false())
    robots_key: Mapped[str] = mapped_column(Text, default="", server_default=text("''"))
    cost_tuple: Mapped[str] = mapped_column(Text, default="[]", server_default=text("'[]'"))
    author_name: Mapped[str] = mapped_column(String(200))
    author_email: Mapped[str] = mapped_column(String(200), default="")
    author_affiliation: Mapped[str] = mapped_column(String(300), default="")
    token_hash: Mapped[str] = mapped_column(String(200))
    valid: Mapped[bool] = mapped_column(Boolean, default=True)
    cost: Mapped[Optional[float]] = mapped_column(Float, nullable=True)
    costs_json: Mapped[str] = mapped_column(Text, default="{}")
    verdict_json: Mapped[str] = mapped_column(Text, default="{}")
    solution_json: Mapped[str] = mapped_column(Text)
    n_modules: Mapped[int] = mapped_column(Integer, default=0)
    dof: Mapped[int] = mapped_column(Integer, default=0)
    created: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow)
    withdrawn: Mapped[bool] = mapped_column(Boolean, default=False)
    withdrawn_at: Mapped[Optional[_dt.datetime]] = mapped_column(DateTime, nullable=True)


class PendingRow(Base):
    """An upload answered 202 (``?async=1``): stored *before* the answer, so that a server killed before its check
    ends resumes it at start-up. ``text`` is emptied once the check is done (a valid solution is then in
    ``solutions``, written in the same transaction as ``state = "done"``)."""
    __tablename__ = "pending_checks"
    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    job_id: Mapped[str] = mapped_column(String(40), unique=True, index=True)
    state: Mapped[str] = mapped_column(String(20), default="queued", index=True)  # queued | done
    text: Mapped[str] = mapped_column(Text)  # the upload as received (UTF-8 text)
    fname: Mapped[str] = mapped_column(String(300), default="solution.json")
    meta_json: Mapped[str] = mapped_column(Text, default="{}")  # author / email / affiliation given outside the file
    token_hash: Mapped[Optional[str]] = mapped_column(String(200), nullable=True)
    unwrap: Mapped[bool] = mapped_column(Boolean, default=False)
    big: Mapped[bool] = mapped_column(Boolean, default=False)
    status: Mapped[Optional[int]] = mapped_column(Integer, nullable=True)  # HTTP status of the result
    result_json: Mapped[Optional[str]] = mapped_column(Text, nullable=True)
    created: Mapped[_dt.datetime] = mapped_column(DateTime, default=utcnow)
    finished: Mapped[Optional[_dt.datetime]] = mapped_column(DateTime, nullable=True)


Index("ix_solutions_board", SolutionRow.task_id, SolutionRow.module_set, SolutionRow.cost_key, SolutionRow.cost)


# columns the listings read (never the stored files: json, solution_json, verdict_json, ...)
TASK_LIST_COLUMNS = (TaskRow.id, TaskRow.task_id, TaskRow.name, TaskRow.tags, TaskRow.folder, TaskRow.assets,
                     TaskRow.n_goals, TaskRow.n_obstacles, TaskRow.robots, TaskRow.origin, TaskRow.created)
MODULE_SET_LIST_COLUMNS = (ModuleSetRow.id, ModuleSetRow.name, ModuleSetRow.folder, ModuleSetRow.assets,
                           ModuleSetRow.module_ids, ModuleSetRow.origin, ModuleSetRow.created)
SOLUTION_LIST_COLUMNS = (SolutionRow.id, SolutionRow.benchmark_id, SolutionRow.task_id, SolutionRow.module_set,
                         SolutionRow.cost_function, SolutionRow.cost_key, SolutionRow.author_name,
                         SolutionRow.author_affiliation, SolutionRow.valid, SolutionRow.cost, SolutionRow.n_modules,
                         SolutionRow.dof, SolutionRow.created, SolutionRow.withdrawn, SolutionRow.collaborative,
                         SolutionRow.robots_key, SolutionRow.cost_tuple)
SOLUTION_PAGE_COLUMNS = SOLUTION_LIST_COLUMNS + (SolutionRow.verdict_json,)


def only(columns: Sequence) -> LoaderOption:
    """Query option: load just these columns (the others raise when touched on a detached row)."""
    return load_only(*columns, raiseload=True)


def check_row(row: Base, fields: Optional[Dict[str, str]] = None, file: Optional[str] = None) -> None:
    """Refuse values the database would refuse, *before* anything is stored or checked: a string longer than its
    column (PostgreSQL raises, SQLite would silently keep it) or containing a NUL character (PostgreSQL text
    cannot hold it). ``fields`` maps column names to the names the user knows (JSON fields, form fields)."""
    unloaded = inspect(row).unloaded
    for col in row.__table__.columns:
        if col.key in unloaded:
            continue
        v = getattr(row, col.key, None)
        if not isinstance(v, str):
            continue
        label = (fields or {}).get(col.key, col.key)
        if "\x00" in v:
            raise InputError("contains a NUL character", file=file, path=[label])
        n = getattr(col.type, "length", None)
        if n is not None and len(v) > n:
            raise InputError(f"at most {n} characters are allowed (got {len(v)})", file=file, path=[label])


def _check_before_flush(session, _ctx, _instances):  # the safety net under every explicit check_row
    for obj in list(session.new) + list(session.dirty):
        if isinstance(obj, Base):
            check_row(obj)


def normalize_url(db_url: Optional[str], data_dir: Path) -> str:
    """Default: ``sqlite:///<data>/bench.db``. ``postgresql://`` / ``postgres://`` use the psycopg 3 driver."""
    if not db_url:
        return f"sqlite:///{(Path(data_dir) / 'bench.db').resolve()}"
    if db_url.startswith("postgres://"):
        db_url = "postgresql://" + db_url[len("postgres://"):]
    if db_url.startswith("postgresql://"):
        db_url = "postgresql+psycopg://" + db_url[len("postgresql://"):]
    return db_url


def make_engine(url: str) -> Engine:
    u = make_url(url)
    if u.get_backend_name() == "sqlite":
        engine = create_engine(url, connect_args={"check_same_thread": False, "timeout": 30}, pool_pre_ping=True)

        @event.listens_for(engine, "connect")
        def _sqlite_pragmas(dbapi_conn, _record):  # WAL: readers never block the (single) writer
            cur = dbapi_conn.cursor()
            cur.execute("PRAGMA journal_mode=WAL")
            cur.execute("PRAGMA synchronous=NORMAL")
            cur.execute("PRAGMA busy_timeout=30000")
            cur.close()
        return engine
    return create_engine(url, pool_pre_ping=True, pool_size=10, max_overflow=20)


def add_missing_columns(engine: Engine) -> list:
    """Bring the tables of an older version up to date: every column of the model that a table lacks is added
    (``ALTER TABLE ... ADD COLUMN`` with the column's server default; existing rows get it). Safe when several
    processes start on one database at once (a column another process has just added is skipped).
    → the added ``table.column`` names."""
    added = []
    for table in Base.metadata.sorted_tables:
        have = {c["name"] for c in inspect(engine).get_columns(table.name)}
        for col in table.columns:
            if col.name in have:
                continue
            ddl = f"ALTER TABLE {table.name} ADD COLUMN {col.name} {col.type.compile(engine.dialect)}"
            if isinstance(col.server_default, DefaultClause):  # (the columns' server defaults are all SQL text)
                default = col.server_default.arg
                ddl += " DEFAULT " + (default if isinstance(default, str)
                                      else str(default.compile(dialect=engine.dialect)))
            try:
                with engine.begin() as con:
                    con.execute(text(ddl))
            except DBAPIError:  # added meanwhile by another process starting on the same database
                if col.name not in {c["name"] for c in inspect(engine).get_columns(table.name)}:
                    raise
                continue
            added.append(f"{table.name}.{col.name}")
    return added


def make_sessionmaker(engine: Engine) -> sessionmaker:
    Base.metadata.create_all(engine)
    add_missing_columns(engine)
    maker = sessionmaker(engine, expire_on_commit=False)
    event.listen(maker, "before_flush", _check_before_flush)
    return maker
