"""The judge: does a solution solve a task, and what does it cost?

``check(task, solution, module_set)`` returns a :class:`Verdict` with every violation (which
constraint or goal, at which time/sample, the value and the bound) and every cost. The same code
judges uploads, solver output and optimizer candidates. Semantics (docs/checker.md):

* ``t`` starts at 0 and no step is longer than the task's time step (the reference's "sampled every
  timeStepSize", applied to the whole trajectory).
* The samples describe one motion (:mod:`robodesign.judge.motion`): between two samples each joint follows
  the least-acceleration motion through its q and velocity, which must stay within the joint's acceleration
  limit. Positions, velocities and collisions are checked on that motion between the samples too
  (collisions certified by :mod:`robodesign.model.sweep`), torques at every sample with the file's ddq and
  with the motion's acceleration just before and after it, and certified between the samples
  (:mod:`robodesign.judge.arc_torques`).
* ``ddq`` limits are enforced (the reference never checks them).
* Costs read the judged motion: its velocities and its acceleration at each sample (and the torques with them),
  not the file's dq/ddq (:attr:`TrajectoryQuantities.motion_accelerations`).
* Torques are drivetrain torques τ = RNEA + k²I_m q̈ + f_v q̇ + f_c σ(q̇) under the task's gravity,
  with the wrench of a follow goal applied at the TCP during that goal.
* Goal-level constraints hold over the goal's own window (pause/follow: [t_g − duration, t_g];
  leave: [t_g, t_g + duration]; at/reach/returnTo: the instant t_g), not from t = 0 as in the reference.
* Moving obstacles (task extension): at each sample an obstacle is at its pose in effect at that time
  (zero-order hold) and stays there over the motion to the next sample.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

import numpy as np

from robodesign.core.errors import AssemblyError
from robodesign.formats.costs import CostContext, CostFunction, MissingQuantityError, named_costs, parse_cost
from robodesign.formats.solution import Solution
from robodesign.formats.task_spec import (
    AllGoalsFulfilled,
    BasePlacement,
    CollisionFree,
    EndEffectorConstraint,
    Goal,
    GoalsInOrder,
    JointLimitsConstraint,
    SelfCollisionFree,
    Task,
    TaskConstraint,
    describe_pose_violations,
)
from robodesign.judge import robots as judge_robots
from robodesign.judge.arc_torques import MAX_DEPTH, arc_torque_steps, certify_arc_torques
from robodesign.judge.motion import StepMotion
from robodesign.judge.quantities import TrajectoryQuantities
from robodesign.model.cell import moving_obstacle_events, moving_obstacle_indices
from robodesign.model.sweep import CollisionEvent, SweepChecker

LIMIT_RTOL = 1e-9  # relative slack on velocity/acceleration/torque limits (float round-off)
Q_ATOL = 1e-9  # absolute slack on position limits [rad or m]
T0_ATOL = 1e-9  # t[0] must be 0 within this [s]
STEP_ATOL = 1e-9  # a step may exceed the task's time step by this (the reference's epsilon) [s]


@dataclass
class Violation:
    constraint: str  # e.g. "joint.q", "collisionFree", "goal", "basePlacement"
    message: str
    goal: Optional[str] = None
    sample: Optional[int] = None
    time: Optional[float] = None
    value: Optional[float] = None
    bound: Optional[float] = None
    joint: Optional[int] = None

    def to_json(self) -> dict:
        """Strict JSON: a non-finite number becomes the string "inf", "-inf" or "nan"."""
        return {k: _num(v) if isinstance(v, float) else v for k, v in self.__dict__.items() if v is not None}

    def __str__(self) -> str:
        where = []
        if self.goal is not None:
            where.append(f"goal {self.goal}")
        if self.time is not None:
            where.append(f"t={self.time:.4f}s")
        if self.sample is not None:
            where.append(f"sample {self.sample}")
        if self.joint is not None:
            where.append(f"joint {self.joint}")
        return f"[{self.constraint}] {', '.join(where)}: {self.message}" if where else f"[{self.constraint}] {self.message}"


@dataclass
class Verdict:
    valid: bool
    violations: List[Violation]
    costs: Dict[str, float]
    cost: Optional[float]
    cost_function: str
    goals: Dict[str, bool] = field(default_factory=dict)
    timings: Dict[str, float] = field(default_factory=dict)
    samples: int = 0

    def to_json(self) -> dict:
        return {"valid": self.valid, "violations": [v.to_json() for v in self.violations],
                "costs": {k: _num(v) for k, v in self.costs.items()}, "cost": _num(self.cost),
                "costFunction": self.cost_function, "goals": self.goals, "samples": self.samples,
                "timings": self.timings}


def _num(v):
    """A number for strict JSON: None stays None, a non-finite float becomes "inf", "-inf" or "nan"."""
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else str(v)


@dataclass
class CheckSettings:
    max_violations_per_constraint: int = 20
    between_samples: bool = True  # certify collision freedom and joint limits between samples
    one_motion: bool = True  # the samples must describe a motion within the acceleration limits (judge.motion)
    all_costs: bool = True  # compute every built-in cost, not only the solution's


def check(task: Task, solution: Solution, module_set=None, settings: Optional[CheckSettings] = None,
          cost: Optional[CostFunction] = None) -> Verdict:
    """Judge ``solution`` on ``task``. Bad input (unknown module set, malformed data) raises InputError;
    everything else — including an invalid assembly — is a violation in the verdict. ``cost``: the solution's
    cost function as the object the caller already has (the solve pipeline's); without it the solution's
    ``costFunction`` text is parsed, once (an upload, a file)."""
    if cost is not None and solution.cost_function not in (str(cost), cost.descriptor()):
        raise ValueError(f"the cost {cost} given to check is not the solution's costFunction "
                         f"{solution.cost_function!r}")
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # huge values: inf/nan, reported as such
        return _check(task, solution, module_set, settings, cost)


def _check(task: Task, solution: Solution, module_set, settings: Optional[CheckSettings],
           given: Optional[CostFunction] = None) -> Verdict:
    settings = settings or CheckSettings()
    timings: Dict[str, float] = {}
    t0 = time.perf_counter()
    violations: List[Violation] = []
    cost_fn = given if given is not None else parse_cost(solution.cost_function, file=solution.source,
                                                         path=["costFunction"])
    tr = solution.trajectory
    if solution.task_id != task.id:
        violations.append(Violation("taskID", f"solution is for task {solution.task_id!r}, not {task.id!r}"))
    try:
        robot = judge_robots.take(task, solution, module_set)
    except AssemblyError as e:
        violations.append(Violation("validAssembly", str(e)))
        return Verdict(False, violations, {}, None, cost_fn.descriptor(), samples=tr.n)
    verdict = _judge(task, solution, robot, settings, cost_fn, violations, timings, t0)
    judge_robots.give_back(task, robot)
    return verdict


def _judge(task: Task, solution: Solution, robot, settings: CheckSettings, cost_fn: CostFunction,
           violations: List[Violation], timings: Dict[str, float], t0: float) -> Verdict:
    """:func:`check` with the solution's robot (``violations`` and ``timings`` so far, the check's start t0)."""
    tr = solution.trajectory
    if tr.q.shape[1] != robot.dof:
        violations.append(Violation("trajectory", f"q has {tr.q.shape[1]} columns but the robot has {robot.dof} joints"))
        return Verdict(False, violations, {}, None, cost_fn.descriptor(), samples=tr.n)
    timings["model"] = time.perf_counter() - t0
    tq = TrajectoryQuantities.from_solution(robot, solution, task)
    t1 = time.perf_counter()
    goal_ok: Dict[str, bool] = {}
    goal_viol: List[Violation] = []
    for g in task.goals:
        vs = check_goal(g, tq)
        goal_ok[g.id] = not vs
        goal_viol += vs
    timings["goals"] = time.perf_counter() - t1
    t1 = time.perf_counter()
    limit = settings.max_violations_per_constraint
    for c in task.constraints:
        violations += _check_constraint(c, tq, None, settings)[: limit]
    violations += _time_violations(tq, task.dt)
    if settings.one_motion:
        violations += _motion_violations(tq, limit)
    # goal-level constraints (over each goal's window)
    for g in task.goals:
        if not g.constraints or g.id not in tq.goal_windows:
            continue
        for c in g.constraints:
            vs = _check_constraint(c, tq, tq.goal_windows[g.id], settings)
            if vs:
                goal_ok[g.id] = False
                for v in vs[:limit]:
                    v.goal = g.id
                    goal_viol.append(v)
    timings["constraints"] = time.perf_counter() - t1
    has_all_goals = any(isinstance(c, AllGoalsFulfilled) for c in task.constraints)
    if has_all_goals:
        violations += goal_viol
    else:
        # goals only count through allGoalsFulfilled (as in the reference); report them as notes
        for v in goal_viol:
            v.constraint = "goal (not required)"
    order_c = [c for c in task.constraints if isinstance(c, GoalsInOrder)]
    for c in order_c:
        violations += _check_order(c, tr.goal2time)
    t1 = time.perf_counter()
    costs, cost = _costs(task, robot, tr, tq, settings, cost_fn, sum(goal_ok.values()))
    if not math.isfinite(cost):
        violations.append(Violation("cost", f"the cost {cost_fn.descriptor()} evaluates to {cost} (not a finite "
                                            "number: a weight or a value overflows)", value=cost))
    timings["costs"] = time.perf_counter() - t1
    timings["total"] = time.perf_counter() - t0
    real = [v for v in violations if v.constraint != "goal (not required)"]
    return Verdict(valid=not real, violations=real + [v for v in violations if v not in real], costs=costs, cost=cost,
                   cost_function=cost_fn.descriptor(), goals=goal_ok, timings=timings, samples=tr.n)


def _costs(task: Task, robot, tr, tq: TrajectoryQuantities, settings: CheckSettings, cost_fn: CostFunction,
           n_ok: int) -> Tuple[Dict[str, float], float]:
    """The solution's cost, and every named cost with ``settings.all_costs``. → (named costs, the cost)."""
    if settings.one_motion and tr.n >= 2:  # costs on the judged motion, not on the file's dq/ddq (docs/checker.md)
        cctx = CostContext(t=tr.t, q=tr.q, dq=tq.velocities, ddq=tq.motion_accelerations,
                           tau=lambda: tq.motion_drivetrain_torques, tau_link=lambda: tq.motion_link_torques,
                           mass=robot.mass, num_joints=robot.dof, goals_achieved=n_ok, num_goals=len(task.goals))
    else:
        cctx = CostContext(t=tr.t, q=tr.q, dq=tr.dq, ddq=tr.ddq, tau=lambda: tq.torques,
                           tau_link=lambda: tq.link_torques, mass=robot.mass, num_joints=robot.dof,
                           goals_achieved=n_ok, num_goals=len(task.goals))
    costs: Dict[str, float] = {}
    if settings.all_costs:
        for name, cf in named_costs().items():
            try:
                costs[name] = float(cf.evaluate(cctx))
            except MissingQuantityError:  # a plugin term that needs what a check does not provide
                continue
    return costs, float(cost_fn.evaluate(cctx))


# ---------------------------------------------------------------------------------------------
# constraints
# ---------------------------------------------------------------------------------------------
def _limit_violations(name, values, bound, tq: TrajectoryQuantities, k0: int, k1: int, limit: int, lower=None,
                      abs_tol=0.0) -> List[Violation]:
    """Samples k0..k1 (inclusive) of ``values`` (the whole trajectory, (N, dof)) outside the limits."""
    vals = values[k0:k1 + 1]
    if lower is None:
        over = np.abs(vals) > bound * (1 + LIMIT_RTOL) + abs_tol
    else:
        over = (vals < lower - abs_tol) | (vals > bound + abs_tol)
    ks, js = np.nonzero(over)
    out = []
    for k, j in list(zip(ks, js))[:limit]:
        kk = int(k + k0)
        v = float(values[kk, j])
        if lower is None:
            out.append(Violation(name, f"|{name.split('.')[-1]}| = {abs(v):.6g} exceeds the limit {bound[j]:.6g}",
                                 sample=kk, time=float(tq.t[kk]), value=v, bound=float(bound[j]), joint=int(j)))
        else:
            b = float(lower[j]) if v < lower[j] else float(bound[j])
            out.append(Violation(name, f"q = {v:.6g} outside [{lower[j]:.6g}, {bound[j]:.6g}]", sample=kk,
                                 time=float(tq.t[kk]), value=v, bound=b, joint=int(j)))
    if len(ks) > limit:
        out.append(Violation(name, f"... and {len(ks) - limit} more samples over the limit"))
    return out


def _motion_violations(tq: TrajectoryQuantities, limit: int) -> List[Violation]:
    """Joints through whose samples no motion within the acceleration limit passes (judge.motion)."""
    fail = tq.motion_failures
    if fail is None:
        return []
    out = []
    A = tq.acceleration_bound
    raw = StepMotion.through(tq.t, tq.q, tq.dq).peak_acceleration
    for j in np.nonzero(fail >= 0)[0][:limit]:
        k, j = int(fail[j]), int(j)
        out.append(Violation("trajectory.motion",
                             f"no motion within the acceleration {A[j]:.6g} passes through samples {k} and "
                             f"{k + 1} (with the file's velocities q, dq need {raw[k, j]:.6g} between them, and no "
                             f"velocities within the slack A·h/2 of dq fit)", sample=k, time=float(tq.t[k]),
                             value=float(raw[k, j]), bound=float(A[j]), joint=j))
    return out


def _time_violations(tq: TrajectoryQuantities, dt: float) -> List[Violation]:
    """``t`` starts at 0 and no step is longer than the task's time step (the reference's rule)."""
    out = []
    t = tq.t
    if abs(t[0]) > T0_ATOL:
        out.append(Violation("trajectory.t", f"the trajectory must start at t = 0, not {t[0]:.9g}", sample=0,
                             time=float(t[0]), value=float(t[0]), bound=0.0))
    if tq.n >= 2:
        h = np.diff(t)
        long_ = np.nonzero(h > dt + STEP_ATOL)[0]
        if len(long_):
            k = int(long_[0])
            out.append(Violation("trajectory.t", f"the step from sample {k} to {k + 1} is {h[k]:.9g} s, longer than "
                                 f"the task's time step {dt:g} s (the solution must be sampled every timeStepSize; "
                                 f"{len(long_)} such steps)", sample=k, time=float(t[k]), value=float(h[k]),
                                 bound=float(dt)))
    return out


def _between_sample_violations(name, extremes, bound, tq: TrajectoryQuantities, k0: int, k1: int,
                               limit: int, lower=None) -> List[Violation]:
    """Steps k0 → k0+1 … k1−1 → k1 over which the motion leaves the limits: ``extremes`` is (|value| max, time in
    step) or, with ``lower``, (min, time, max, time), arrays (N−1, dof)."""
    if lower is None:
        vals, when = extremes[0][k0:k1], extremes[1][k0:k1]
        over = vals > bound * (1 + LIMIT_RTOL)
    else:
        mn, tmn, mx, tmx = (x[k0:k1] for x in extremes)
        over = (mn < lower - Q_ATOL) | (mx > bound + Q_ATOL)
    ks, js = np.nonzero(over)
    out = []
    what = name.split(".")[-1]
    for k, jk in list(zip(ks, js))[:limit]:
        kk, j = int(k + k0), int(jk)
        if lower is None:
            v, tt, b = float(vals[k, j]), float(tq.t[kk] + when[k, j]), float(bound[j])
            msg = f"|{what}| = {v:.6g} between samples {kk} and {kk + 1} exceeds the limit {b:.6g}"
        else:
            low = mn[k, j] < lower[j] - Q_ATOL
            v = float(mn[k, j] if low else mx[k, j])
            tt = float(tq.t[kk] + (tmn[k, j] if low else tmx[k, j]))
            b = float(lower[j] if low else bound[j])
            msg = f"q = {v:.6g} between samples {kk} and {kk + 1} outside [{lower[j]:.6g}, {bound[j]:.6g}]"
        out.append(Violation(name, msg + f" (at t={tt:.4f}s)", sample=kk, time=tt, value=v, bound=b, joint=j))
    if len(ks) > limit:
        out.append(Violation(name, f"... and {len(ks) - limit} more steps over the limit"))
    return out


def _arc_torque_violations(tq: TrajectoryQuantities, k0: int, k1: int, limit: int,
                           at_samples: List[Violation]) -> List[Violation]:
    """Torques on the judged motion between samples k0 … k1 (judge.arc_torques), except on steps whose samples
    already violate the torque limit for the same joint."""
    r = tq.robot
    steps = arc_torque_steps(tq.n, k0, k1)
    skip = np.zeros((max(tq.n - 1, 0), r.dof), dtype=bool)
    for v in at_samples:
        if v.constraint == "joint.tau" and v.joint is not None and v.sample is not None:
            skip[max(v.sample - 1, 0):v.sample + 1, v.joint] = True
    rep = certify_arc_torques(r, tq.motion, tq.external_wrenches, steps, r.tau_max * (1 + LIMIT_RTOL), skip=skip,
                              sample_torques=tq.motion_torques)
    out = []
    for a in rep.violations[:limit]:
        b = float(r.tau_max[a.joint])
        where = f"between samples {a.step} and {a.step + 1} (at t={a.time:.4f}s)"
        if not math.isfinite(a.value):
            msg = f"|tau| {where} is not a finite number on the judged motion ({a.value})"
        elif a.certified_over:
            msg = f"|tau| = {abs(a.value):.6g} {where} exceeds the limit {b:.6g} on the judged motion"
        else:
            msg = (f"|tau| {where} could not be certified within the limit {b:.6g} (bound {abs(a.value):.6g} on the "
                   f"smallest piece bounded, at most h/2^{MAX_DEPTH})")
        out.append(Violation("joint.tau", msg, sample=a.step, time=a.time, value=a.value, bound=b, joint=a.joint))
    if len(rep.violations) > limit:
        out.append(Violation("joint.tau", f"... and {len(rep.violations) - limit} more steps over the limit"))
    return out


def _new_steps(at_samples: List[Violation], between: List[Violation]) -> List[Violation]:
    """``between`` without the steps that start or end at a sample already in ``at_samples`` (same joint)."""
    seen = {(v.sample, v.joint) for v in at_samples if v.joint is not None}
    return [v for v in between
            if v.joint is None or v.sample is None or not ({(v.sample, v.joint), (v.sample + 1, v.joint)} & seen)]


def _check_constraint(c: TaskConstraint, tq: TrajectoryQuantities, window, settings: CheckSettings) -> List[Violation]:
    """Violations of ``c`` over the samples of ``window`` ((k0, k1) inclusive; None: the whole trajectory)."""
    r = tq.robot
    k0, k1 = (0, tq.n - 1) if window is None else window
    sl = slice(k0, k1 + 1)
    limit = settings.max_violations_per_constraint
    if isinstance(c, JointLimitsConstraint):
        out = []
        m = tq.motion if settings.between_samples and tq.n >= 2 else None
        if "q" in c.parts:
            out += _limit_violations("joint.q", tq.q, r.q_upper, tq, k0, k1, limit, lower=r.q_lower, abs_tol=Q_ATOL)
            if m is not None:
                out += _new_steps(out, _between_sample_violations("joint.q", m.position_extremes(), r.q_upper, tq,
                                                                  k0, k1, limit, lower=r.q_lower))
        if "dq" in c.parts:
            out += _limit_violations("joint.dq", tq.dq, r.dq_max, tq, k0, k1, limit)
            if m is not None:
                out += _new_steps(out, _between_sample_violations("joint.dq", m.velocity_extremes(), r.dq_max, tq,
                                                                  k0, k1, limit))
        if "ddq" in c.parts:
            out += _limit_violations("joint.ddq", tq.ddq, r.ddq_max, tq, k0, k1, limit)
        if "tau" in c.parts:
            out += _limit_violations("joint.tau", tq.torques, r.tau_max, tq, k0, k1, limit)
            if m is not None:
                seen = {(v.sample, v.joint) for v in out if v.constraint == "joint.tau"}
                for side, tau in zip(("before", "after"), tq.motion_torques):
                    vs = [v for v in _limit_violations("joint.tau", tau, r.tau_max, tq, k0, k1, limit)
                          if v.joint is None or (v.sample, v.joint) not in seen]
                    for v in vs:
                        if v.joint is not None:
                            seen.add((v.sample, v.joint))
                            v.message += f" (with the motion's acceleration just {side} the sample)"
                    out += vs
                out += _arc_torque_violations(tq, k0, k1, limit, out)
        return out
    if isinstance(c, (CollisionFree, SelfCollisionFree)):
        return _collision_violations(c, tq, k0, k1, settings)
    if isinstance(c, BasePlacement):
        if c.pose is None or c.pose.valid(r.base_pose):
            return []
        return [Violation("basePlacement",
                          "base pose outside its tolerance: " + describe_pose_violations(c.pose.violations(r.base_pose)))]
    if isinstance(c, EndEffectorConstraint):
        out = []
        if math.isfinite(c.v_max) or c.v_min > 0 or math.isfinite(c.o_max) or c.o_min > 0:
            tw = tq.tcp_twists[sl]
            v = np.linalg.norm(tw[:, :3], axis=1)
            o = np.linalg.norm(tw[:, 3:], axis=1)
            for name, vals, lo, hi in (("v", v, c.v_min, c.v_max), ("o", o, c.o_min, c.o_max)):
                bad = np.nonzero((vals < lo * (1 - LIMIT_RTOL)) | (vals > hi * (1 + LIMIT_RTOL)))[0]
                for k in bad[:limit]:
                    kk = int(k + k0)
                    out.append(Violation("endEffector." + name, f"TCP {'speed' if name == 'v' else 'angular speed'} "
                                         f"{vals[k]:.6g} outside [{lo:.6g}, {hi:.6g}]", sample=kk,
                                         time=float(tq.t[kk]), value=float(vals[k]),
                                         bound=float(hi if vals[k] > hi else lo)))
        if c.pose is not None:
            T = tq.tcp_poses
            outside = [k for k in range(k0, k1 + 1) if not c.pose.valid(T[k])]
            for k in outside[:limit]:
                out.append(Violation("endEffector.pose", "TCP pose outside the tolerance: " +
                                     describe_pose_violations(c.pose.violations(T[k])), sample=k, time=float(tq.t[k])))
        return out
    # allGoalsFulfilled, order, validAssembly, alwaysTrue are handled elsewhere / always true
    return []


def _collision_violations(c, tq: TrajectoryQuantities, k0: int, k1: int, settings: CheckSettings) -> List[Violation]:
    r = tq.robot
    env = isinstance(c, CollisionFree)
    Q = tq.q[k0:k1 + 1]
    task = tq.task
    moving = moving_obstacle_indices(r, task) if env and task is not None else []  # no task: no moving obstacles
    path = at = None  # the judged motion between samples (None: the chord)
    if settings.between_samples and settings.one_motion and len(Q) >= 2:
        m = tq.motion
        path, at = m.path_bound()[k0:k1], (lambda k, s: m.at(k + k0, s))
    # the self pairs' sweep is shared by selfCollisionFree and collisionFree; pairs with moving obstacles are
    # checked piecewise (cell.moving_obstacle_events), the static ones in the sweep
    if settings.between_samples:
        events = _sweep_events(tq, k0, k1, False, path, at)
        if env:
            events = sorted(events + _sweep_events(tq, k0, k1, True, path, at), key=lambda e: (e.sample, e.s))
    else:  # one event per sample in contact
        hits = _sweep_events(tq, k0, k1, False, None, None, samples_only=True)
        if env:
            hits = hits | _sweep_events(tq, k0, k1, True, None, None, samples_only=True)
        events = [CollisionEvent(int(k), 0.0, "", "", 0.0, env) for k in np.nonzero(hits)[0]]
    if moving and task is not None:
        events = sorted(events + moving_obstacle_events(r, task, moving, tq.t[k0:k1 + 1], Q,
                                                        between_samples=settings.between_samples,
                                                        path=path, at=at),
                        key=lambda e: (e.sample, e.s))
    limit = settings.max_violations_per_constraint
    out = []
    for e in events[:limit]:
        k = e.sample + k0
        tt = float(tq.t[k] + e.s * (tq.t[min(k + 1, tq.n - 1)] - tq.t[k]))
        kind = "robot–obstacle" if e.environment else "self"
        between = f" between samples {k} and {k + 1}" if e.s > 0 else ""
        margin = r.safety_margin if e.environment else 0.0
        out.append(Violation(c.type, f"{kind} collision {e.first} ↔ {e.second}{between} "
                                     f"(distance {e.distance:.4g} m, margin {margin:.3g})",
                             sample=k, time=tt, value=e.distance))
    if len(events) > limit:
        out.append(Violation(c.type, f"... and {len(events) - limit} more collisions"))
    return out


def _sweep_events(tq: TrajectoryQuantities, k0: int, k1: int, env: bool, path, at, samples_only: bool = False):
    """Collision events over samples k0 … k1 of the self pairs (``env`` False) or of the pairs with the static
    obstacles (True), each computed once per trajectory and window; one SweepChecker (its bounds) serves both.
    Each pair is certified on its own (SweepChecker.check), so the events of the two sets, merged by (sample,
    s), are those of one sweep over all pairs. ``samples_only``: per sample, in contact (no motion between)."""
    cache = tq.judge_cache
    key = ("sweep", k0, k1, env, samples_only, path is None)
    if key in cache:
        return cache[key].copy()
    if "checker" not in cache:
        r = tq.robot
        moving = set(moving_obstacle_indices(r, tq.task)) if tq.task is not None else set()
        static = [i for i in range(len(r.obstacles)) if i not in moving] if moving else None
        cache["checker"] = SweepChecker(r, check_self=True, check_env=True, obstacles=static, posed_arms=True,
                                        scratch=judge_robots.scratch(r))
    full: SweepChecker = cache["checker"]
    n_self = tq.robot.n_self_collision_pairs
    checker = full.subset(range(n_self, len(full.pairs)) if env else range(n_self))
    Q = tq.q[k0:k1 + 1]
    poses = tq.joint_poses if (k0, k1) == (0, tq.n - 1) else None  # (a window's: the sweep's own pass over it)
    out = checker.sample_collisions(Q) if samples_only else checker.check(Q, first_only=False, path=path, at=at,
                                                                          poses=poses)
    cache[key] = out
    return out.copy()


def _check_order(c: GoalsInOrder, g2t: Dict[str, float]) -> List[Violation]:
    missing = [g for g in c.order if g not in g2t]
    if missing:
        return [Violation("allGoalsFulfilledInOrder", f"goals {missing} have no goal2time entry")]
    actual = sorted(c.order, key=lambda g: g2t[g])
    if list(actual) != list(c.order):
        return [Violation("allGoalsFulfilledInOrder", f"goals reached in order {actual}, required {list(c.order)}")]
    return []


# ---------------------------------------------------------------------------------------------
# goals
# ---------------------------------------------------------------------------------------------
def check_goal(g: Goal, tq: TrajectoryQuantities) -> List[Violation]:
    """Why goal ``g`` is not achieved by the trajectory (empty: achieved), as the goal's own
    :meth:`~robodesign.formats.task_spec.Goal.check` says. Goal-level constraints are checked separately,
    over :attr:`TrajectoryQuantities.goal_windows`."""
    g2t = tq.goal2time
    if g.id not in g2t:
        return [Violation("goal", f"{g.type} goal has no entry in goal2time", goal=g.id)]
    tg = g2t[g.id]
    k = tq.goal_sample(g.id)
    if k is None:
        return [Violation("goal", f"no unique sample at the goal time {tg}", goal=g.id, time=tg)]

    def violation(message: str, **kw) -> Violation:
        return Violation("goal", message, goal=g.id, time=kw.pop("time", float(tq.t[k])), **kw)
    return g.check(tq, k, violation)
