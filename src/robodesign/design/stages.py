"""What a solve is asked and what it answers: the stage names, :class:`SolveSettings` (validated up front by
:func:`check_settings`) and :class:`SolveResult` (the stages' records, the solution and its verdict)."""
from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import List, Optional, Sequence

from robodesign.core.errors import InputError
from robodesign.formats.module_spec import ModuleSet
from robodesign.formats.solution import Solution
from robodesign.formats.task_spec import Task
from robodesign.judge.checker import Verdict
from robodesign.judge.quantities import TrajectoryQuantities
from robodesign.model.cell import solution_robot
from robodesign.solvers.planning import planner_name

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
    # stop collecting a goal's IK solutions once this many converged restarts since its last new solution were
    # duplicates of those found (0: run every restart). 8 halves a feasible six-joint arm's IK stage; it loses
    # the rarely found solutions, and with them a little of the sequencing's choice (docs/benchmarks.md, "IK
    # restarts that stop when a goal's solutions stop growing")
    ik_saturate: int = 0
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
    if not (isinstance(settings.ik_saturate, int) and not isinstance(settings.ik_saturate, bool)
            and settings.ik_saturate >= 0):
        fail("ik_saturate", f"must be a whole number of repeated IK solutions, 0 (off) or more, got "
                            f"{settings.ik_saturate!r}")
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
    goals_reached: int = 0  # how far the design got: goals with an IK solution (ik), goals whose moves were planned (plan)
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
