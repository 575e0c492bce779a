"""Collaborative tasks and solutions: several robots in one cell (benchmark IDs ``[R1,R2]:[C1,C2]:C-Θ``).

A collaborative task is a CoBRA task with a top-level ``"robots"`` list; each goal may name the robot
that must achieve it (``"robot": "left"``), otherwise any robot may. A collaborative solution holds one
CoBRA solution per robot on a common time base. The JSON forms and the exact semantics are in
docs/collaborative.md; in short:

* every robot is judged by the single-robot checker on the task restricted to its goals (the goals
  assigned to it plus the "any robot" goals its ``goal2time`` claims) with its own base placement;
* every goal is achieved by the robot it is assigned to, an "any robot" goal by at least one robot;
* no two robots come closer than the task's ``collisionFree`` safety margin, certified between samples
  (both robots move linearly in joint space between the common samples);
* each robot has its own cost; the verdict reports the tuple in the order of the task's robots.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from robodesign.core.errors import InputError
from robodesign.core.jsonio import load_json, write_json
from robodesign.core.trajectory import Trajectory
from robodesign.formats.costs import CostFunction, parse_cost
from robodesign.formats.module_spec import ModuleSet
from robodesign.formats.solution import Solution, parse_solution
from robodesign.formats.task_io import parse_task, resolve_task_path
from robodesign.formats.task_spec import CollisionFree, GoalsInOrder, Task
from robodesign.judge.checker import CheckSettings, Verdict, Violation, check
from robodesign.model.cell import build_robot, resolve_module_set

if TYPE_CHECKING:  # for annotations only: solve_collab imports the solve pipeline when it runs
    from robodesign.design.stages import SolveResult
    from robodesign.model.robot import Robot

ANY = None  # goal assignment: any robot


@dataclass(frozen=True, eq=False)
class CollabTask:
    """The shared cell (``task``: obstacles, every goal, task-level constraints) plus one view per robot
    (``robot_tasks[id]``: the same task with the robot's own base placement)."""
    task: Task
    robot_ids: Tuple[str, ...]
    robot_names: Dict[str, str]
    robot_tasks: Dict[str, Task]
    assignment: Dict[str, Optional[str]]  # goal ID → robot ID, or None for "any robot"

    @property
    def id(self) -> str:
        return self.task.id

    def goals_of(self, rid: str) -> Tuple[str, ...]:
        """Goal IDs assigned to robot ``rid`` (not the "any robot" goals)."""
        return tuple(g.id for g in self.task.goals if self.assignment[g.id] == rid)

    @property
    def any_goals(self) -> Tuple[str, ...]:
        return tuple(g.id for g in self.task.goals if self.assignment[g.id] is ANY)

    def task_for(self, rid: str, goal_ids) -> Task:
        """Robot ``rid``'s view restricted to the goals ``goal_ids`` (file order kept; an order constraint
        keeps the listed goals among them)."""
        keep = set(goal_ids)
        t = self.robot_tasks[rid]
        cons = tuple(replace(c, order=tuple(g for g in c.order if g in keep)) if isinstance(c, GoalsInOrder) else c
                     for c in t.constraints)
        return replace(t, goals=tuple(g for g in t.goals if g.id in keep), constraints=cons)

    @property
    def safety_margin(self) -> Optional[float]:
        """Robot–robot distance that counts as a collision (None: robots may touch, no collisionFree)."""
        cf = [c.safety_margin for c in self.task.constraints if isinstance(c, CollisionFree)]
        return max(cf) if cf else None


def is_collaborative(data) -> bool:
    return isinstance(data, dict) and isinstance(data.get("robots"), list)


def load_collab_task(name_or_path: Union[str, Path]) -> CollabTask:
    f = resolve_task_path(name_or_path)
    return parse_collab_task(load_json(f, display_name=f.name), f)


def shared_cell_json(data: dict) -> dict:
    """A collaborative task file without what makes it collaborative (``robots``, the goals' ``robot``): the
    shared cell as a single-robot task file (a copy; ``data`` is not changed)."""
    base = copy.deepcopy(data)
    base.pop("robots", None)
    goals = base.get("goals")
    for g in goals if isinstance(goals, list) else []:
        if isinstance(g, dict):
            g.pop("robot", None)
    return base


def parse_collab_task(data, file: Path) -> CollabTask:
    fname = Path(file).name
    if not is_collaborative(data):
        raise InputError("a collaborative task needs a 'robots' list", file=fname, path=["robots"])
    robots = data["robots"]
    if not robots:
        raise InputError("needs at least one robot", file=fname, path=["robots"])
    base = shared_cell_json(data)
    ids: List[str] = []
    names: Dict[str, str] = {}
    placements: Dict[str, Optional[dict]] = {}
    for i, r in enumerate(robots):
        if not isinstance(r, dict) or not isinstance(r.get("ID"), (str, int)) or isinstance(r.get("ID"), bool):
            raise InputError("each robot needs an 'ID' (string)", file=fname, path=["robots", i, "ID"])
        rid = str(r["ID"])
        if rid in ids:
            raise InputError(f"duplicate robot ID {rid!r}", file=fname, path=["robots", i, "ID"])
        ids.append(rid)
        names[rid] = str(r.get("name") or rid)
        bp = r.get("basePlacement")
        if bp is not None and not isinstance(bp, dict):
            raise InputError("basePlacement must be a tolerated pose object", file=fname,
                             path=["robots", i, "basePlacement"])
        placements[rid] = bp
    assignment: Dict[str, Optional[str]] = {}
    goals = data.get("goals")
    for i, g in enumerate(goals if isinstance(goals, list) else []):
        if isinstance(g, dict) and "robot" in g:
            rid = g["robot"]
            if rid is not None and rid != "any" and str(rid) not in ids:
                raise InputError(f"unknown robot {rid!r} (robots: {', '.join(ids)})", file=fname,
                                 path=["goals", i, "robot"])
            assignment[str(g.get("ID"))] = None if rid in (None, "any") else str(rid)
    task = parse_task(base, Path(file))
    for g in task.goals:
        assignment.setdefault(g.id, ANY)
    robot_tasks = {}
    for k, rid in enumerate(ids):
        if placements[rid] is None:
            robot_tasks[rid] = task
            continue
        d = copy.deepcopy(base)
        cons = [c for c in d.get("constraints", []) if not (isinstance(c, dict) and c.get("type") == "basePlacement")]
        cons.append({"type": "basePlacement", "pose": placements[rid]})
        if "constraints" not in d:  # keep the default constraint set, plus the base placement
            from robodesign.formats.task_spec import default_constraints
            t = parse_task({**d, "constraints": [{"type": "basePlacement", "pose": placements[rid]}]}, Path(file))
            robot_tasks[rid] = replace(task, constraints=tuple(default_constraints()) + t.constraints)
            continue
        d["constraints"] = cons
        try:
            robot_tasks[rid] = parse_task(d, Path(file))
        except InputError as e:  # name the robot's field, not the synthesized constraint
            raise InputError(e.reason, file=fname, path=f"robots[{k}].basePlacement") from None
    for g in task.goals:  # a returnTo must stay with the robot of its target
        target = getattr(g, "return_to", None)
        if target is not None and assignment[g.id] != assignment.get(target):
            raise InputError(f"returnTo goal {g.id!r} and its target {target!r} are assigned to different robots",
                             file=fname, path=["goals"])
    return CollabTask(task, tuple(ids), names, robot_tasks, assignment)


# ---------------------------------------------------------------------------------------------------------
# solutions
# ---------------------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class CollabSolution:
    task_id: str
    robots: Tuple[Tuple[str, Solution], ...]  # (robot ID, its solution), all on one time base
    computation_time: float = -1.0
    notes: str = ""
    source: Optional[str] = None

    def solution(self, rid: str) -> Solution:
        for r, s in self.robots:
            if r == rid:
                return s
        raise KeyError(rid)

    @property
    def cost_functions(self) -> Tuple[str, ...]:
        return tuple(s.cost_function for _, s in self.robots)

    def benchmark_id(self, order: Optional[Sequence[str]] = None) -> str:
        """``[M-set1,M-set2]:[C1,C2]:task`` (robots in ``order``, default the solution's), canonical form."""
        from robodesign.formats.benchmark_id import BenchmarkID, RobotRef, RobotSpec
        sols = [self.solution(r) for r in (order or [r for r, _ in self.robots])]
        costs = tuple(parse_cost(s.cost_function) for s in sols)
        bid = BenchmarkID(RobotSpec(tuple(RobotRef(s.module_set, "M-") for s in sols), True), costs[0], self.task_id,
                          costs)
        return str(BenchmarkID.parse(str(bid)))  # checks the names and the task ID against the grammar

    def to_json(self) -> dict:
        robots: List[dict] = []
        out = {"taskID": self.task_id, "collaborative": True, "computationTime": self.computation_time,
               "robots": robots}
        if self.notes:
            out["notes"] = self.notes
        for rid, s in self.robots:
            d = s.to_json()
            d.pop("taskID", None)
            robots.append({"ID": rid, **d})
        return out

    def write(self, path) -> Path:
        return write_json(path, self.to_json())


SOLUTION_KEYS = frozenset({"taskID", "taskId", "collaborative", "computationTime", "notes", "robots"})  # top level


def load_collab_solution(path) -> CollabSolution:
    p = Path(path)
    return parse_collab_solution(load_json(p, display_name=p.name), p.name, source=str(p))


def parse_collab_solution(data, fname: str, source: Optional[str] = None) -> CollabSolution:
    if not is_collaborative(data):
        raise InputError("a collaborative solution needs a 'robots' list", file=fname, path=["robots"])
    unknown = sorted(set(data) - SOLUTION_KEYS)
    if unknown:  # as the single-robot schema: a misspelt key is an error, not silently dropped
        raise InputError(f"unknown key(s): {', '.join(repr(k[:100]) for k in unknown[:5])} (a collaborative solution "
                         f"has {', '.join(sorted(SOLUTION_KEYS - {'taskId'}))}; the rest belongs to each robot)",
                         file=fname, path=[unknown[0][:100]])
    if data.get("collaborative", True) is not True:
        raise InputError("expected true (a solution with a 'robots' list is collaborative)", file=fname,
                         path=["collaborative"])
    for key, types, what in (("computationTime", (int, float), "a number"), ("notes", (str,), "a string")):
        v = data.get(key)
        if v is not None and (not isinstance(v, types) or isinstance(v, bool)):
            raise InputError(f"expected {what}", file=fname, path=[key])
    tid = data.get("taskID", data.get("taskId"))
    if not isinstance(tid, str):
        raise InputError("expected the task ID (a string)", file=fname, path=["taskID"])
    out = []
    seen = set()
    for i, r in enumerate(data["robots"]):
        if not isinstance(r, dict) or not isinstance(r.get("ID"), str):
            raise InputError("each robot needs an 'ID' (string)", file=fname, path=["robots", i, "ID"])
        if r["ID"] in seen:
            raise InputError(f"duplicate robot ID {r['ID']!r}", file=fname, path=["robots", i, "ID"])
        seen.add(r["ID"])
        body = {k: v for k, v in r.items() if k != "ID"}
        own = body.get("taskID", body.get("taskId", tid))
        if own != tid:
            raise InputError(f"robot {r['ID'][:100]!r} names task {str(own)[:200]!r}, the solution {tid[:200]!r}",
                             file=fname, path=["robots", i, "taskID" if "taskID" in body else "taskId"])
        body.pop("taskId", None)
        body["taskID"] = tid
        try:
            sol = parse_solution(body, fname, source=source)
        except InputError as e:
            inner = f".{e.json_path}" if e.json_path else ""
            raise InputError(e.reason, file=fname, path=f"robots[{i}]{inner}") from None
        out.append((r["ID"], sol))
    if not out:
        raise InputError("needs at least one robot", file=fname, path=["robots"])
    t0 = out[0][1].trajectory.t
    for i, (rid, s) in enumerate(out[1:], start=1):
        t = s.trajectory.t
        if len(t) != len(t0) or np.max(np.abs(t - t0)) > 1e-9:
            raise InputError(f"robot {rid!r} is not on the common time base of robot {out[0][0]!r} "
                             "(every robot's trajectory.t must be the same)", file=fname,
                             path=["robots", i, "trajectory", "t"])
    ct = data.get("computationTime", -1.0)
    return CollabSolution(tid, tuple(out), float(ct) if isinstance(ct, (int, float)) and not isinstance(ct, bool)
                          else -1.0, str(data.get("notes") or ""), source)


# ---------------------------------------------------------------------------------------------------------
# the judge
# ---------------------------------------------------------------------------------------------------------
@dataclass
class CollabVerdict:
    valid: bool
    violations: List[Tuple[Optional[str], Violation]]  # (robot ID or None for the cell, violation)
    robots: Dict[str, Verdict]
    costs: Tuple[Optional[float], ...]  # one per robot, in the task's robot order
    cost_functions: Tuple[str, ...]
    goal_robot: Dict[str, Optional[str]] = field(default_factory=dict)  # goal → robot that achieved it
    benchmark_id: str = ""  # [M-set1,M-set2]:[C1,C2]:task (empty when the solution cannot name one)

    @property
    def total_cost(self) -> Optional[float]:
        """Sum of the robots' costs (the leaderboard's primary key; docs/collaborative.md)."""
        known = [c for c in self.costs if c is not None]
        return None if len(known) < len(self.costs) else float(sum(known))

    def to_json(self) -> dict:
        return {"valid": self.valid, "collaborative": True,
                "violations": [{"robot": r, **v.to_json()} for r, v in self.violations],
                "costs": [None if c is None else float(c) for c in self.costs], "totalCost": self.total_cost,
                "costFunctions": list(self.cost_functions), "goals": self.goal_robot, "benchmarkID": self.benchmark_id,
                "robots": {rid: v.to_json() for rid, v in self.robots.items()}}


def robot_module_set(module_sets, rid: str):
    """Robot ``rid``'s entry of ``module_sets`` (one set for all, a dict by robot ID, or None)."""
    if module_sets is None or isinstance(module_sets, (str, Path, ModuleSet)):
        return module_sets
    return module_sets.get(rid)


def check_collab(ctask: CollabTask, csol: CollabSolution, module_sets=None,
                 settings: Optional[CheckSettings] = None) -> CollabVerdict:
    """Judge a collaborative solution. ``module_sets``: one module set (name, path or ModuleSet) for
    every robot, a dict robot ID → module set, or None (each robot's ``moduleSet``)."""
    from robodesign.model.pair_sweep import RobotPairSweep
    viol: List[Tuple[Optional[str], Violation]] = []
    if csol.task_id != ctask.id:
        viol.append((None, Violation("taskID", f"solution is for task {csol.task_id!r}, not {ctask.id!r}")))
    sol_ids = [r for r, _ in csol.robots]
    for rid in sol_ids:
        if rid not in ctask.robot_ids:
            viol.append((rid, Violation("robots", f"the task has no robot {rid!r} (robots: {', '.join(ctask.robot_ids)})")))
    for rid in ctask.robot_ids:
        if rid not in sol_ids:
            viol.append((rid, Violation("robots", f"robot {rid!r} has no trajectory in the solution")))
    if viol:
        return CollabVerdict(False, viol, {}, tuple(None for _ in ctask.robot_ids), csol.cost_functions)
    # who claims which goal
    goal_robot: Dict[str, Optional[str]] = {}
    claimed: Dict[str, List[str]] = {}
    for rid, s in csol.robots:
        for gid in s.trajectory.goal2time:
            claimed.setdefault(gid, []).append(rid)
    views: Dict[str, List[str]] = {rid: [] for rid in ctask.robot_ids}
    for g in ctask.task.goals:
        owner = ctask.assignment[g.id]
        by = claimed.get(g.id, [])
        if owner is not None:
            for other in by:
                if other != owner:
                    viol.append((other, Violation("goalAssignment", f"goal {g.id} is assigned to robot {owner!r}")))
            views[owner].append(g.id)
            goal_robot[g.id] = owner
        else:
            for rid in by:
                views[rid].append(g.id)
            goal_robot[g.id] = by[0] if by else None
    verdicts: Dict[str, Verdict] = {}
    robots = {}
    for rid in ctask.robot_ids:
        s = csol.solution(rid)
        t_r = ctask.task_for(rid, views[rid])
        v = check(t_r, s, robot_module_set(module_sets, rid), settings)
        verdicts[rid] = v
        viol += [(rid, x) for x in v.violations]
        if not any(x.constraint == "validAssembly" for x in v.violations):
            ms = resolve_module_set(s, robot_module_set(module_sets, rid))
            robots[rid] = build_robot(t_r, ms, s.assembly(ms), s.base_pose)
    any_missing = [g for g in ctask.any_goals if goal_robot.get(g) is None]
    for gid in any_missing:
        viol.append((None, Violation("allGoalsFulfilled", f"goal {gid} (any robot) is achieved by no robot")))
    margin = ctask.safety_margin
    if margin is not None:
        t = csol.robots[0][1].trajectory.t
        ids = [rid for rid in ctask.robot_ids if rid in robots]
        for a in range(len(ids)):
            for b in range(a + 1, len(ids)):
                ra, rb = ids[a], ids[b]
                qa, qb = csol.solution(ra).trajectory.q, csol.solution(rb).trajectory.q
                if qa.shape[1] != robots[ra].dof or qb.shape[1] != robots[rb].dof:
                    continue  # reported by the robot's own check
                sweep = RobotPairSweep(robots[ra], robots[rb], margin=margin, names=(ra, rb))
                events = sweep.check(np.hstack([qa, qb]), first_only=False)
                for e in events[:20]:
                    k = e.sample
                    tt = float(t[k] + e.s * (t[min(k + 1, len(t) - 1)] - t[k]))
                    between = f" between samples {k} and {k + 1}" if e.s > 0 else f" at sample {k}"
                    viol.append((None, Violation("robotCollisionFree", f"robot–robot collision {e.first} ↔ "
                                                 f"{e.second}{between} (distance {e.distance:.4g} m, margin {margin:.3g})",
                                                 sample=k, time=tt, value=e.distance)))
    costs = tuple(verdicts[rid].cost for rid in ctask.robot_ids)
    try:
        bid = csol.benchmark_id(ctask.robot_ids)
    except InputError:  # e.g. a module set name the ID grammar does not allow: the verdict stands without it
        bid = ""
    return CollabVerdict(not viol, viol, verdicts, costs, tuple(csol.solution(r).cost_function for r in ctask.robot_ids),
                         goal_robot, bid)


# ---------------------------------------------------------------------------------------------------------
# solving: prioritized planning
# ---------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class RobotSetup:
    """One robot of a collaborative solve: its module set, module order and base pose (None: the nominal
    pose of its base placement)."""
    id: str
    module_set: ModuleSet
    order: Tuple[str, ...]
    base_pose: Optional[np.ndarray] = None


@dataclass
class CollabSolveResult:
    solution: Optional[CollabSolution]
    verdict: Optional[CollabVerdict]
    priority: Tuple[str, ...]  # the order in which the robots were planned
    results: Dict[str, SolveResult]  # robot ID → its result (of the last priority order tried)
    assignment: Dict[str, str]  # goal → robot (the "any robot" goals resolved)
    message: str = ""

    @property
    def feasible(self) -> bool:
        return self.verdict is not None and self.verdict.valid


def assign_goals(ctask: CollabTask, setups: Sequence[RobotSetup]) -> Dict[str, str]:
    """Every goal's robot: the assigned one, or for an "any robot" goal the robot whose base is nearest
    to the goal's nominal TCP position (goals without a pose go to the first robot)."""
    from robodesign.design.solve import goal_poses
    bases = {s.id: _base_of(ctask, s) for s in setups}
    out = {}
    for g in ctask.task.goals:
        owner = ctask.assignment[g.id]
        if owner is None:
            poses = goal_poses(g)
            if poses:
                p = poses[0].nominal[:3, 3]
                owner = min(bases, key=lambda r: float(np.linalg.norm(bases[r][:3, 3] - p)))
            else:
                owner = setups[0].id
        out[g.id] = owner
    return out


def _base_of(ctask: CollabTask, s: RobotSetup) -> np.ndarray:
    return np.asarray(s.base_pose, float) if s.base_pose is not None else ctask.robot_tasks[s.id].nominal_base_pose


def _pad(sol: Solution, t: np.ndarray) -> Solution:
    """Hold the last configuration until the common end time (``t`` extends the solution's own times)."""
    tr = sol.trajectory
    n_extra = len(t) - tr.n
    q = np.vstack([tr.q, np.repeat(tr.q[-1:], n_extra, axis=0)])
    dq = np.vstack([tr.dq, np.zeros((n_extra, tr.q.shape[1]))])
    ddq = np.vstack([tr.ddq, np.zeros((n_extra, tr.q.shape[1]))])
    if n_extra:
        ddq[tr.n - 1] = 0.0  # at rest from the last move's end on
    return sol.with_(trajectory=Trajectory(np.array(t, dtype=float), q, dq, ddq, dict(tr.goal2time)))


def solve_collab(ctask: CollabTask, setups: Sequence[RobotSetup], cost: Union[CostFunction, str] = "cyc",
                 settings=None, priorities: Optional[Sequence[Sequence[str]]] = None) -> CollabSolveResult:
    """Prioritized planning: the robots are solved one after the other, each starting from its home
    configuration (zero joint angles where that is collision-free and holds against gravity, else its
    first goal's configuration) and waiting, before each move, until the move
    misses the timed motions of the robots before it (``solvers/schedule.py``); every robot then holds its
    last configuration until the last one is done. Priority orders tried: ``priorities``, or the given order
    and its reverse. The first combination the collaborative checker accepts is returned. ``cost``: a
    CostFunction, or a descriptor parsed here once (every robot's solve gets the object)."""
    from robodesign.design.solve import SolveSettings, solve
    from robodesign.solvers.schedule import OtherRobot, static_cell
    settings = settings or SolveSettings()
    cost = cost if isinstance(cost, CostFunction) else parse_cost(cost, path="cost")
    ids = [s.id for s in setups]
    if sorted(ids) != sorted(ctask.robot_ids):
        raise InputError(f"give one robot for each of the task's robots {list(ctask.robot_ids)}, got {ids}")
    by_id = {s.id: s for s in setups}
    assignment = assign_goals(ctask, setups)
    orders = [tuple(p) for p in priorities] if priorities else list(dict.fromkeys([tuple(ids), tuple(reversed(ids))]))
    margin = ctask.safety_margin or 0.0
    message = ""
    results: Dict[str, SolveResult] = {}
    for order in orders:
        done: List[Tuple[str, Robot, Solution]] = []  # (robot ID, its robot model, its solution)
        results = {}
        for rid in order:
            s = by_id[rid]
            t_r = ctask.task_for(rid, [g for g, r in assignment.items() if r == rid])
            base = _base_of(ctask, s)
            me = build_robot(static_cell(t_r), s.module_set, _assembly(s), base)
            colliders = [OtherRobot(me, other, sol.trajectory.t, sol.trajectory.q, margin=margin, names=(rid, oid))
                         for oid, other, sol in done]
            for start in _starts(me, settings.seed):
                res = solve(t_r, s.module_set, list(s.order), base_pose=base, cost=cost, settings=settings,
                            colliders=colliders, start=start)
                if res.feasible:
                    break
            results[rid] = res
            if not res.feasible:
                message = f"robot {rid} (planned after {[d[0] for d in done]}): {res.stage}: {res.message}"
                break
            assert res.solution is not None  # a feasible result has its solution (the checked one)
            done.append((rid, me, res.solution))
        else:
            dt = ctask.task.dt
            n = max(int(round(sol.trajectory.t[-1] / dt)) for _, _, sol in done) + 1
            t = np.arange(n) * dt
            sols = {rid: _pad(sol, t) for rid, _, sol in done}
            csol = CollabSolution(ctask.id, tuple((rid, sols[rid]) for rid in ctask.robot_ids),
                                  computation_time=sum(sum(st.seconds for st in r.stages) for r in results.values()),
                                  notes=f"robodesign solve (prioritized: {', '.join(order)})")
            verdict = check_collab(ctask, csol, {s.id: s.module_set for s in setups})
            if verdict.valid:
                return CollabSolveResult(csol, verdict, order, results, assignment)
            message = f"priority {', '.join(order)}: " + "; ".join(
                f"{r or 'cell'}: {v}" for r, v in verdict.violations[:3])
    return CollabSolveResult(None, None, orders[-1], results, assignment, message)


def _starts(robot, seed: int = 0) -> list:
    """Where a robot of a shared cell may start (and wait for the others), in the order tried: its zero
    configuration (clipped into the joint limits), then the most folded of 200 seeded random configurations
    (the TCP nearest to the base: the smallest footprint in the shared space), each only when it is
    collision-free and gravity alone stays within the torque limits; last the solver's default (the
    configuration of its first goal)."""
    def ok(q):
        return not robot.in_collision(q) and bool(np.all(np.abs(robot.gravity_torque(q)) <= robot.tau_max))
    out = []
    q0 = np.clip(np.zeros(robot.dof), robot.q_lower, robot.q_upper)
    if ok(q0):
        out.append(q0)
    rng = np.random.default_rng(seed)
    base = robot.base_pose[:3, 3]
    park = [q for q in (robot.random_configuration(rng) for _ in range(200)) if ok(q)]
    if park:
        out.append(min(park, key=lambda q: float(np.linalg.norm(robot.fk(q)[:3, 3] - base))))
    return out + [None]


def _assembly(s: RobotSetup):
    from robodesign.formats.assembly import Assembly
    return Assembly.from_order(s.module_set, list(s.order))
