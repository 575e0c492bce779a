"""The optimization problem: what to search and how a design is scored (like OMPL's ProblemDefinition).

A :class:`Problem` is immutable and holds everything that defines a design problem:

* ``task`` — the :class:`~robodesign.formats.task_spec.Task` (workcell, goals, constraints, base placement),
* ``module_set`` — the :class:`~robodesign.formats.module_spec.ModuleSet` designs are assembled from,
* ``cost`` — the :class:`~robodesign.formats.costs.CostFunction` every design is scored with,
* ``space`` — the :class:`~robodesign.design.search_space.SearchSpace`: module-order rules and base-pose bounds.

It is built once — by the CLI (``robodesign optimize``), the experiment runner and the Python API — with
:meth:`Problem.build`, and handed to the optimizer (``Optimizer(problem, seed, **options)``), to the
evaluator (``EvaluatorSpec(problem, ...)``) and to the results store (``to_json``, ``fingerprint``).
So an optimizer that prunes with cost bounds reads the cost from ``problem.cost``: it is always the
cost the study evaluates.

A problem built from references (a task file or built-in task ID, a module-set folder or built-in
name) pickles as those references plus its cost, rules and base bounds, and reloads the task and
module set in the receiving process (once per process): evaluator workers get small messages.
"""
from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import Any, Dict, Mapping, Optional, Tuple, Union

import numpy as np

from robodesign.core.errors import InputError
from robodesign.design.search_space import BaseBounds, Candidate, SearchSpace
from robodesign.design.solve import goal_poses, position_slack
from robodesign.formats.costs import CostFunction, parse_cost
from robodesign.formats.module_spec import ModuleSet
from robodesign.formats.task_spec import Task
from robodesign.solvers.ik import fixes_full_pose

#: the search-space rules a problem may set (fields of :class:`SearchSpace` besides the module set and bounds)
RULES = ("min_dof", "max_dof", "max_links_between", "max_modules", "bases", "end_effectors", "exclude")


@dataclass(frozen=True, eq=False)
class Problem:
    """One design problem. Build it with :meth:`build`; construct it directly only to set a custom
    ``space`` (e.g. hand-made base bounds in a test)."""
    task: Task
    module_set: ModuleSet
    cost: CostFunction
    space: SearchSpace
    task_ref: Optional[str] = None      # what reloads ``task`` in another process (None: pickle the object)
    modules_ref: Optional[str] = None   # what reloads ``module_set`` in another process

    def __post_init__(self):
        if self.space.module_set is not self.module_set:
            raise ValueError("Problem: the search space must be over the problem's module set")

    @classmethod
    def build(cls, task: Union[Task, str, Path], module_set: Union[ModuleSet, str, Path],
              cost: Union[CostFunction, str] = "cyc", *, rules: Optional[Mapping[str, Any]] = None,
              base_search: bool = True, base_bounds: Optional[BaseBounds] = None) -> "Problem":
        """The problem of ``task`` (a Task, a task file or a built-in task ID) with ``module_set`` (a
        ModuleSet, a folder, a URDF file or a built-in name) and ``cost`` (a CostFunction or a descriptor
        such as ``"cyc"`` or ``"Whit2"``).

        ``rules``: search-space rules (:data:`RULES`; lists are accepted for ``bases``,
        ``end_effectors``, ``exclude``); a DoF bound not given is the task's and cost's (:func:`default_dof`). The
        base-pose bounds come from the task's base-placement
        tolerance (the only place they are derived); ``base_search=False`` fixes the base at its
        nominal pose; ``base_bounds`` overrides both.
        """
        task_ref = modules_ref = None
        if not isinstance(task, Task):
            task_ref = _ref(task)
            task = _load_task(task_ref)
        if not isinstance(module_set, ModuleSet):
            from robodesign.formats.module_io import load_module_set
            modules_ref = _ref(module_set)
            module_set = load_module_set(modules_ref)
        cf = cost if isinstance(cost, CostFunction) else parse_cost(cost, path="cost")
        if cf.is_empty:
            raise InputError("empty cost function", path="cost")
        rules = _rules(rules, module_set)
        rules.update(_dof_range(rules, task, cf, module_set))
        if base_bounds is None:
            base_bounds = _task_base_bounds(task, base_search, SearchSpace(module_set, **rules))
        space = SearchSpace(module_set, base_bounds=base_bounds, **rules, **_geometry(task))
        return cls(task=task, module_set=module_set, cost=cf, space=space, task_ref=task_ref,
                   modules_ref=modules_ref)

    # -- derived ----------------------------------------------------------------------------------------
    @property
    def base_bounds(self) -> BaseBounds:
        return self.space.base_bounds

    @property
    def cost_descriptor(self) -> str:
        """The cost as written to solution files: the compound name (``Whit2``) or the descriptor."""
        return str(self.cost)

    def base_pose(self, candidate: Candidate) -> np.ndarray:
        """The 4x4 world pose of ``candidate``'s base (its base parameters decoded by the bounds)."""
        return self.space.base_pose(candidate)

    def rules(self) -> Dict[str, Any]:
        """The search-space rules as plain data."""
        return {k: (list(v) if isinstance(v, tuple) else v) for k in RULES for v in [getattr(self.space, k)]}

    def with_(self, **changes) -> "Problem":
        """A copy with some fields replaced (``cost=...`` accepts a descriptor; ``rules=...``, ``base_search``
        and ``base_bounds`` rebuild the search space)."""
        if "cost" in changes and not isinstance(changes["cost"], CostFunction):
            changes["cost"] = parse_cost(changes["cost"], path="cost")
        space_changes = {}
        if "rules" in changes:
            new_rules = _rules(changes.pop("rules"), self.module_set)
            if "min_dof" in new_rules or "max_dof" in new_rules:  # the other bound as Problem.build sets it
                new_rules.update(_dof_range(new_rules, self.task, self.cost, self.module_set))
            space_changes.update(new_rules)
        if "base_search" in changes:
            space_changes["base_bounds"] = _task_base_bounds(
                self.task, changes.pop("base_search"),
                replace(self.space, **{k: v for k, v in space_changes.items() if k in RULES}))
        if "base_bounds" in changes:
            space_changes["base_bounds"] = changes.pop("base_bounds")
        if space_changes:
            changes["space"] = replace(self.space, **space_changes)
        return replace(self, **changes)

    def to_json(self) -> dict:
        """Plain-data description (for result files and meta data): what defines the problem."""
        bb = self.base_bounds
        return {"task": self.task.id, "task_ref": self.task_ref, "module_set": self.module_set.name,
                "modules_ref": self.modules_ref, "cost": self.cost_descriptor, "rules": self.rules(),
                "base_bounds": {"nominal": np.asarray(bb.nominal).round(12).tolist(), "lower": list(bb.lower),
                                "upper": list(bb.upper), "free": list(bb.free),
                                "tolerance": None if bb.tolerance is None else
                                [[n, list(iv), fr] for n, iv, fr in bb.tolerance.entries]}}

    def fingerprint(self) -> str:
        """A short hash of everything in the problem that changes a design's score: the task and module-set
        files (their contents, not where they are), the cost terms and the base-pose bounds. Equal problems
        give equal fingerprints in every process and on every machine."""
        d = self.to_json()
        d.pop("rules")  # the rules restrict which designs are asked, not how one is scored
        d["cost"] = [[n, w] for n, w in self.cost.terms]
        d.pop("task_ref")
        d.pop("modules_ref")  # where the files are does not change a score; what they hold does
        d["task_file"] = _file_digest(self.task.source)
        d["modules_file"] = _file_digest(self.module_set.source)
        return hashlib.sha256(json.dumps(d, sort_keys=True, default=str).encode()).hexdigest()[:16]

    def __reduce__(self):
        if self.task_ref is None or self.modules_ref is None:
            return (Problem, tuple(getattr(self, f.name) for f in fields(self)))
        rules = {k: getattr(self.space, k) for k in RULES}
        return (_restore, (self.task_ref, self.modules_ref, self.cost, rules, self.base_bounds))


def _task_base_bounds(task: Task, base_search: bool, space: Optional[SearchSpace] = None) -> BaseBounds:
    """The base-pose bounds of ``task`` (the one place they are derived): its base-placement tolerance, or
    with ``base_search=False`` its nominal base pose alone. A task without a basePlacement constraint allows
    any base pose (as the reference judges it): the bounds are then the region around its goals where a
    design of ``space`` can stand (:func:`free_base_bounds`)."""
    if task.base_placement is None and base_search and space is not None:
        goals = _goal_points(task)
        if goals:
            return free_base_bounds(goals, space.max_reach())
    bb = BaseBounds.from_tolerance(task.base_placement)
    return bb if base_search else BaseBounds(nominal=bb.nominal)


def free_base_bounds(goals, reach: float) -> BaseBounds:
    """Bounds for a base that the task leaves free: world x, y, z (offsets from the identity) in the box of
    the points within ``reach`` + tolerance of every goal (``goals``: (x, y, z, position tolerance) rows;
    ``reach``: :meth:`SearchSpace.max_reach`, an upper bound of any design's base-to-TCP distance, so no
    base outside the box reaches every goal), any yaw. When no point is within reach of every goal (no
    design of the set can do the task), the box of the goals themselves: the reach stage then says how far
    each design falls short."""
    G = np.asarray(goals, dtype=float).reshape(-1, 4)
    r = reach if np.isfinite(reach) else 10.0
    lo = np.max(G[:, :3] - r - G[:, 3:], axis=0)
    hi = np.min(G[:, :3] + r + G[:, 3:], axis=0)
    if np.any(lo > hi):
        lo, hi = G[:, :3].min(axis=0), G[:, :3].max(axis=0)
    lo = [float(v) for v in lo] + [-math.pi]
    hi = [float(v) for v in hi] + [math.pi]
    return BaseBounds(nominal=np.eye(4), lower=(lo[0], lo[1], lo[2], lo[3]), upper=(hi[0], hi[1], hi[2], hi[3]),
                      tolerance=None)


def _goal_points(task: Task) -> Tuple[Tuple[float, float, float, float], ...]:
    """The world positions of the task's pose goals (every pose of a follow goal) with their position
    tolerance, as the reach stage tests them."""
    out = []
    for g in task.goals:
        for pose in goal_poses(g):
            p = np.asarray(pose.nominal, dtype=float)[:3, 3]
            out.append((float(p[0]), float(p[1]), float(p[2]), float(min(position_slack(pose), 1e3))))
    return tuple(out)


def _geometry(task: Task) -> Dict[str, Any]:
    """The task geometry a search space samples base poses with: goal positions and static obstacles."""
    obstacles = tuple(geo for o in task.obstacles if not o.moving for geo in o.collision)
    return {"goals": _goal_points(task), "obstacles": obstacles, "goal_rank": 6 if _fixes_a_full_pose(task) else 0}


def _fixes_a_full_pose(task: Task) -> bool:
    """Whether some goal of ``task`` fixes the tool's position and orientation (:func:`fixes_full_pose`)."""
    return any(fixes_full_pose(p) for g in task.goals for p in goal_poses(g))


def _rules(rules: Optional[Mapping[str, Any]], ms: ModuleSet) -> Dict[str, Any]:
    """Search-space keyword arguments from plain-data rules (unknown rules and modules are input errors)."""
    out: Dict[str, Any] = {}
    for k, v in (rules or {}).items():
        if k not in RULES:
            raise InputError(f"unknown search-space rule {k!r} (known: {', '.join(RULES)})", path=["rules", k])
        if k in ("bases", "end_effectors", "exclude"):
            if v is None:
                if k == "exclude":
                    v = ()
            else:
                v = tuple(str(x) for x in ([v] if isinstance(v, (str, int)) else v))
                kind = {"bases": "base", "end_effectors": "eef"}.get(k)
                for j, mid in enumerate(v):
                    if mid not in ms:
                        raise InputError(f"module {mid!r} is not in module set {ms.name!r}", path=["rules", k, j])
                    if kind and ms[mid].kind != kind:
                        raise InputError(f"module {mid!r} is a {ms[mid].kind} module, not a {kind} module",
                                         path=["rules", k, j])
        elif v is None:
            continue
        out[k] = v
    lo, hi = out.get("min_dof"), out.get("max_dof")
    if lo is not None and hi is not None and lo > hi:
        raise InputError(f"min_dof ({lo}) is larger than max_dof ({hi})", path="rules")
    return out


#: the degrees of freedom of the designs searched when the rules do not say (:func:`default_dof`)
DEFAULT_DOF = 6
#: ... and for a task with a goal that fixes position and orientation among static obstacles
REDUNDANT_DOF = 7
#: cost terms that charge the design itself (its joints, its mass): with them a seventh joint is a trade-off
DESIGN_COST_TERMS = frozenset({"numJ", "mass"})


def default_dof(task: Task, cost: Optional[CostFunction] = None) -> Tuple[int, int]:
    """The (min, max) number of joints of the designs of a search when the rules do not say.

    6 joints, except for a task with a goal that fixes the tool's position and orientation
    (:func:`robodesign.solvers.ik.fixes_full_pose`) and static obstacles: then 7 (:data:`REDUNDANT_DOF`), or
    6 to 7 when ``cost`` charges joints or mass (:data:`DESIGN_COST_TERMS`, e.g. Whit2), so the search weighs
    the seventh joint against its price. (:meth:`Problem.build` keeps 6 for a module set that builds no
    7-joint order.)

    Why: a 6-joint arm holds such a pose in at most 16 configurations; among obstacles few of them are
    collision-free, and the free space often does not connect those of consecutive goals (the plan stage
    fails for design after design). A seventh joint gives every pose a curve of configurations (the
    self-motion), a way around. Measured on the published families (docs/benchmarks.md, "Seven joints where
    the pose is fixed among obstacles")."""
    if not (_fixes_a_full_pose(task) and any(not o.moving for o in task.obstacles)):
        return DEFAULT_DOF, DEFAULT_DOF
    charged = cost is not None and any(n in DESIGN_COST_TERMS and w > 0 for n, w in cost.terms)
    return (DEFAULT_DOF if charged else REDUNDANT_DOF), REDUNDANT_DOF


def _dof_range(rules: Mapping[str, Any], task: Task, cost: Optional[CostFunction],
               module_set: ModuleSet) -> Dict[str, int]:
    """``min_dof`` and ``max_dof`` of ``rules``, a missing one from :func:`default_dof` (kept within the
    given one: ``max_dof=5`` alone searches 5 joints, ``min_dof=8`` alone 8). A module set that builds no
    7-joint order under the other rules (IMPROV: none at all) keeps the 6 joints."""
    lo, hi = rules.get("min_dof"), rules.get("max_dof")
    d_lo, d_hi = default_dof(task, cost)
    if d_hi > DEFAULT_DOF and (lo is None or hi is None):
        others = {k: v for k, v in rules.items() if k not in ("min_dof", "max_dof")}
        if SearchSpace(module_set, **others, min_dof=d_hi, max_dof=d_hi).count_orders() == 0:
            d_lo = d_hi = DEFAULT_DOF
    if lo is None:
        return {"min_dof": d_lo, "max_dof": d_hi} if hi is None else {"min_dof": min(d_lo, int(hi)), "max_dof": int(hi)}
    return {"min_dof": int(lo), "max_dof": max(d_hi, int(lo)) if hi is None else int(hi)}


_DIGESTS: Dict[Tuple[str, int], str] = {}


def _file_digest(path: Optional[str]) -> Optional[str]:
    """SHA-256 of a file's bytes (cached per file version); None without a readable file."""
    if not path:
        return None
    try:
        p = Path(path)
        key = (str(p.resolve()), p.stat().st_mtime_ns)
    except OSError:
        return None
    if key not in _DIGESTS:
        _DIGESTS[key] = hashlib.sha256(p.read_bytes()).hexdigest()
    return _DIGESTS[key]


def _ref(name_or_path) -> str:
    """An existing file or folder as an absolute path (valid in any worker's working folder); else the
    name as given (a built-in task ID or module set)."""
    p = Path(name_or_path)
    return str(p.resolve()) if p.exists() else str(name_or_path)


_TASKS: Dict[Tuple[str, int], Task] = {}


def _load_task(ref: str) -> Task:
    """load_task, once per process and file version (module sets are cached by load_module_set)."""
    from robodesign.formats.task_io import load_task, resolve_task_path
    f = resolve_task_path(ref)
    key = (str(Path(f).resolve()), Path(f).stat().st_mtime_ns)
    task = _TASKS.get(key)
    if task is None:
        task = _TASKS[key] = load_task(ref)
    return task


def _restore(task_ref: str, modules_ref: str, cost: CostFunction, rules: dict, base_bounds: BaseBounds) -> Problem:
    from robodesign.formats.module_io import load_module_set
    ms = load_module_set(modules_ref)
    task = _load_task(task_ref)
    return Problem(task=task, module_set=ms, cost=cost,
                   space=SearchSpace(ms, base_bounds=base_bounds, **rules, **_geometry(task)), task_ref=task_ref,
                   modules_ref=modules_ref)
