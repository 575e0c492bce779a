"""CoBRA solutions: the robot (module set, assembly, base pose) and its trajectory.

A :class:`Solution` is plain data; :func:`load_solution` / :func:`Solution.to_json` read and write
the CoBRA solution format (docs/formats.md). Missing ``dq``/``ddq`` are derived with
``numpy.gradient`` along t, like the reference.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Optional, Tuple, Union

import numpy as np

from robodesign.core.errors import InputError, describe_value
from robodesign.core.jsonio import check_finite, load_json, write_json
from robodesign.core.schema import validate
from robodesign.core.spatial import parse_pose, pose_to_list
from robodesign.core.trajectory import Trajectory
from robodesign.formats.assembly import Assembly
from robodesign.formats.module_spec import ModuleSet

SolutionTrajectory = Trajectory  # the old name, kept for code written against it


@dataclass(frozen=True, eq=False)
class Solution:
    task_id: str
    cost_function: str
    module_set: str
    module_order: Tuple[str, ...]
    base_pose: np.ndarray
    trajectory: Trajectory
    module_connection: Optional[Tuple[Tuple[int, str, int, str], ...]] = None
    base_connection: Optional[Tuple[int, str]] = None
    version: str = "2023"
    author: Tuple[str, ...] = ()
    email: Tuple[str, ...] = ()
    affiliation: Tuple[str, ...] = ()
    tags: Tuple[str, ...] = ()
    publication: str = ""
    date: str = ""
    computation_time: float = -1.0
    processor_name: str = ""
    notes: str = ""
    cost: Optional[float] = None  # as written in the file; never trusted, always recomputed
    source: Optional[str] = None

    def assembly(self, ms: ModuleSet) -> Assembly:
        if self.module_connection is None:
            return Assembly.from_order(ms, self.module_order)
        return Assembly.from_graph(ms, self.module_order, self.module_connection, self.base_connection)

    def with_(self, **kw) -> "Solution":
        return replace(self, **kw)

    def to_json(self) -> dict:
        tr = self.trajectory
        out = {
            "taskID": self.task_id, "version": self.version, "author": list(self.author), "email": list(self.email),
            "affiliation": list(self.affiliation), "tags": list(self.tags), "publication": self.publication,
            "date": self.date, "computationTime": self.computation_time, "processorName": self.processor_name,
            "notes": self.notes, "costFunction": self.cost_function, "moduleSet": self.module_set,
            "moduleOrder": list(self.module_order), "basePose": [pose_to_list(self.base_pose)],
            "trajectory": {"t": tr.t.tolist(), "q": tr.q.tolist(), "dq": tr.dq.tolist(), "ddq": tr.ddq.tolist(),
                           "goal2time": {k: float(v) for k, v in tr.goal2time.items()}},
        }
        for key in ("publication", "date", "processorName", "notes"):
            if out[key] == "":
                del out[key]
        if self.cost is not None:
            out["cost"] = float(self.cost)
        if self.module_connection is not None:
            out["moduleConnection"] = [list(c) for c in self.module_connection]
            if self.base_connection is not None:
                out["baseConnection"] = [[self.base_connection[0], self.base_connection[1], 0]]
        return out

    def write(self, path: Union[str, Path]) -> Path:
        return write_json(path, self.to_json())


def load_solution(path: Union[str, Path]) -> Solution:
    p = Path(path)
    data = load_json(p, display_name=p.name)
    return parse_solution(data, p.name, source=str(p))


_HEADER_KEYS = {"taskid": "taskID", "version": "version", "author": "author", "email": "email",
                "affiliation": "affiliation", "tags": "tags", "publication": "publication", "date": "date",
                "computationtime": "computationTime", "processorname": "processorName", "notes": "notes"}


_OPTIONAL_HEADER = ("version", "author", "email", "affiliation", "tags", "publication", "date", "computationTime",
                    "processorName", "notes")
_HEADER_LISTS = ("author", "email", "affiliation", "tags")


def parse_solution(data, fname: str, source: Optional[str] = None) -> Solution:
    if not isinstance(data, dict):
        raise InputError("a solution file must hold a JSON object", file=fname)
    # header fields are matched case-insensitively (as the reference does)
    data = {(_HEADER_KEYS.get(k.lower(), k)): v for k, v in data.items()}
    # null for an optional header string (notes, publication, ...) means absent; null list entries are dropped
    data = {k: ([x for x in v if x is not None] if k in _HEADER_LISTS and isinstance(v, list) else v)
            for k, v in data.items() if not (v is None and k in _OPTIONAL_HEADER)}
    validate(data, "solution", fname)
    tr_raw = data["trajectory"]
    tp = ["trajectory"]
    q = _matrix(tr_raw.get("q"), fname, tp + ["q"])
    n, dof = q.shape
    t_raw = tr_raw.get("t")
    if isinstance(t_raw, (int, float)) and not isinstance(t_raw, bool):
        dt = check_finite(t_raw, fname, tp + ["t"])
        if dt <= 0:
            raise InputError(f"time step must be positive, got {dt}", file=fname, path=tp + ["t"])
        t = np.arange(n) * dt
    else:
        if not isinstance(t_raw, list):
            raise InputError(f"expected a list of times or a time step, got {describe_value(t_raw)}", file=fname,
                             path=tp + ["t"])
        t = np.array([check_finite(x, fname, tp + ["t", k]) for k, x in enumerate(t_raw)])
        if len(t) != n:
            raise InputError(f"{len(t)} time stamps but {n} joint samples", file=fname, path=tp + ["t"])
    if n >= 2 and np.any(np.diff(t) <= 0):
        k = int(np.argmax(np.diff(t) <= 0))
        raise InputError(f"time stamps must be strictly increasing (t[{k}]={t[k]}, t[{k+1}]={t[k+1]})", file=fname,
                         path=tp + ["t", k + 1])
    if "pose" in tr_raw:
        raise InputError("pose-based trajectories are not supported; give joint values 'q'", file=fname,
                         path=tp + ["pose"])
    grads = {}
    for key in ("dq", "ddq"):
        if key in tr_raw and tr_raw[key] is not None:
            a = _matrix(tr_raw[key], fname, tp + [key])
            if a.shape != q.shape:
                raise InputError(f"shape {a.shape} differs from q's {q.shape}", file=fname, path=tp + [key])
            grads[key] = a
    if "dq" not in grads:
        grads["dq"] = np.gradient(q, t, axis=0) if n > 1 else np.zeros_like(q)
    if "ddq" not in grads:
        grads["ddq"] = np.gradient(grads["dq"], t, axis=0) if n > 1 else np.zeros_like(q)
    g2t = {}
    for gid, tv in (tr_raw.get("goal2time") or {}).items():
        v = check_finite(tv, fname, tp + ["goal2time", gid])
        if n and not (t[0] - 1e-12 <= v <= t[-1] + 1e-12):
            raise InputError(f"goal time {v} is outside the trajectory [{t[0]}, {t[-1]}]", file=fname,
                             path=tp + ["goal2time", gid])
        g2t[str(gid)] = v
    traj = Trajectory(t=t, q=q, dq=grads["dq"], ddq=grads["ddq"], goal2time=g2t)
    bp = data.get("basePose", [np.eye(4).tolist()])
    if isinstance(bp, list) and bp and isinstance(bp[0], list) and bp and isinstance(bp[0][0], list):
        base_pose = parse_pose(bp[0], fname, ["basePose", 0])
    else:
        base_pose = parse_pose(bp, fname, ["basePose"])
    mc = data.get("moduleConnection")
    module_connection = None
    base_connection = None
    if mc:
        module_connection = tuple((int(c[0]), str(c[1]), int(c[2]), str(c[3])) for c in mc)
        bc = data.get("baseConnection")
        if bc:
            if len(bc) > 1:
                raise InputError("only one base connection is supported", file=fname, path=["baseConnection"])
            base_connection = (int(bc[0][0]), str(bc[0][1]))
    order = tuple(str(x) for x in data.get("moduleOrder", []))
    return Solution(
        task_id=str(data["taskID"]), cost_function=str(data["costFunction"]), module_set=str(data.get("moduleSet", "")),
        module_order=order, base_pose=base_pose, trajectory=traj, module_connection=module_connection,
        base_connection=base_connection, version=str(data.get("version", "2023")),
        author=tuple(_as_list(data.get("author"))), email=tuple(_as_list(data.get("email"))),
        affiliation=tuple(_as_list(data.get("affiliation"))), tags=tuple(_as_list(data.get("tags"))),
        publication=str(data.get("publication", "")), date=str(data.get("date", "")),
        computation_time=float(data.get("computationTime", -1) or -1), processor_name=str(data.get("processorName", "")),
        notes=str(data.get("notes", "")), cost=data.get("cost"), source=source)


def _as_list(v):
    if v is None:
        return []
    return v if isinstance(v, list) else [v]


def _matrix(v, fname, path) -> np.ndarray:
    if not isinstance(v, list) or not v:
        raise InputError(f"expected a non-empty list of joint vectors, got {describe_value(v)}", file=fname, path=path)
    rows = []
    dof = None
    for k, row in enumerate(v):
        if not isinstance(row, list):
            row = [row]
        if dof is None:
            dof = len(row)
        elif len(row) != dof:
            raise InputError(f"sample {k} has {len(row)} values, sample 0 has {dof}", file=fname, path=list(path) + [k])
        rows.append([check_finite(x, fname, list(path) + [k, j]) for j, x in enumerate(row)])
    return np.array(rows, dtype=float)
