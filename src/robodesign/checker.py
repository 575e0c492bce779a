"""The judge: does a solution solve a task, and what does it cost?

``check(task, solution, module_set)`` returns a :class:`Verdict` with every violation (which
constraint or goal, at which time/sample, the value and the bound) and every cost. The same code
judges uploads, solver output and optimizer candidates. Semantics (docs/checker.md):

* Per-sample constraints are checked at every sample. Collisions are checked *between* samples too:
  the motion between samples is the linear interpolation of q, certified by :mod:`robodesign.sweep`.
* ``ddq`` limits are enforced (the reference never checks them).
* Torques are drivetrain torques τ = RNEA + k²I_m q̈ + f_v q̇ + f_c σ(q̇) under the task's gravity,
  with the wrench of a follow goal applied at the TCP during that goal.
* Goal-level constraints hold over the goal's own window (pause/follow: [t_g − duration, t_g];
  leave: [t_g, t_g + duration]; at/reach/returnTo: the instant t_g), not from t = 0 as in the reference.
* Moving obstacles (task extension): at each sample an obstacle is at its pose in effect at that time
  (zero-order hold) and stays there over the motion to the next sample.
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

import numpy as np
import pinocchio as pin

from .assembly import Assembly
from .costs import CostContext, parse_cost
from .errors import AssemblyError, InputError
from .geometry import coal_shapes
from .module_io import load_module_set
from .module_spec import ModuleSet
from .robot import Obstacle, Robot
from .solution import Solution
from .sweep import SweepChecker
from .task_spec import (AllGoalsFulfilled, At, BasePlacement, CollisionFree, Constraint, EndEffectorConstraint,
                        Follow, Goal, GoalsInOrder, JointLimitsConstraint, Leave, Pause, Reach, ReturnTo,
                        SelfCollisionFree, Task)

LIMIT_RTOL = 1e-9  # relative slack on velocity/acceleration/torque limits (float round-off)
Q_ATOL = 1e-9  # absolute slack on position limits [rad or m]
TIME_ATOL = 1e-8
TIME_RTOL = 1e-5
ALL_COSTS = ("cyc", "mechEnergy", "linkMechEnergy", "qDist", "effort", "mass", "numJ", "fulfillN", "fulfillP",
             "Liu2", "Whit2")


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
        return {k: (None if isinstance(v, float) and not math.isfinite(v) and k != "value" else v)
                for k, v in self.__dict__.items() if v is not None}

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


def _describe(violations) -> str:
    """``[(projection, value, lo, hi)]`` of a tolerated pose → readable text."""
    return "; ".join(f"{p} = {val:.6g} not in [{lo:.6g}, {hi:.6g}]" for p, val, lo, hi in violations)


def _num(v):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return None
    return float(v)


@dataclass
class CheckSettings:
    max_violations_per_constraint: int = 20
    between_samples: bool = True  # certify collision freedom between samples
    all_costs: bool = True  # compute every built-in cost, not only the solution's


def resolve_module_set(solution: Solution, module_set=None) -> ModuleSet:
    if isinstance(module_set, ModuleSet):
        return module_set
    name = module_set or solution.module_set
    if not name:
        raise InputError("the solution names no moduleSet; pass --modules", file=solution.source or "solution")
    return load_module_set(name)


def task_obstacles(task: Task, t: float = 0.0) -> List[Obstacle]:
    out = []
    for ob in task.obstacles:
        M = ob.transform_at(t)
        for gi, g in enumerate(ob.collision):
            for si, shape in enumerate(coal_shapes(g)):
                out.append(Obstacle(f"{ob.id}.{gi}.{si}", shape, M @ g.pose))
    return out


def build_robot(task: Task, ms: ModuleSet, assembly: Assembly, base_pose: np.ndarray) -> Robot:
    """The robot in the task's cell: base pose, the task's gravity, obstacles with the safety margin."""
    robot = Robot(ms, assembly, base_pose=base_pose, gravity=task.header.gravity)
    margin = max([c.safety_margin for c in task.constraints if isinstance(c, CollisionFree)], default=0.0)
    robot.set_obstacles(task_obstacles(task), safety_margin=margin)
    return robot


def find_time_index(t: np.ndarray, value: float) -> Optional[int]:
    """The unique sample at ``value`` (numpy.isclose rule of the reference), else None."""
    close = np.nonzero(np.isclose(t, value, rtol=TIME_RTOL, atol=TIME_ATOL))[0]
    return int(close[0]) if len(close) == 1 else None


class _Context:
    """Per-check cache of kinematic quantities along the trajectory."""

    def __init__(self, robot: Robot, task: Task, sol: Solution):
        self.robot, self.task, self.sol = robot, task, sol
        tr = sol.trajectory
        self.t, self.q, self.dq, self.ddq = tr.t, tr.q, tr.dq, tr.ddq
        self._tcp = None
        self._twist = None
        self._tau = None
        self._tau_link = None
        self.f_ext_windows: List[Tuple[int, int, np.ndarray]] = []  # (k0, k1, wrench world [f; τ] at TCP)

    @property
    def n(self) -> int:
        return len(self.t)

    def tcp(self) -> np.ndarray:
        if self._tcp is None:
            r = self.robot
            out = np.empty((self.n, 4, 4))
            for k in range(self.n):
                pin.framesForwardKinematics(r.model, r.data, self.q[k])
                out[k] = r.data.oMf[r.tcp_frame].homogeneous
            self._tcp = out
        return self._tcp

    def tcp_at(self, time_: float) -> np.ndarray:
        """TCP pose at any time (linear interpolation of q between samples)."""
        return self.robot.fk(self.q_at(time_))

    def q_at(self, time_: float) -> np.ndarray:
        return np.array([np.interp(time_, self.t, self.q[:, j]) for j in range(self.q.shape[1])])

    def twist(self) -> np.ndarray:
        if self._twist is None:
            r = self.robot
            out = np.empty((self.n, 6))
            for k in range(self.n):
                pin.forwardKinematics(r.model, r.data, self.q[k], self.dq[k])
                pin.updateFramePlacements(r.model, r.data)
                out[k] = pin.getFrameVelocity(r.model, r.data, r.tcp_frame, pin.LOCAL_WORLD_ALIGNED).vector
            self._twist = out
        return self._twist

    def _fext(self, k: int):
        for k0, k1, w in self.f_ext_windows:
            if k0 <= k <= k1:
                return self._wrench_to_joints(k, w)
        return None

    def _wrench_to_joints(self, k: int, w: np.ndarray):
        """The world wrench w = [f; τ] acting at the TCP as pinocchio joint-frame forces."""
        r = self.robot
        pin.framesForwardKinematics(r.model, r.data, self.q[k])
        fr = r.model.frames[r.tcp_frame]
        jid = fr.parentJoint
        oMi = r.data.oMi[jid]
        p_tcp = r.data.oMf[r.tcp_frame].translation
        f, tau = np.asarray(w[:3], dtype=float), np.asarray(w[3:], dtype=float)
        # the force acts at the TCP point: about the joint origin it adds the moment (p_tcp − p_joint) × f;
        # then both are expressed in the joint frame, as pinocchio's external forces are
        moment = tau + np.cross(p_tcp - oMi.translation, f)
        fext = pin.StdVec_Force()
        for _ in range(r.model.njoints):
            fext.append(pin.Force.Zero())
        # an external force on the body: RNEA subtracts it, so the joints see −Jᵀw (they resist the push)
        fext[jid] = pin.Force(oMi.rotation.T @ f, oMi.rotation.T @ moment)
        return fext

    def taus(self) -> Tuple[np.ndarray, np.ndarray]:
        if self._tau is None:
            r = self.robot
            N, dof = self.q.shape
            tau_link = np.empty((N, dof))
            for k in range(N):
                fext = self._fext(k)
                if fext is None:
                    tau_link[k] = pin.rnea(r.model, r.data, self.q[k], self.dq[k], self.ddq[k])
                else:
                    tau_link[k] = pin.rnea(r.model, r.data, self.q[k], self.dq[k], self.ddq[k], fext)
            arm = r.model.armature * self.ddq
            self._tau_link = tau_link - arm
            from .robot import smooth_sign
            self._tau = tau_link + r.friction_viscous * self.dq + r.friction_coulomb * smooth_sign(self.dq)
        return self._tau, self._tau_link


def check(task: Task, solution: Solution, module_set=None, settings: Optional[CheckSettings] = None) -> Verdict:
    """Judge ``solution`` on ``task``. Bad input (unknown module set, malformed data) raises InputError;
    everything else — including an invalid assembly — is a violation in the verdict."""
    settings = settings or CheckSettings()
    timings: Dict[str, float] = {}
    t0 = time.perf_counter()
    violations: List[Violation] = []
    cost_fn = parse_cost(solution.cost_function, file=solution.source, path=["costFunction"])
    tr = solution.trajectory
    if solution.task_id != task.id:
        violations.append(Violation("taskID", f"solution is for task {solution.task_id!r}, not {task.id!r}"))
    ms = resolve_module_set(solution, module_set)
    try:
        asm = solution.assembly(ms)
    except AssemblyError as e:
        violations.append(Violation("validAssembly", str(e)))
        return Verdict(False, violations, {}, None, cost_fn.descriptor(), samples=tr.n)
    robot = build_robot(task, ms, asm, solution.base_pose)
    if tr.q.shape[1] != robot.dof:
        violations.append(Violation("trajectory", f"q has {tr.q.shape[1]} columns but the robot has {robot.dof} joints"))
        return Verdict(False, violations, {}, None, cost_fn.descriptor(), samples=tr.n)
    timings["model"] = time.perf_counter() - t0
    ctx = _Context(robot, task, solution)
    # goals first: follow goals define external-force windows used by the torque checks
    t1 = time.perf_counter()
    goal_ok: Dict[str, bool] = {}
    goal_viol: List[Violation] = []
    windows: Dict[str, Tuple[int, int]] = {}
    for g in task.goals:
        ok, vs, win = _check_goal(g, ctx, tr.goal2time)
        windows[g.id] = win if win is not None else (-1, -1)
        goal_ok[g.id] = ok
        goal_viol += vs
    timings["goals"] = time.perf_counter() - t1
    t1 = time.perf_counter()
    limit = settings.max_violations_per_constraint
    for c in task.constraints:
        violations += _check_constraint(c, ctx, None, settings)[: limit]
    # goal-level constraints (over each goal's window)
    for g in task.goals:
        if not g.constraints or g.id not in tr.goal2time or windows[g.id][0] < 0:
            continue
        for c in g.constraints:
            vs = _check_constraint(c, ctx, windows[g.id], settings)
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
    n_ok = sum(goal_ok.values())
    tau_fn = lambda: ctx.taus()[0]
    tau_link_fn = lambda: ctx.taus()[1]
    cctx = CostContext(t=tr.t, q=tr.q, dq=tr.dq, ddq=tr.ddq, tau=tau_fn, tau_link=tau_link_fn, mass=robot.mass,
                       num_joints=robot.dof, goals_achieved=n_ok, num_goals=len(task.goals))
    costs: Dict[str, float] = {}
    if settings.all_costs:
        for name in ALL_COSTS:
            costs[name] = float(parse_cost(name).evaluate(cctx))
    cost = float(cost_fn.evaluate(cctx))
    timings["costs"] = time.perf_counter() - t1
    timings["total"] = time.perf_counter() - t0
    real = [v for v in violations if v.constraint != "goal (not required)"]
    return Verdict(valid=not real, violations=real + [v for v in violations if v not in real], costs=costs, cost=cost,
                   cost_function=cost_fn.descriptor(), goals=goal_ok, timings=timings, samples=tr.n)


# ---------------------------------------------------------------------------------------------
# constraints
# ---------------------------------------------------------------------------------------------
def _range(ctx, window):
    if window is None:
        return 0, ctx.n - 1
    return window


def _limit_violations(name, values, bound, ctx, k0, limit, lower=None, abs_tol=0.0) -> List[Violation]:
    out = []
    vals = values[k0:]
    if lower is None:
        over = np.abs(vals) > bound * (1 + LIMIT_RTOL) + abs_tol
    else:
        over = (vals < lower - abs_tol) | (vals > bound + abs_tol)
    ks, js = np.nonzero(over)
    for k, j in list(zip(ks, js))[:limit]:
        kk = int(k + k0)
        v = float(values[kk, j])
        if lower is None:
            out.append(Violation(name, f"|{name.split('.')[-1]}| = {abs(v):.6g} exceeds the limit {bound[j]:.6g}",
                                 sample=kk, time=float(ctx.t[kk]), value=v, bound=float(bound[j]), joint=int(j)))
        else:
            b = float(lower[j]) if v < lower[j] else float(bound[j])
            out.append(Violation(name, f"q = {v:.6g} outside [{lower[j]:.6g}, {bound[j]:.6g}]", sample=kk,
                                 time=float(ctx.t[kk]), value=v, bound=b, joint=int(j)))
    if len(ks) > limit:
        out.append(Violation(name, f"... and {len(ks) - limit} more samples over the limit"))
    return out


def _check_constraint(c: Constraint, ctx: _Context, window, settings: CheckSettings) -> List[Violation]:
    r = ctx.robot
    k0, k1 = _range(ctx, window)
    sl = slice(k0, k1 + 1)
    limit = settings.max_violations_per_constraint
    if isinstance(c, JointLimitsConstraint):
        out = []
        if "q" in c.parts:
            out += _limit_violations("joint.q", ctx.q[sl], r.q_upper, ctx, k0, limit, lower=r.q_lower, abs_tol=Q_ATOL)
        if "dq" in c.parts:
            out += _limit_violations("joint.dq", ctx.dq[sl], r.dq_max, ctx, k0, limit)
        if "ddq" in c.parts:
            out += _limit_violations("joint.ddq", ctx.ddq[sl], r.ddq_max, ctx, k0, limit)
        if "tau" in c.parts:
            out += _limit_violations("joint.tau", ctx.taus()[0][sl], r.tau_max, ctx, k0, limit)
        return out
    if isinstance(c, (CollisionFree, SelfCollisionFree)):
        env = isinstance(c, CollisionFree)
        Q = ctx.q[sl]
        checker = SweepChecker(r, check_self=True, check_env=env)
        moving = _moving_obstacle_pairs(r, ctx.task, checker) if env else None
        if moving is not None:  # pairs with moving obstacles are checked piecewise below
            _restrict_pairs(checker, ~moving)
        if settings.between_samples:
            events = checker.check(Q, first_only=False)
        else:
            hits = np.nonzero(checker.sample_collisions(Q))[0]
            from .sweep import CollisionEvent
            events = [CollisionEvent(int(k), 0.0, "", "", 0.0, env) for k in hits]
        if moving is not None:
            events = sorted(events + _moving_obstacle_events(r, ctx, k0, k1, moving, settings),
                            key=lambda e: (e.sample, e.s))
        out = []
        for e in events[:limit]:
            k = e.sample + k0
            tt = float(ctx.t[k] + e.s * (ctx.t[min(k + 1, ctx.n - 1)] - ctx.t[k]))
            kind = "robot–obstacle" if e.environment else "self"
            between = f" between samples {k} and {k + 1}" if e.s > 0 else ""
            out.append(Violation(c.type, f"{kind} collision {e.first} ↔ {e.second}{between} "
                                         f"(distance {e.distance:.4g} m, margin {getattr(r, 'safety_margin', 0.0) if e.environment else 0:.3g})",
                                 sample=k, time=tt, value=e.distance))
        if len(events) > limit:
            out.append(Violation(c.type, f"... and {len(events) - limit} more collisions"))
        return out
    if isinstance(c, BasePlacement):
        if c.pose is None or c.pose.valid(r.base_pose):
            return []
        v = c.pose.violations(r.base_pose)
        return [Violation("basePlacement", "base pose outside its tolerance: " +
                          _describe(v))]
    if isinstance(c, EndEffectorConstraint):
        out = []
        if math.isfinite(c.v_max) or c.v_min > 0 or math.isfinite(c.o_max) or c.o_min > 0:
            tw = ctx.twist()[sl]
            v = np.linalg.norm(tw[:, :3], axis=1)
            o = np.linalg.norm(tw[:, 3:], axis=1)
            for name, vals, lo, hi in (("v", v, c.v_min, c.v_max), ("o", o, c.o_min, c.o_max)):
                bad = np.nonzero((vals < lo * (1 - LIMIT_RTOL)) | (vals > hi * (1 + LIMIT_RTOL)))[0]
                for k in bad[:limit]:
                    kk = int(k + k0)
                    out.append(Violation("endEffector." + name, f"TCP {'speed' if name == 'v' else 'angular speed'} "
                                         f"{vals[k]:.6g} outside [{lo:.6g}, {hi:.6g}]", sample=kk,
                                         time=float(ctx.t[kk]), value=float(vals[k]),
                                         bound=float(hi if vals[k] > hi else lo)))
        if c.pose is not None:
            T = ctx.tcp()
            bad = [k for k in range(k0, k1 + 1) if not c.pose.valid(T[k])]
            for k in bad[:limit]:
                vv = c.pose.violations(T[k])
                out.append(Violation("endEffector.pose", "TCP pose outside the tolerance: " +
                                     _describe(vv),
                                     sample=k, time=float(ctx.t[k])))
        return out
    # allGoalsFulfilled, order, validAssembly, alwaysTrue are handled elsewhere / always true
    return []


def _moving_obstacle_pairs(robot: Robot, task: Task, checker: SweepChecker) -> Optional[np.ndarray]:
    """Mask over ``checker.pairs``: robot–obstacle pairs whose obstacle moves (None if nothing moves)."""
    if not any(ob.moving for ob in task.obstacles):
        return None
    moving_ids = {ob.id for ob in task.obstacles if ob.moving}
    n_robot = robot.n_collision_geometries
    geom_to_ob = {gk: robot.obstacles[i].name.rsplit(".", 2)[0] for i, gk in enumerate(robot._obstacle_ids)}
    mask = np.zeros(len(checker.pairs), dtype=bool)
    for c, k in enumerate(checker.pairs):
        b = robot.geom_model.collisionPairs[k].second
        mask[c] = b >= n_robot and geom_to_ob.get(b) in moving_ids
    return mask if mask.any() else None


def _restrict_pairs(checker: SweepChecker, keep: np.ndarray) -> None:
    idx = np.nonzero(keep)[0]
    checker.pairs = [checker.pairs[i] for i in idx]
    checker.W = checker.W[:, idx]
    checker.margins = checker.margins[idx]
    checker.is_env = checker.is_env[idx]
    checker._names = [checker._names[i] for i in idx]


def _moving_obstacle_events(robot: Robot, ctx: "_Context", k0: int, k1: int, moving: np.ndarray,
                            settings: CheckSettings):
    """Collisions with moving obstacles over samples k0..k1. An obstacle's pose is the one in effect at a
    sample's time (zero-order hold, ``ObstacleSpec.transform_at``) and is kept over the motion to the next
    sample; runs of samples with unchanged obstacle poses are certified together."""
    specs = {ob.id: ob for ob in ctx.task.obstacles if ob.moving}
    movers = []  # (robot obstacle index, spec, t=0 world pose of the geometry)
    for i, ob in enumerate(robot.obstacles):
        sid = ob.name.rsplit(".", 2)[0]
        if sid in specs:
            movers.append((i, specs[sid], np.array(ob.pose, dtype=float)))
    chk = SweepChecker(robot, check_self=False, check_env=True)
    _restrict_pairs(chk, moving[len(moving) - len(chk.pairs):])  # chk holds the env pairs (the tail)
    t = ctx.t
    keys = [tuple(int(np.searchsorted(sp.motion_t, t[k] + 1e-12, side="right")) for sp in specs.values())
            for k in range(k0, k1 + 1)]
    events = []
    last: Dict[tuple, int] = {}  # pair → last sample in contact (one event per pair and contact episode)
    a = 0
    try:
        while a < len(keys):
            b = a
            while b + 1 < len(keys) and keys[b + 1] == keys[a]:
                b += 1
            for i, sp, pose0 in movers:
                robot.move_obstacle(i, sp.transform_at(float(t[k0 + a])) @ pose0)
            if not settings.between_samples:
                from .sweep import CollisionEvent
                hits = np.nonzero(chk.sample_collisions(ctx.q[k0 + a:k0 + b + 1]))[0]
                events += [CollisionEvent(int(k + a), 0.0, "", "", 0.0, True) for k in hits]
                a = b + 1
                continue
            end = min(b + 1, len(keys) - 1)  # include the motion to the next sample (obstacle still here)
            Q = ctx.q[k0 + a:k0 + end + 1]
            evs = chk.check(Q, first_only=False)
            for e in evs:
                e = dataclasses.replace(e, sample=e.sample + a)
                pair = (e.first, e.second)
                if pair not in last or e.sample > last[pair] + 1:  # else: the episode of the previous run
                    events.append(e)
                last[pair] = e.sample
            for pair in {(e.first, e.second) for e in evs}:
                c = chk._names.index(pair)
                if chk._distances_at(Q[-1], [c])[0] <= chk.margins[c]:
                    last[pair] = end  # still in contact at the end of this run
            a = b + 1
    finally:
        for i, _, pose0 in movers:
            robot.move_obstacle(i, pose0)
    return events


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
def _check_goal(g: Goal, ctx: _Context, g2t: Dict[str, float]):
    """(achieved, violations, window (k0, k1) or None)."""
    if g.id not in g2t:
        return False, [Violation("goal", f"{g.type} goal has no entry in goal2time", goal=g.id)], None
    tg = g2t[g.id]
    k = find_time_index(ctx.t, tg)
    if k is None:
        return False, [Violation("goal", f"no unique sample at the goal time {tg}", goal=g.id, time=tg)], None
    V = lambda msg, **kw: Violation("goal", msg, goal=g.id, time=kw.pop("time", float(ctx.t[k])), **kw)
    if isinstance(g, (At, Reach)):
        T = ctx.tcp()[k]
        out = []
        if not g.pose.valid(T):
            vv = g.pose.violations(T)
            out.append(V(f"{g.type}: TCP pose outside the goal tolerance: " +
                         _describe(vv),
                         sample=k))
        if isinstance(g, Reach):
            tw = ctx.twist()[k]
            m = float(np.abs(tw).max())
            if m > g.velocity_tolerance:
                out.append(V(f"reach: the TCP is still moving (max twist component {m:.4g} > {g.velocity_tolerance})",
                             sample=k, value=m, bound=g.velocity_tolerance))
        return not out, out, (k, k)
    if isinstance(g, ReturnTo):
        if g.return_to is None:
            kr = 0
        else:
            if g.return_to not in g2t:
                return False, [V(f"returnTo: goal {g.return_to!r} has no goal2time entry", sample=k)], (k, k)
            kr = find_time_index(ctx.t, g2t[g.return_to])
            if kr is None:
                return False, [V(f"returnTo: no unique sample at goal {g.return_to!r}'s time", sample=k)], (k, k)
        out = []
        for name, arr in (("q", ctx.q), ("dq", ctx.dq), ("ddq", ctx.ddq)):
            d = float(np.linalg.norm(arr[k] - arr[kr]))
            if d > g.epsilon:
                out.append(V(f"returnTo: ‖Δ{name}‖ = {d:.4g} to sample {kr} exceeds {g.epsilon}", sample=k, value=d,
                             bound=g.epsilon))
        return not out, out, (k, k)
    if isinstance(g, Pause):
        t_start = tg - g.duration
        if t_start < ctx.t[0] - 1e-9:
            return False, [V(f"pause: the window starts at {t_start:.4f} s, before the trajectory", sample=k)], None
        k0 = int(np.searchsorted(ctx.t, t_start - 1e-9, side="left"))
        out = []
        q0 = ctx.q[k0]
        dq_max = float(np.abs(ctx.q[k0:k + 1] - q0).max())
        v_max = float(np.abs(ctx.dq[k0:k + 1]).max())
        a_max = float(np.abs(ctx.ddq[k0:k + 1]).max())
        if dq_max > 1e-9:
            out.append(V(f"pause: q moves by {dq_max:.3g} during the pause [{ctx.t[k0]:.4f}, {tg:.4f}] s", sample=k))
        if v_max > 1e-9 or a_max > 1e-9:
            out.append(V(f"pause: dq/ddq not zero during the pause (max |dq| {v_max:.3g}, |ddq| {a_max:.3g})",
                         sample=k))
        return not out, out, (k0, k)
    if isinstance(g, Follow):
        return _check_follow(g, ctx, k, tg, V)
    if isinstance(g, Leave):
        t_end = tg + g.duration
        if t_end > ctx.t[-1] + 1e-9:
            return False, [V(f"leave: the trajectory ends before t_g + duration = {t_end:.4f} s", sample=k)], None
        k1 = int(np.searchsorted(ctx.t, t_end + 1e-9, side="right") - 1)
        T = ctx.tcp()
        inside = [kk for kk in range(k, k1 + 1) if g.region.valid(T[kk])]
        if inside:
            return False, [V(f"leave: the TCP is inside the region at {len(inside)} samples of [{tg:.4f}, {t_end:.4f}] s "
                             f"(first at t={ctx.t[inside[0]]:.4f})", sample=inside[0])], (k, k1)
        return True, [], (k, k1)
    return False, [V(f"unsupported goal type {type(g).__name__}")], None


def _check_follow(g: Follow, ctx: _Context, k: int, tg: float, V):
    T = ctx.tcp()
    wrench = np.concatenate([g.external_force, g.external_torque])
    if g.t is not None:
        rel = g.t - g.t[-1]
        t_start = tg + rel[0]
        if t_start < ctx.t[0] - 1e-9:
            return False, [V(f"follow: the timed trajectory would start at {t_start:.4f} s, before t=0", sample=k)], None
        out = []
        for i, (pose, dt_) in enumerate(zip(g.poses, rel)):
            ti = tg + dt_
            Ti = ctx.tcp_at(ti)
            if not pose.valid(Ti):
                vv = pose.violations(Ti)
                out.append(V(f"follow: pose {i} not met at t={ti:.4f}: " +
                             _describe(vv),
                             time=ti))
        k0 = int(np.searchsorted(ctx.t, t_start - 1e-9, side="left"))
    else:
        # untimed: walking back from t_g, each pose (last to first) is met at an earlier or equal sample
        kk = k
        out = []
        for i in range(len(g.poses) - 1, -1, -1):
            while kk >= 0 and not g.poses[i].valid(T[kk]):
                kk -= 1
            if kk < 0:
                out.append(V(f"follow: pose {i} (of {len(g.poses)}) is never met before t_g", sample=k))
                break
        k0 = max(kk, 0)
    if np.any(wrench != 0):
        ctx.f_ext_windows.append((k0, k, wrench))
    return not out, out, (k0, k)
