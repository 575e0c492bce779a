"""From a robot (assembly + base pose) and a task to a checked CoBRA solution.

The pipeline runs stages from cheap to expensive and stops at the first failure (the paper's
hierarchical elimination); every stage records pass/fail and time:

  assembly → base → reach → ik → static_torque → plan → timing → [trajopt] → check

Goals are handled in the task's goal order: ``at``/``reach`` and ``returnTo`` move to a configuration
and stop; ``pause`` holds still; ``follow`` visits the IK solutions of its poses one after the other
(stopping at each; timed trajectories with exactly the given timing); ``leave`` retreats to a
configuration whose TCP is outside the space to leave and holds it for the duration. The trajectory starts
at the configuration of the first pose goal (or a collision-free configuration if there is none).
The returned cost is the checker's: one judge.

Moving obstacles (and other robots, passed as timed ``colliders``) are avoided in time: IK and planning
see the static cell, and before each move the robot waits at rest until the timed move misses everything
that moves (``solvers/schedule.py``, certified between samples with the checker's semantics).
"""
from __future__ import annotations

import difflib
import math
import time
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Dict, List, Optional, Sequence, Union

import numpy as np

from robodesign.core.errors import AssemblyError, InfeasibleError, InputError
from robodesign.formats.assembly import Assembly
from robodesign.formats.costs import CostFunction, cost_term, parse_cost
from robodesign.formats.module_spec import ModuleSet
from robodesign.formats.solution import Solution, SolutionTrajectory
from robodesign.formats.task_spec import Goal, Task
from robodesign.formats.tolerance import ToleratedPose
from robodesign.judge.checker import Verdict, check
from robodesign.judge.quantities import TrajectoryQuantities
from robodesign.model.cell import build_robot, solution_robot
from robodesign.solvers.planning import planner_name
from robodesign.solvers.schedule import ScheduleError, check_hold, find_wait, moving_obstacles, static_cell

STAGES = ("assembly", "base", "reach", "ik", "static_torque", "plan", "timing", "trajopt", "check")


@dataclass
class SolveSettings:
    planner: str = "rrtconnect"
    plan_time: float = 1.0
    timing: str = "toppra"
    optimize_trajectory: bool = False
    trajopt_nodes: int = 30
    ik_restarts: int = 300  # LM restarts per goal before the goal counts as unreachable
    # distinct IK solutions per goal to choose from: the sequencing picks the combination with the
    # shortest time-optimal bounds, so more choice gives shorter, less random cycle times
    # (docs/benchmarks.md, "Choosing among IK solutions")
    ik_solutions: int = 48
    resolution: float = 0.01  # rad: dense collision-check step of planned paths
    # when no path reaches a goal's chosen IK solution, one more query (half of plan_time) to it or any of this
    # many of the goal's other IK solutions (nearest first)
    plan_alternatives: int = 8
    seed: int = 0
    check: bool = True
    stop_after: Optional[str] = None  # stop after this stage (screening, e.g. "ik"); no solution is produced
    # a task without allGoalsFulfilled accepts a solution that misses goals, but the solver still wants
    # them: the motions of the goals the checker found missed are re-timed this many times, each at half
    # the joint speed (a quarter of the acceleration) of the previous try; the try that achieves most
    # goals is kept (a goal-level endEffector v_max is the usual reason a goal is missed)
    goal_retries: int = 5


TIMING_METHODS = ("toppra", "ruckig")


def check_settings(settings: SolveSettings, file: Optional[str] = None, path: Sequence = ()) -> None:
    """Bad input in ``settings`` (an unknown planner or timing method, a plan time that is not a positive
    number, an unknown ``stop_after`` stage) as an :class:`InputError` before anything is evaluated, instead
    of every candidate failing at the stage that uses it. The error names the command-line option
    (``--planner``) or, with ``file``, the file and the JSON path ``path + [field]``."""
    def fail(name: str, message: str) -> None:
        if file is None:
            raise InputError(f"--{name.replace('_', '-')}: {message}")
        raise InputError(message, file=file, path=[*path, name])
    try:
        planner_name(settings.planner)
    except InputError as e:
        fail("planner", e.reason)
    if settings.timing not in TIMING_METHODS:
        close = difflib.get_close_matches(str(settings.timing), TIMING_METHODS, n=1)
        fail("timing", f"unknown timing method {settings.timing!r}" + (f" (did you mean {close[0]!r}?)" if close else "")
             + f"; available: {', '.join(TIMING_METHODS)}")
    if not (isinstance(settings.plan_time, (int, float)) and settings.plan_time > 0 and math.isfinite(settings.plan_time)):
        fail("plan_time", f"must be a positive number of seconds, got {settings.plan_time!r}")
    if settings.stop_after is not None and settings.stop_after not in STAGES:
        fail("stop_after", f"unknown stage {settings.stop_after!r}; stages: {', '.join(STAGES)}")


@dataclass
class StageRecord:
    name: str
    passed: bool
    seconds: float
    message: str = ""

    def to_json(self) -> dict:
        return {"name": self.name, "passed": self.passed, "seconds": round(self.seconds, 6), "message": self.message}


@dataclass
class SolveResult:
    stages: List[StageRecord] = field(default_factory=list)
    solution: Optional[Solution] = None
    verdict: Optional[Verdict] = None
    goals_reached: int = 0  # goals with an IK solution (how far the ik stage got)
    # how far the failed stage missed, in its own unit: metres beyond the reach bound (reach: the farthest
    # goal), Nm over the limit (static_torque: the smallest excess among the failing goal's IK solutions);
    # None when the stage passed or does not measure it
    shortfall: Optional[float] = None
    num_goals: int = 0
    task: Optional[Task] = field(default=None, repr=False, compare=False)  # what was solved, for `quantities`
    module_set: Optional[ModuleSet] = field(default=None, repr=False, compare=False)

    @cached_property
    def quantities(self) -> Optional[TrajectoryQuantities]:
        """What the solution's motion does on the robot in its cell — TCP poses and twists, goal windows,
        follow-goal wrenches, drivetrain torques — as the shared, lazily computed
        :class:`~robodesign.judge.quantities.TrajectoryQuantities` the checker and the viewer read (None without a
        solution)."""
        if self.solution is None or self.task is None:
            return None
        robot = solution_robot(self.task, self.solution, self.module_set)
        return TrajectoryQuantities.from_solution(robot, self.solution, self.task)

    @property
    def goals_achieved(self) -> Optional[int]:
        """Goals the checker found achieved in the solution (None when there is no checked solution)."""
        return None if self.verdict is None else sum(bool(ok) for ok in self.verdict.goals.values())

    @property
    def goals_missed(self) -> List[str]:
        return [] if self.verdict is None else [gid for gid, ok in self.verdict.goals.items() if not ok]

    @property
    def feasible(self) -> bool:
        return self.verdict is not None and self.verdict.valid

    @property
    def stage(self) -> str:
        """Name of the first failed stage, or 'done'."""
        for s in self.stages:
            if not s.passed:
                return s.name
        return "done"

    @property
    def stage_index(self) -> int:
        """How far the candidate got: index in STAGES of the failed stage (len(STAGES) when done)."""
        st = self.stage
        return len(STAGES) if st == "done" else STAGES.index(st)

    @property
    def cost(self) -> Optional[float]:
        return self.verdict.cost if self.verdict is not None else None

    @property
    def message(self) -> str:
        for s in self.stages:
            if not s.passed:
                return s.message
        return ""


class _Stage:
    def __init__(self, result: SolveResult, name: str):
        self.result, self.name = result, name

    def __enter__(self):
        self.t0 = time.perf_counter()
        return self

    def __exit__(self, et, ev, tb):
        dt = time.perf_counter() - self.t0
        if et is None:
            self.result.stages.append(StageRecord(self.name, True, dt))
            return False
        if _infeasible(self.name, ev):
            self.result.stages.append(StageRecord(self.name, False, dt, str(ev)))
            return True  # swallowed: the caller checks result.stage
        return False  # bad input (InputError, exit 2) and bugs keep their kind


def _infeasible(stage: str, e: BaseException) -> bool:
    """Whether ``e``, raised in ``stage``, means the robot cannot do the task (a failing stage): a stage's
    own failure, an :class:`InfeasibleError` of a solver, or a module order that does not assemble (the
    ``assembly`` stage only: a candidate order is a design, not a file). Every other error is bad input or a
    bug and leaves :func:`solve` as it is."""
    return isinstance(e, (_Fail, InfeasibleError)) or (stage == "assembly" and isinstance(e, AssemblyError))


class _Fail(Exception):
    pass


def solve(task: Task, module_set: ModuleSet, order_or_assembly, base_pose: Optional[np.ndarray] = None,
          cost: Union[CostFunction, str] = "cyc", settings: Optional[SolveSettings] = None, colliders: Sequence = (),
          start: Optional[np.ndarray] = None) -> SolveResult:
    """Produce (and check) a solution of ``task`` with the given robot. Never raises for an infeasible
    robot: the failing stage and its reason are in the result. ``cost``: a CostFunction (e.g. ``Problem.cost``),
    or a descriptor, parsed here once (a malformed one raises InputError); the same object reaches the
    sequencing, trajectory optimization and the solution file.

    IK and planning see the static cell; the task's moving obstacles and the extra timed ``colliders``
    (e.g. another robot's motion, :class:`robodesign.solvers.schedule.OtherRobot`) are avoided in time:
    before each move the robot waits at rest as long as needed (``solvers/schedule.py``). ``start``: the
    configuration the motion starts from (default: that of the first pose goal); a ``returnTo`` the start
    returns there."""
    settings = settings or SolveSettings()
    cost = cost if isinstance(cost, CostFunction) else parse_cost(cost)  # bad input, not an infeasible robot
    res = SolveResult(num_goals=len(task.goals), task=task, module_set=module_set)
    base_pose = task.nominal_base_pose if base_pose is None else np.asarray(base_pose, dtype=float)
    run = _Pipeline(task, module_set, order_or_assembly, base_pose, cost, settings, res, colliders, start)
    for name in STAGES:
        if name == "trajopt" and not settings.optimize_trajectory:
            continue
        if name == "check":
            res.solution = run.solution()
            if not settings.check:
                break
        with _Stage(res, name):
            getattr(run, name)()
        if res.stage != "done" or _stop(res, settings):
            break
    return res


def warm_up() -> None:
    """Load now what :func:`solve` otherwise loads at its first use: the compiled IK kernels (when numba's
    cache holds them, ~0.3 s; with a cold cache this starts their background compilation, as the first IK
    would) and the time-scaling library (~0.3 s). Evaluator pools call it in every worker as it starts, so
    that the first candidates a worker gets cost what the others do. Results never depend on it."""
    from robodesign.solvers import ik_kernel, timing
    if ik_kernel.ready():
        ik_kernel.warm_up()
    timing.preload()


class _Pipeline:
    """The stages of :func:`solve`, one method per name in STAGES; each raises _Fail (or an InfeasibleError)
    to stop the pipeline with its reason."""

    def __init__(self, task, module_set, order_or_assembly, base_pose, cost, settings, res, colliders=(), start=None):
        self.task, self.module_set, self.order_or_assembly = task, module_set, order_or_assembly
        self.colliders, self.start = list(colliders), start
        self.base_pose, self.cost, self.settings, self.res = base_pose, cost, settings, res
        self.rng = np.random.default_rng(settings.seed)

    def assembly(self) -> None:
        ms, a = self.module_set, self.order_or_assembly
        self.asm = a if isinstance(a, Assembly) else Assembly.from_order(ms, a)
        self.robot = build_robot(static_cell(self.task), ms, self.asm, self.base_pose)
        moving = moving_obstacles(self.task, ms, self.asm, self.base_pose)
        self.colliders = ([moving] if moving is not None else []) + self.colliders

    def base(self) -> None:
        bp = self.task.base_placement
        if bp is not None and not bp.valid(self.base_pose):
            raise _Fail("base pose outside the base-placement tolerance")

    def reach(self) -> None:
        o, R = self.robot.reach_bound()
        worst = None  # (metres beyond the reach bound, goal, distance) of the farthest goal
        for g in self.task.goals:
            for pose in goal_poses(g):
                d = float(np.linalg.norm(pose.nominal[:3, 3] - o))
                miss = d - R - position_slack(pose)
                if miss > 0 and (worst is None or miss > worst[0]):
                    worst = (miss, g, d)
        if worst is not None:
            miss, g, d = worst
            self.res.shortfall = miss
            raise _Fail(f"goal {g.id} is {d:.3f} m from the first joint, the arm reaches at most {R:.3f} m")

    def ik(self) -> None:
        self.planner = GoalPlanner(self.task, self.robot, self.settings, self.rng, self.res, self.cost,
                                   colliders=self.colliders, start=self.start)
        self.planner.solve_ik()

    def static_torque(self) -> None:
        self.planner.filter_static_torque()

    def plan(self) -> None:
        self.planner.choose_and_plan()

    def timing(self) -> None:
        self.motion, self.g2t = self.planner.time_parameterize()

    def trajopt(self) -> None:
        self.motion, self.g2t = self.planner.time_parameterize(self.cost)

    def solution(self, motion=None, g2t=None) -> Solution:
        """The solution of the timed motion (default: the last stage's)."""
        asm, ms = self.asm, self.module_set
        m, g2t = (self.motion, self.g2t) if motion is None else (motion, g2t)
        return Solution(task_id=self.task.id, cost_function=str(self.cost), module_set=ms.name,
                        module_order=tuple(asm.module_ids), base_pose=self.base_pose,
                        trajectory=SolutionTrajectory(m.t, m.q, m.dq, m.ddq, g2t),
                        module_connection=None if asm.is_serial() else asm.connections,
                        base_connection=None if asm.is_serial() else asm.base,
                        computation_time=sum(s.seconds for s in self.res.stages), notes="robodesign solve")

    def check(self) -> None:
        res = self.res
        v = check(self.task, res.solution, self.module_set)
        if not v.valid and _only_collisions(v) and not self.settings.optimize_trajectory:
            v = self._repair_collisions(v)
        res.verdict = v
        res.solution = res.solution.with_(cost=v.cost)
        if not v.valid:
            raise _Fail("; ".join(str(x) for x in v.violations[:3]))
        _achieve_missed_goals(res, self.planner, self.task, self.module_set, self.solution, self.cost, self.settings)


    def _repair_collisions(self, verdict):
        """The judge sweeps the continuous motion; the planner checked states ``resolution`` apart and the blends
        cut corners. When collisions between samples are all that is wrong, the moves are timed again with a stop
        at every waypoint (along the checked segments), then planned again with a 4× finer check step; the first
        motion the judge accepts is kept, else the first verdict stands with the motion it judged."""
        kept = (self.res.solution, self.motion, self.g2t)
        for resolution in (None, self.settings.resolution / 4):
            try:
                if resolution is not None:
                    self.planner.settings = replace(self.settings, resolution=resolution)
                    self.planner.choose_and_plan()
                self.planner.blend_radius = 0.0
                self.motion, self.g2t = self.planner.time_parameterize()
            except (_Fail, InfeasibleError):
                break
            finally:
                self.planner.settings = self.settings
            self.res.solution = self.solution()
            v = check(self.task, self.res.solution, self.module_set)
            if v.valid or not _only_collisions(v):
                return v
        self.res.solution, self.motion, self.g2t = kept
        return verdict


def _only_collisions(verdict) -> bool:
    """Whether every violation of an invalid verdict is a collision (robot–obstacle or self)."""
    return bool(verdict.violations) and all(x.constraint in ("collisionFree", "selfCollisionFree")
                                            for x in verdict.violations)


def _achieve_missed_goals(res: SolveResult, plan: "GoalPlanner", task: Task, module_set: ModuleSet, solution_of,
                          cost: CostFunction, settings: SolveSettings) -> None:
    """A valid solution that misses goals (possible only without allGoalsFulfilled): re-time the motions of
    the missed goals slower (``settings.goal_retries`` times, halving the speed each time) and keep the
    valid solution that achieves most goals (then the cheaper one)."""
    slow: Dict[str, float] = {}
    for _ in range(settings.goal_retries):
        missed = res.goals_missed
        if not missed:
            return
        for gid in missed:
            slow[gid] = slow.get(gid, 1.0) * 0.5
        try:
            motion, g2t = plan.time_parameterize(cost if settings.optimize_trajectory else None, slow=slow)
        except InfeasibleError:
            return
        sol = solution_of(motion, g2t)
        v = check(task, sol, module_set)
        achieved = sum(bool(ok) for ok in v.goals.values())
        if v.valid and (achieved, -v.cost) > (res.goals_achieved, -res.verdict.cost):
            res.verdict, res.solution = v, sol.with_(cost=v.cost)


def _stop(res: SolveResult, settings: SolveSettings) -> bool:
    return settings.stop_after is not None and bool(res.stages) and res.stages[-1].name == settings.stop_after


def goal_poses(g: Goal) -> List[ToleratedPose]:
    """The tolerated poses the TCP must reach for goal ``g`` (:attr:`Goal.target_poses`)."""
    return list(g.target_poses)


def position_slack(pose: ToleratedPose) -> float:
    """How far [m] a goal position may lie from the pose's nominal position (its largest position bound)."""
    s = 0.0
    for name, (lo, hi), _ in pose.entries:
        if name in ("r_sph", "r_cyl"):
            s = max(s, hi)
        elif name in ("x", "y", "z"):
            s = max(s, max(abs(lo), abs(hi)))
    return s if math.isfinite(s) else 1e9


class GoalPlanner:
    """The ik → static_torque → plan → timing stages for one robot: holds the per-goal IK solutions
    (``ik``, ``follow_ik``), the chosen ones (``choice``), the start configuration ``q0`` and the
    actions and paths of the goal sequence, and turns them into a motion."""

    def __init__(self, task: Task, robot, settings: SolveSettings, rng, res: SolveResult,
                 cost: Optional[CostFunction] = None,
                 colliders: Sequence = (), start: Optional[np.ndarray] = None):
        self.task, self.robot, self.settings, self.rng, self.res = task, robot, settings, rng, res
        self.colliders = list(colliders)  # timed colliders: moving obstacles, other robots
        self.start = None if start is None else np.asarray(start, dtype=float)  # given start configuration
        self.blend_radius = 0.05  # rad: the time scaling's corner blends (0: stop at every waypoint)
        terms = dict((cost if cost is not None else CostFunction((("cyc", 1.0),))).terms)
        # weights of the transition cost used to choose among IK solutions: time (time-optimal bound) and
        # energy (the Coulomb-friction work Σ f_c·|Δq|, a lower bound of the drivetrain energy of a move),
        # the latter for every term that integrates torques (mechEnergy, linkMechEnergy, effort)
        self.w_time = terms.get("cyc", 0.0)
        self.w_energy = sum(w for n, w in terms.items() if cost_term(n).needs_torques)
        if self.w_time == 0.0 and self.w_energy == 0.0:
            self.w_time = 1.0
        self.order = [task.goal(gid) for gid in task.goal_order]
        self.ik: Dict[str, List[np.ndarray]] = {}  # at/reach goal → candidate configurations
        self.follow_ik: Dict[str, List[np.ndarray]] = {}

    # -- IK ------------------------------------------------------------------------------------
    def solve_ik(self) -> None:
        from robodesign.solvers.ik import fixes_full_pose, provably_unreachable, solve_ik
        # an arm that cannot move its tool in all six directions (solvers.ik.fixes_full_pose) does not look for
        # a goal that fixes position and orientation: its restarts would all fail (docs/diagnosis.md)
        full = next((g for g in self.order if any(fixes_full_pose(p) for p in goal_poses(g))), None)
        if full is not None and self.robot.generic_rank() < 6:
            self.res.goals_reached = 0
            raise _Fail(f"no IK solution for goal {full.id}: it fixes position and orientation, but the arm's tool "
                        f"moves in only {self.robot.generic_rank()} independent directions at any configuration "
                        "(its Jacobian's rank; parallel or coaxial joint axes)")
        # a goal that provably no configuration reaches (solvers.ik.ChainBounds) fails the stage whatever
        # comes before it. The last IK goal before it then only needs to show whether it is reachable: its
        # first solution decides that exactly as when ik_solutions are wanted (the attempts up to the first
        # accepted one are the same), and nothing after it draws from the random generator any more (the
        # earlier goals keep collecting: collecting draws perturbations that later goals' starts depend on)
        doomed = next((i for i, g in enumerate(self.order)
                       if any(provably_unreachable(self.robot, p) for p in goal_poses(g))), None)
        probe = None
        if doomed is not None:
            before = [i for i in range(doomed) if self.order[i].solver_kind in ("pose", "poses")]
            if before and self.order[before[-1]].solver_kind == "pose":
                probe = before[-1]
        reached = 0
        for i, g in enumerate(self.order):
            if g.solver_kind == "pose":
                n_sol = 1 if i == probe else self.settings.ik_solutions
                r = solve_ik(self.robot, g.target_poses[0], self.rng, max_restarts=self.settings.ik_restarts,
                             n_solutions=n_sol)
                sols, reason = r.solutions, str(r.stats.get("reason"))
                if not sols:
                    self.res.goals_reached = reached
                    raise _Fail(f"no collision-free IK solution for goal {g.id} ({reason})")
                self.ik[g.id] = sols
                reached += 1
            elif g.solver_kind == "poses":
                sols = []
                seed = None
                for i, pose in enumerate(g.target_poses):
                    r = solve_ik(self.robot, pose, self.rng, q_seed=seed, max_restarts=self.settings.ik_restarts)
                    if not r:
                        self.res.goals_reached = reached
                        raise _Fail(f"no IK solution for pose {i} of follow goal {g.id}")
                    seed = r.q
                    sols.append(r.q)
                self.follow_ik[g.id] = sols
                reached += 1
            else:
                reached += 1
        self.res.goals_reached = reached

    def filter_static_torque(self) -> None:
        r = self.robot
        limit = r.tau_max - r.friction_coulomb * 0  # at rest the Coulomb term vanishes (σ(0) = 0)
        for gid, sols in self.ik.items():
            taus = [np.abs(r.gravity_torque(q)) for q in sols]
            ok = [q for q, tau in zip(sols, taus) if np.all(tau <= limit)]
            if not ok:
                tau = taus[0]
                j = int(np.argmax(tau / limit))
                self.res.shortfall = min(float(np.max(t - limit)) for t in taus)
                raise _Fail(f"goal {gid}: holding the pose needs {tau[j]:.1f} Nm at joint {j} (limit {limit[j]:.1f})")
            self.ik[gid] = ok
        for gid, sols in self.follow_ik.items():
            for i, q in enumerate(sols):
                tau = np.abs(r.gravity_torque(q))
                if np.any(tau > limit):
                    self.res.shortfall = float(np.max(tau - limit))
                    j = int(np.argmax(tau / limit))
                    raise _Fail(f"follow goal {gid}, pose {i}: static torque {tau[j]:.1f} Nm > {limit[j]:.1f} at joint {j}")

    # -- sequencing ------------------------------------------------------------------------------
    def _cost(self, A: np.ndarray, B: np.ndarray) -> np.ndarray:
        """Transition costs between every configuration of ``A`` (rows) and of ``B`` (columns)."""
        from robodesign.solvers.timing import time_optimal_bounds
        D = np.abs(B[None, :, :] - A[:, None, :])
        c = np.zeros(D.shape[:2])
        if self.w_time:
            c += self.w_time * time_optimal_bounds(self.robot, D)
        if self.w_energy:
            c += self.w_energy * np.sum((self.robot.friction_coulomb + 1e-3) * D, axis=-1)
        return c

    def choose_and_plan(self) -> None:
        """Choose one IK solution per pose goal (dynamic programming over the goal sequence, minimising
        the sum of time-optimal bounds of all moves, including returns to the start), then plan
        collision-free paths between the stops."""
        choice: Dict[str, np.ndarray] = {}
        nodes = self._sequence_nodes()
        if nodes:
            from robodesign.solvers.sequencing import choose
            idx, _ = choose(nodes, self._cost)
            choice = {gid: self.ik[gid][i] for gid, i in idx.items()}
        self.choice = choice
        # the start configuration
        first_pose = next((g for g in self.order if g.solver_kind in ("pose", "poses")), None)
        if self.start is not None:
            if self.robot.in_collision(self.start):
                raise _Fail("the start configuration is in collision")
            q0 = self.start
        elif first_pose is None:
            q0 = self._free_configuration()
        elif first_pose.solver_kind == "poses":
            q0 = self.follow_ik[first_pose.id][0]
        else:
            q0 = choice[first_pose.id]
        self.q0 = q0
        # build the list of actions: ("move", q_target, goal or None) | ("hold", duration, goal) | ...
        actions = []
        q = q0
        at_config: Dict[str, np.ndarray] = {}
        for g in self.order:
            if g.solver_kind == "pose":
                actions.append(("move", choice[g.id], g))
                q = choice[g.id]
            elif g.solver_kind == "hold":
                actions.append(("hold", g.duration, g))
            elif g.solver_kind == "return":
                target = q0 if g.return_to is None else at_config.get(g.return_to)
                if target is None:
                    raise _Fail(f"returnTo goal {g.id}: goal {g.return_to!r} has no configuration before it")
                actions.append(("move", target, g))
                q = target
            elif g.solver_kind == "poses":
                pts = self.follow_ik[g.id]
                actions.append(("move", pts[0], None))
                actions.append(("follow", pts, g))
                q = pts[-1]
            elif g.solver_kind == "leave":
                q_out = self._leave_configuration(q, g)
                actions.append(("move", q_out, None))
                actions.append(("hold", g.duration, g))
                q = q_out
            at_config[g.id] = q
        self.actions = actions
        # plan every move
        self.paths = []
        q = q0
        for i in range(len(self.actions)):
            kind, arg, g = self.actions[i]  # an earlier move may have replaced a goal's configuration
            if kind == "move":
                if np.allclose(arg, q, atol=1e-12):
                    self.paths.append(None)
                    continue
                r = self._plan(q, arg, self.settings.plan_time)
                if not r:
                    r, arg = self._plan_to_another_solution(q, arg, g, r)
                if not r:
                    raise _Fail(f"no collision-free path to {'goal ' + g.id if g else 'the next waypoint'} "
                                f"({r.stats.get('reason')})")
                self.paths.append(r.path)
                q = arg
            elif kind == "follow":
                from robodesign.solvers.planning import check_path
                P = np.vstack(arg)
                ok, bad = check_path(self.robot, P, self.settings.resolution)
                if not ok:
                    raise _Fail(f"follow goal {g.id}: the motion between poses {bad} and {bad + 1} collides")
                self.paths.append(P)
                q = arg[-1]
            else:
                self.paths.append(None)

    def _plan(self, q, target, time_limit: float, other_goals=()):
        from robodesign.solvers.planning import plan_path
        return plan_path(self.robot, q, target, planner=self.settings.planner, time_limit=time_limit,
                         seed=int(self.rng.integers(2 ** 31)), resolution=self.settings.resolution,
                         static_torque=True,  # as the static_torque stage: timing cannot repair it
                         other_goals=other_goals)

    def _plan_to_another_solution(self, q, target, g, failed):
        """When no path reaches the chosen IK solution of an at/reach goal (free space, with the poses the
        joints can hold, often falls apart into pieces: the goal's other solutions lie in other pieces), plan
        once more, with half the planning effort, to any of the goal's IK solutions: the chosen one and up to
        ``settings.plan_alternatives`` others, nearest first (the sequencing's transition cost from ``q``), all
        goal states of one query, each also with one joint turned a whole turn (the long way round an obstacle).
        The one the path reaches replaces the chosen one in every later action.
        Returns (plan result, target)."""
        if (g is None or g.solver_kind != "pose" or self.choice.get(g.id) is not target
                or self.settings.plan_alternatives <= 0):
            return failed, target
        others = [c for c in self.ik.get(g.id, []) if not np.array_equal(c, target)]
        order = (np.argsort(self._cost(np.asarray(q, dtype=float)[None, :], np.vstack(others))[0], kind="stable")
                 if others else [])
        alts = [others[int(k)] for k in order[: self.settings.plan_alternatives]]
        # and the same poses with one joint turned a whole turn (Robot.turn_variants): the long way round
        alts += [v for c in [target] + alts for v in self.robot.turn_variants(c)]
        r = self._plan(q, target, self.settings.plan_time / 2, other_goals=alts)
        if not r:
            return failed, target
        k = int(r.stats.get("goal", 0))
        if k == 0:
            return r, target
        alt = alts[k - 1]
        self.choice[g.id] = alt
        self.actions = [(kd, alt if (kd == "move" and a is target) else a, gg) for kd, a, gg in self.actions]
        return r, alt

    def _sequence_nodes(self) -> list:
        """The goal sequence as a chain for ``solvers.sequencing.choose``. A ``returnTo`` another at/reach
        goal than the first is left out of the objective (its target is chosen by its own neighbours)."""
        from robodesign.solvers.sequencing import Fixed, Free, Jump, Tied
        first = next((g for g in self.order if g.solver_kind in ("pose", "poses")), None)
        if first is None:
            return []
        nodes = [] if self.start is None else [Fixed(self.start)]
        for g in self.order:
            if g.solver_kind == "pose":
                nodes.append(Free(g.id, np.asarray(self.ik[g.id])))
            elif g.solver_kind == "poses":
                pts = self.follow_ik[g.id]
                nodes += [Fixed(pts[0]), Jump(pts[-1])]
            elif g.solver_kind == "return" and nodes:
                if g.return_to is None and self.start is not None:
                    nodes.append(Tied())
                elif g.return_to is None:
                    nodes.append(Tied() if first.solver_kind == "pose" else Fixed(self.follow_ik[first.id][0]))
                elif g.return_to == first.id and first.solver_kind == "pose" and self.start is None:
                    nodes.append(Tied())
                elif g.return_to in self.follow_ik:
                    nodes.append(Fixed(self.follow_ik[g.return_to][-1]))
        return nodes

    def _free_configuration(self) -> np.ndarray:
        q = np.clip(np.zeros(self.robot.dof), self.robot.q_lower, self.robot.q_upper)
        for _ in range(200):
            if not self.robot.in_collision(q):
                return q
            q = self.robot.random_configuration(self.rng)
        raise _Fail("no collision-free start configuration found")

    def _leave_configuration(self, q: np.ndarray, g: Goal) -> np.ndarray:
        """A nearby configuration whose TCP is outside the space to leave: the TCP moves in a straight line
        (2 cm steps through the damped Jacobian pseudo-inverse) until it and a point 2 cm further on are
        outside, collision-free. Directions tried: away from the space's centre and along ±x, ±y, ±z; the
        shortest retreat wins."""
        r = self.robot
        away = r.fk(q)[:3, 3] - g.center
        dirs = [away / np.linalg.norm(away)] if np.linalg.norm(away) > 1e-6 else []
        dirs += [s * e for e in np.eye(3) for s in (1.0, -1.0)]
        best = None
        for u in dirs:
            qc = q.copy()
            for n in range(150 if best is None else best[0]):
                T = r.fk(qc)
                if not g.contains(T) and not g.contains(_translate(T, 0.02 * u)) and not r.in_collision(qc):
                    best = (n, qc)
                    break
                J = r.jacobian(qc)[:3]
                dq = J.T @ np.linalg.solve(J @ J.T + 1e-4 * np.eye(3), 0.02 * u)  # damped near singularities
                dq *= min(1.0, 0.05 / max(float(np.abs(dq).max()), 1e-12))     # ≤ 0.05 rad per step
                qc = np.clip(qc + dq, r.q_lower, r.q_upper)
        if best is None:
            raise _Fail(f"leave goal {g.id}: could not move the TCP out of the space to leave")
        return best[1]

    # -- timing ----------------------------------------------------------------------------------
    def time_parameterize(self, cost: Optional[CostFunction] = None, slow: Optional[Dict[str, float]] = None):
        """:meth:`timed_motion` avoiding what moves: each move waits at rest until it is free; if some wait
        cannot help (the robot would be hit while it waits), the whole motion is instead delayed at its
        start until it runs free of everything that moves."""
        try:
            return self.timed_motion(cost, slow, self.colliders)
        except _Fail as per_move:
            if not self.colliders:
                raise
            traj, g2t = self.timed_motion(cost, slow, ())
            dt = self.task.dt
            try:
                n = find_wait(self.colliders, 0.0, traj.q[0], traj.t, traj.q, dt)
            except ScheduleError:
                raise per_move from None
            if n == 0:
                return traj, g2t
            from robodesign.solvers.timing import JointTrajectory
            return (JointTrajectory.at_rest(traj.q[0]).hold(n * dt, dt).concatenate(traj),
                    {k: v + n * dt for k, v in g2t.items()})

    def timed_motion(self, cost: Optional[CostFunction] = None, slow: Optional[Dict[str, float]] = None,
                     colliders: Sequence = ()):
        """The whole motion, sampled at the task's time step, and the goal times. With ``cost`` (trajectory
        optimization enabled) every rest-to-rest move is re-timed by CasADi/ipopt for that cost; a move
        whose optimization fails keeps its time-optimal TOPP-RA timing. ``slow`` maps goal IDs to a speed
        factor s < 1 for the motion of that goal (joint speed limits × s, accelerations × s²). Before each
        move the robot waits at rest until the move misses every timed collider of ``colliders``."""
        from robodesign.solvers.timing import JointTrajectory, time_parameterize
        dt = self.task.dt
        traj = JointTrajectory.at_rest(self.q0)
        g2t: Dict[str, float] = {}
        slow = slow or {}
        for (kind, arg, g), path in zip(self.actions, self.paths):
            robot = self.robot if g is None or g.id not in slow else _SlowedRobot(self.robot, slow[g.id])
            if kind == "move":
                if path is not None:
                    seg = time_parameterize(robot, path, dt=dt, method=self.settings.timing,
                                            blend_radius=self.blend_radius)
                    if cost is not None and robot is self.robot:  # a slowed move keeps its slow timing
                        seg = self._optimize_move(seg, cost)
                    traj = self._append_after_wait(traj, seg, g, colliders)
                if g is not None:
                    g2t[g.id] = float(traj.t[-1])
            elif kind == "hold":
                self._check_hold(traj, arg, g, colliders)
                if arg > 0:
                    traj = traj.hold(arg, dt)
                g2t[g.id] = float(traj.t[-1])
                if g.solver_kind == "leave":
                    g2t[g.id] = float(traj.t[-1] - _ceil_to(arg, dt))
            elif kind == "follow":
                if g.t is None:
                    seg = time_parameterize(robot, path, dt=dt, method=self.settings.timing, blend_radius=0.0,
                                            stop_at=list(range(len(path))))
                else:
                    seg = _timed_follow(path, g.t, dt)
                traj = self._append_after_wait(traj, seg, g, colliders)
                g2t[g.id] = float(traj.t[-1])
        return traj, g2t

    def _append_after_wait(self, traj, seg, g, colliders):
        """``traj`` followed by the move ``seg``, after waiting at rest as long as needed for the move to
        miss every timed collider (moving obstacles, other robots)."""
        if not colliders:
            return traj.concatenate(seg)
        try:
            n = find_wait(colliders, float(traj.t[-1]), traj.q[-1], seg.t, seg.q, self.task.dt)
        except ScheduleError as e:
            raise _Fail(f"the move to {'goal ' + g.id if g else 'the next waypoint'}: {e}") from None
        if n:
            traj = traj.hold(n * self.task.dt, self.task.dt)
        return traj.concatenate(seg)

    def _check_hold(self, traj, duration: float, g, colliders) -> None:
        why = check_hold(colliders, float(traj.t[-1]), traj.q[-1], duration, self.task.dt)
        if why:
            raise _Fail(f"goal {g.id}: a moving part hits the robot while it holds still {why}")

    def _optimize_move(self, seg, cost: CostFunction):
        from robodesign.solvers.trajopt import TrajoptError, optimize_trajectory
        weights = cost.trajopt_weights() or {"cyc": 1.0}
        if "cyc" not in weights:
            # energy only: slower is always cheaper (viscous losses), so the optimum is an endless move;
            # a tiny time weight (1 % of the energy weight) makes the duration finite
            weights["cyc"] = 0.01
        try:
            out = optimize_trajectory(self.robot, seg, cost=weights, n_nodes=self.settings.trajopt_nodes,
                                      dt_out=self.task.dt)
        except TrajoptError:  # ipopt failure: keep the TOPP-RA move (valid, time-optimal)
            return seg
        return out if np.allclose(out.q[-1], seg.q[-1], atol=1e-9) and np.all(out.dq[-1] == 0) else seg


class _SlowedRobot:
    """The robot with its joint speed limits scaled by ``s`` and its acceleration limits by ``s²`` (for
    timing only: a motion timed with it is the robot's own motion, slower)."""

    def __init__(self, robot, s: float):
        self._robot = robot
        self.dq_max = np.asarray(robot.dq_max, dtype=float) * s
        self.ddq_max = np.asarray(robot.ddq_max, dtype=float) * s * s

    def __getattr__(self, name):
        return getattr(self._robot, name)


def _ceil_to(x: float, dt: float) -> float:
    return math.ceil(x / dt - 1e-9) * dt


def _translate(T: np.ndarray, d: np.ndarray) -> np.ndarray:
    T2 = T.copy()
    T2[:3, 3] += d
    return T2


def _timed_follow(path: np.ndarray, t_rel: np.ndarray, dt: float):
    """Quintic rest-to-rest moves between consecutive follow poses with exactly the given timing."""
    from robodesign.solvers.timing import JointTrajectory
    out = JointTrajectory.at_rest(path[0])
    for a, b, T in zip(path, path[1:], np.diff(t_rel)):
        n = max(1, int(round(T / dt)))
        s = np.linspace(0, 1, n + 1)[:, None]
        d = b - a
        q = a + d * (10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5)
        dq = d * (30 * s ** 2 - 60 * s ** 3 + 30 * s ** 4) / T
        ddq = d * (60 * s - 180 * s ** 2 + 120 * s ** 3) / T ** 2
        ddq[-1] = 0.0
        out = out.concatenate(JointTrajectory(np.arange(n + 1) * dt, q, dq, ddq))
    return out
