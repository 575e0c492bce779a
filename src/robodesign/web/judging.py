"""Judging uploads: an upload is unwrapped, size-checked and parsed against the registered task and module
set(s) (:meth:`Judging.prepare_submission`), judged by the checker and stored with its verdict
(:meth:`Judging.judge`); asynchronous uploads wait as pending checks that survive a restart
(:class:`Judging`, part of :class:`~robodesign.web.service.Bench`)."""
from __future__ import annotations

import json
import secrets
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

from sqlalchemy import select, update

from robodesign.collab.core import (
    CollabSolution,
    CollabTask,
    check_collab,
    is_collaborative,
    parse_collab_solution,
)
from robodesign.core.errors import InputError
from robodesign.core.jsonio import loads_json
from robodesign.formats.benchmark_id import BenchmarkID
from robodesign.formats.module_spec import ModuleSet
from robodesign.formats.solution import Solution, parse_solution
from robodesign.formats.task_spec import Task
from robodesign.judge.checker import Verdict, check
from robodesign.web import db
from robodesign.web.bench_base import BenchBase
from robodesign.web.boards import canonical_benchmark, clean_json, collab_benchmark_key
from robodesign.web.safefiles import TooLarge
from robodesign.web.site_errors import AlreadyJudged, NotFound
from robodesign.web.site_settings import Limits
from robodesign.web.tokens import check_token, hash_token


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
        out: Dict[str, Any] = {"id": self.id, "valid": self.valid, "cost": self.cost, "benchmark_id": self.benchmark_id}
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


class Judging(BenchBase):
    """Preparing, judging and storing uploaded solutions; pending (asynchronous) checks."""

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
        sol: Union[Solution, CollabSolution]
        task: Union[Task, CollabTask]
        ms: Union[ModuleSet, Dict[str, ModuleSet]]
        robot_sols: List[Solution]
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
            ctask, msets = sub.task, sub.module_set
            assert isinstance(ctask, CollabTask) and isinstance(msets, dict)  # prepare_collab made them together
            cverdict = check_collab(ctask, sol, msets)
            vj = clean_json(cverdict.to_json())
            cost, costs, valid = vj.get("totalCost"), vj.get("costs"), cverdict.valid
            all_costs = {rid: v.get("costs", {}) for rid, v in vj.get("robots", {}).items()}
            dof = sum(int(v.costs.get("numJ", 0) or 0) for v in cverdict.robots.values())
        else:
            task, ms = sub.task, sub.module_set
            assert isinstance(task, Task) and isinstance(ms, ModuleSet)  # prepare_solution made them together
            verdict: Verdict = check(task, sol, ms)
            vj = clean_json(verdict.to_json())
            cost, costs, valid = vj.get("cost"), None, verdict.valid
            all_costs, dof = vj.get("costs", {}), int(verdict.costs.get("numJ", 0) or 0)
        if not valid:
            return SubmitResult(False, row.benchmark_id, vj, cost, task_id=sol.task_id, module_set=row.module_set,
                                costs=costs)
        token = sub.token or (None if token_hash else secrets.token_urlsafe(24))
        if token:
            row.token_hash = hash_token(token)
        else:  # an async upload whose file names no token: the hash of the one its answer gave
            assert token_hash is not None
            row.token_hash = token_hash
        row.cost, row.dof = cost, dof
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
        out: Dict[str, Any]
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
            return {"status": 200, "body": (self.pending_status(pending) if pending is not None else None) or {}}
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


def check_solution_size(data: dict, sol: Solution, limits: Limits, fname: str, where: Sequence = ()) -> None:
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
