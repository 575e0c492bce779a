"""Benchmarks and leaderboards: benchmark IDs from URLs and uploads, the ranking of collaborative boards, and
the queries behind the site's solution lists, leaderboards, benchmark counters and withdrawal
(:class:`Leaderboards`, part of :class:`~robodesign.web.service.Bench`)."""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Dict, List, Optional, Tuple, Union

from sqlalchemy import func, select

from robodesign.collab.core import (
    CollabSolution,
    is_collaborative,
    parse_collab_solution,
)
from robodesign.core.errors import InputError
from robodesign.core.jsonio import loads_json
from robodesign.formats.benchmark_id import BenchmarkID, RobotRef, RobotSpec
from robodesign.formats.costs import parse_cost
from robodesign.formats.solution import Solution, parse_solution
from robodesign.web import db
from robodesign.web.bench_base import BenchBase
from robodesign.web.site_errors import Forbidden, NotFound
from robodesign.web.tokens import verify_token


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


def clean_json(obj):
    """Replace non-finite floats (not representable in strict JSON) by None."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: clean_json(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [clean_json(v) for v in obj]
    return obj


def solution_id(sid) -> int:
    """A solution ID from a URL: a decimal integer the database can hold, else :class:`NotFound`."""
    text = str(sid)
    if not (text.isascii() and text.isdigit()) or len(text) > 19 or int(text) > db.MAX_ID:
        raise NotFound(f"unknown solution {text[:40]!r}")
    return int(text)


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


class Leaderboards(BenchBase):
    """Solutions as the site shows them: one solution, lists, leaderboards, benchmark counters; withdrawal."""

    def solution_row(self, sid: Union[int, str]) -> db.SolutionRow:
        """The row shown on a solution page (not the solution file itself)."""
        with self.Session() as s:
            row = s.scalar(select(db.SolutionRow).options(db.only(db.SOLUTION_PAGE_COLUMNS))
                           .where(db.SolutionRow.id == solution_id(sid)))
        if row is None:
            raise NotFound(f"unknown solution {sid}")
        return row

    def solution_text(self, sid: Union[int, str]) -> str:
        """The solution file as uploaded."""
        with self.Session() as s:
            text = s.scalar(select(db.SolutionRow.solution_json).where(db.SolutionRow.id == solution_id(sid)))
        if text is None:
            raise NotFound(f"unknown solution {sid}")
        return text

    def solution(self, sid: Union[int, str]) -> Union[Solution, CollabSolution]:
        """The stored solution, parsed (a CollabSolution when it is collaborative)."""
        name = f"solution-{sid}.json"
        data = loads_json(self.solution_text(sid), name)
        return parse_collab_solution(data, name) if is_collaborative(data) else parse_solution(data, name)

    def withdraw(self, sid: Union[int, str], token: Optional[str]) -> dict:
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
