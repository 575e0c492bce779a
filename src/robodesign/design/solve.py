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

import time
import weakref
from dataclasses import replace
from typing import Dict, Optional, Sequence, Union

import numpy as np

from robodesign.core.errors import AssemblyError, InfeasibleError
from robodesign.core.trajectory import Trajectory
from robodesign.design.goal_planner import GoalPlanner, goal_poses, position_slack
from robodesign.design.goal_planner import StageFailure as _Fail
from robodesign.design.stages import (  # noqa: F401 - TIMING_METHODS, check_settings: the documented import path
    STAGES,
    TIMING_METHODS,
    SolveResult,
    SolveSettings,
    StageRecord,
    check_settings,
)
from robodesign.formats.assembly import Assembly
from robodesign.formats.costs import CostFunction, parse_cost
from robodesign.formats.module_spec import ModuleSet
from robodesign.formats.solution import Solution
from robodesign.formats.task_spec import Task
from robodesign.judge.checker import check
from robodesign.model.cell import RobotPool
from robodesign.model.robot import vector_norm
from robodesign.solvers.lazy_rng import LazyGenerator
from robodesign.solvers.schedule import moving_obstacles, static_cell


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
    run.give_back()
    return res


_POOLS: "weakref.WeakKeyDictionary[Task, RobotPool]" = weakref.WeakKeyDictionary()


def robot_pool(task: Task) -> RobotPool:
    """The robots built for ``task``'s static cell in this process (:class:`~robodesign.model.cell.RobotPool`):
    every solve of the task takes its robot from there, so a search that meets an assembly again does not
    build it again."""
    pool = _POOLS.get(task)
    if pool is None:
        pool = _POOLS[task] = RobotPool(static_cell(task))
    return pool


_GOAL_POINTS: "weakref.WeakKeyDictionary[Task, list]" = weakref.WeakKeyDictionary()


def goal_points(task: Task) -> list:
    """(goal, nominal position, :func:`~robodesign.design.goal_planner.position_slack`) of every pose of every goal
    of ``task`` in goal order (:func:`~robodesign.design.goal_planner.goal_poses`), the reach stage's data, made
    once per task."""
    pts = _GOAL_POINTS.get(task)
    if pts is None:
        pts = _GOAL_POINTS[task] = [(g, np.array(pose.nominal[:3, 3], dtype=float), position_slack(pose))
                                    for g in task.goals for pose in goal_poses(g)]
    return pts


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
        self.robot = None

    def assembly(self) -> None:
        ms, a = self.module_set, self.order_or_assembly
        self.asm = a if isinstance(a, Assembly) else Assembly.from_order(ms, a)
        self.robot = robot_pool(self.task).take(ms, self.asm, self.base_pose)
        moving = moving_obstacles(self.task, ms, self.asm, self.base_pose)
        self.colliders = ([moving] if moving is not None else []) + self.colliders

    def give_back(self) -> None:
        """The robot back to the task's pool (the solve is over)."""
        if self.robot is not None:
            robot_pool(self.task).give_back(self.robot)
            self.robot = None

    def base(self) -> None:
        bp = self.task.base_placement
        if bp is not None and not bp.valid(self.base_pose):
            raise _Fail("base pose outside the base-placement tolerance")
        hit = self.robot.base_collisions()  # the part before the first joint: in contact at every configuration
        if hit:
            raise _Fail(f"the robot's base ({hit[0][0]}) collides with {hit[0][1].removeprefix('obstacle:')} "
                        "whatever the joints do")

    def reach(self) -> None:
        o, R = self.robot.reach_bound()
        worst = None  # (metres beyond the reach bound, goal, distance) of the farthest goal
        for g, p, slack in goal_points(self.task):
            d = vector_norm(p - o)   # (float(np.linalg.norm(p - o)), bit for bit)
            miss = d - R - slack
            if miss > 0 and (worst is None or miss > worst[0]):
                worst = (miss, g, d)
        if worst is not None:
            miss, g, d = worst
            self.res.shortfall = miss
            raise _Fail(f"goal {g.id} is {d:.3f} m from the first joint, the arm reaches at most {R:.3f} m")

    def ik(self) -> None:
        rng = LazyGenerator(self.settings.seed)   # (made at its first draw: most candidates never draw)
        self.planner = GoalPlanner(self.task, self.robot, self.settings, rng, self.res, self.cost,
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
                        trajectory=Trajectory(m.t, m.q, m.dq, m.ddq, g2t),
                        module_connection=None if asm.is_serial() else asm.connections,
                        base_connection=None if asm.is_serial() else asm.base,
                        computation_time=sum(s.seconds for s in self.res.stages), notes="robodesign solve")

    def check(self) -> None:
        res = self.res
        v = check(self.task, res.solution, self.module_set, cost=self.cost)
        if not v.valid and _only_collisions(v) and not self.settings.optimize_trajectory:
            v = self._repair_collisions(v)
        if not v.valid and _only_slight_torque(v) and not self.settings.optimize_trajectory:
            v = self._repair_torques(v)
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
        def along_segments(resolution=None):
            def attempt():
                try:
                    if resolution is not None:
                        self.planner.settings = replace(self.settings, resolution=resolution)
                        self.planner.choose_and_plan()
                    self.planner.blend_radius = 0.0
                    return self.planner.time_parameterize()
                finally:
                    self.planner.settings = self.settings
            return attempt
        return self._first_accepted(verdict, (along_segments(), along_segments(self.settings.resolution / 4)),
                                    go_on=_only_collisions)

    def _repair_torques(self, verdict):
        """The time scaling checks torques at the samples with the file's accelerations; the judge certifies the
        continuous motion between them, which may need a little more (|τ| over the limit by up to
        :data:`TORQUE_REPAIR_RATIO`). Then every goal's motion is timed again with the joint speeds scaled by
        0.97, then 0.9 (accelerations by the square); the first motion the judge accepts is kept, else the first
        verdict stands with the motion it judged."""
        def slower(s):
            return lambda: self.planner.time_parameterize(slow={g.id: s for g in self.task.goals})
        return self._first_accepted(verdict, (slower(0.97), slower(0.9)), go_on=lambda v: True)

    def _first_accepted(self, verdict, attempts, go_on):
        """Each attempt (a callable giving a new motion and goal times) in turn, judged: the first valid verdict,
        or the first invalid one for which ``go_on`` is false, is kept with its motion; when an attempt raises
        an infeasibility or all are used up, the first ``verdict`` stands with the motion it judged."""
        kept = (self.res.solution, self.motion, self.g2t)
        for attempt in attempts:
            try:
                self.motion, self.g2t = attempt()
            except (_Fail, InfeasibleError):
                break
            self.res.solution = self.solution()
            v = check(self.task, self.res.solution, self.module_set, cost=self.cost)
            if v.valid or not go_on(v):
                return v
        self.res.solution, self.motion, self.g2t = kept
        return verdict


#: the judge's torque violations that the check stage repairs by timing the motion slower (|τ|/limit at most this)
TORQUE_REPAIR_RATIO = 1.05


def _only_slight_torque(verdict) -> bool:
    """Whether every violation of an invalid verdict is a torque limit exceeded by at most TORQUE_REPAIR_RATIO."""
    vs = verdict.violations
    measured = [x for x in vs if x.value is not None and x.bound is not None]  # the others: "... and n more"
    return bool(measured) and all(x.constraint == "joint.tau" for x in vs) and all(
        x.bound > 0 and abs(x.value) <= TORQUE_REPAIR_RATIO * x.bound for x in measured)


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
        v = check(task, sol, module_set, cost=cost)
        achieved = sum(bool(ok) for ok in v.goals.values())
        kept = res.verdict
        assert kept is not None and kept.cost is not None  # a valid verdict (it misses goals): it has a cost
        if v.valid and v.cost is not None and (achieved, -v.cost) > (res.goals_achieved, -kept.cost):
            res.verdict, res.solution = v, sol.with_(cost=v.cost)


def _stop(res: SolveResult, settings: SolveSettings) -> bool:
    return settings.stop_after is not None and bool(res.stages) and res.stages[-1].name == settings.stop_after
