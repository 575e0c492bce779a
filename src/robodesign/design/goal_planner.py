"""The per-robot stages of the solve pipeline (ik → static_torque → plan → timing): :class:`GoalPlanner` holds
a goal's IK solutions, chooses one per goal, plans the moves between them and times the motion
(``design/solve.py`` runs the stages and judges the result)."""
from __future__ import annotations

import math
import weakref
from typing import TYPE_CHECKING, Any, Dict, List, Optional, Protocol, Sequence, Tuple, cast

import numpy as np

from robodesign.core.trajectory import Trajectory
from robodesign.design.blocked import tool_block
from robodesign.design.follow_ik import FOLLOW_TRIES, follow_chain, timed_follow
from robodesign.design.stages import SolveResult, SolveSettings
from robodesign.formats.costs import CostFunction, cost_term
from robodesign.formats.task_spec import Goal, Task
from robodesign.formats.tolerance import ToleratedPose
from robodesign.solvers.lazy_rng import LazyGenerator
from robodesign.solvers.schedule import ScheduleError, check_hold, find_wait
from robodesign.solvers.timing import time_parameterize

if TYPE_CHECKING:
    from robodesign.solvers.sequencing import Node


class StageFailure(Exception):
    """A stage found the design infeasible; the message says why."""


_Fail = StageFailure


# What the handler of a goal's solver_kind reads of it besides the Goal attributes (Goal.solver_kind): the
# goals are told apart by that name, not by their class (a plugin goal type may use any handler)
class _HoldGoal(Protocol):  # "hold"
    @property
    def duration(self) -> float: ...


class _ReturnGoal(Protocol):  # "return"
    @property
    def return_to(self) -> Optional[str]: ...


class _FollowGoal(Protocol):  # "poses"
    @property
    def t(self) -> Optional[np.ndarray]: ...


class _LeaveGoal(Protocol):  # "leave"
    @property
    def id(self) -> str: ...
    @property
    def duration(self) -> float: ...
    @property
    def center(self) -> np.ndarray: ...
    def contains(self, T: np.ndarray) -> bool: ...


#: a step of the motion: ("move", target configuration, goal or None), ("hold", duration, goal) or
#: ("follow", the configurations of the poses, goal)
_Action = Tuple[str, Any, Optional[Goal]]


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


#: the key that tells the goals' IK streams (GoalPlanner.goal_rng) from other streams of the same seed
_IK_STREAM = 0x1C0


_FULL_POSE: "weakref.WeakKeyDictionary[Task, Tuple[Tuple[str, ...], Optional[Goal]]]" = weakref.WeakKeyDictionary()


def _full_pose_goal(task: Task, order: Sequence[Goal], fixes_full_pose) -> Optional[Goal]:
    """The first goal of ``order`` (the task's goals in goal order) with a pose that ``fixes_full_pose``
    (solvers.ik's), or None; found once per task."""
    ids = tuple(g.id for g in order)
    hit = _FULL_POSE.get(task)
    if hit is None or hit[0] != ids:
        hit = _FULL_POSE[task] = (ids, next((g for g in order if any(fixes_full_pose(p) for p in goal_poses(g))),
                                            None))
    return hit[1]


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
        self._searches: Dict[str, Any] = {}   # pose goal → its IK search (solvers.ik.IKSearch), to collect from
        self._held: Dict[str, Tuple[List[np.ndarray], List[np.ndarray]]] = {}   # see _holdable
        self._timed_memo: Dict[tuple, Trajectory] = {}   # the moves timed for this robot (see _timed)

    # -- IK ------------------------------------------------------------------------------------
    def solve_ik(self) -> None:
        from robodesign.solvers.ik import IKSearch, fixes_full_pose
        # a goal at whose pose this design's end effector lies inside an obstacle deeper than the goal's
        # tolerance can move it (design/blocked.py) has no collision-free IK solution: no restarts
        block = self._tool_block()
        if block is not None:
            self.res.goals_reached = 0
            raise _Fail(f"no collision-free IK solution for goal {block.goal}: at its pose the end effector "
                        f"{block.eef} lies inside obstacle {block.obstacle} deeper than the goal's tolerance can "
                        f"move it ({block.slack * 1e3:.1f} mm)")
        # an arm that cannot move its tool in all six directions (solvers.ik.fixes_full_pose) does not look for
        # a goal that fixes position and orientation: its restarts would all fail (docs/diagnosis.md)
        full = _full_pose_goal(self.task, self.order, fixes_full_pose)
        if full is not None and self.robot.generic_rank() < 6:
            self.res.goals_reached = 0
            raise _Fail(f"no IK solution for goal {full.id}: it fixes position and orientation, but the arm's tool "
                        f"moves in only {self.robot.generic_rank()} independent directions at any configuration "
                        "(its Jacobian's rank; parallel or coaxial joint axes)")
        # first one solution per goal, in goal order: a goal without any fails the stage after the earlier
        # goals' first solutions only (each goal draws from a random stream of its own, so the order of the work
        # does not change what any goal finds); then each goal's other solutions (collect_ik)
        reached = 0
        self._searches = {}
        for i, g in enumerate(self.order):
            if g.solver_kind == "pose":
                search = IKSearch(self.robot, g.target_poses[0], self.goal_rng(i),
                                  max_restarts=self.settings.ik_restarts, saturate=self.settings.ik_saturate)
                r = search.run(1)
                if not r.solutions:
                    self.res.goals_reached = reached
                    raise _Fail(f"no collision-free IK solution for goal {g.id} ({r.stats.get('reason')})")
                self._searches[g.id] = search
                reached += 1
            elif g.solver_kind == "poses":
                try:
                    self.follow_ik[g.id] = self.follow_chain(i, g)
                except _Fail:
                    self.res.goals_reached = reached
                    raise
                reached += 1
            else:
                reached += 1
        self.res.goals_reached = reached
        self.collect_ik()

    def follow_chain(self, i: int, g: Goal) -> List[np.ndarray]:
        """One configuration per pose of follow goal ``g`` (goal ``i``, its own random stream):
        :func:`robodesign.design.follow_ik.follow_chain`."""
        t_rel = cast(_FollowGoal, g).t
        sols, k = follow_chain(self.robot, list(g.target_poses), t_rel, self.task.dt, self.goal_rng(i),
                               self.settings.ik_restarts)
        if sols is not None:
            return sols
        if t_rel is None or k == 0:
            raise _Fail(f"no IK solution for pose {k} of follow goal {g.id}")
        raise _Fail(f"no IK solution for pose {k} of follow goal {g.id} that the joints reach from pose {k - 1} in "
                    f"its {float(t_rel[k] - t_rel[k - 1]):.3g} s (speed and acceleration limits; {FOLLOW_TRIES} "
                    "configurations of the first pose tried)")

    def goal_rng(self, i: int) -> LazyGenerator:
        """The random stream of the IK of goal ``i`` (in goal order): its own, from the settings' seed."""
        return LazyGenerator([self.settings.seed, _IK_STREAM, i])

    def collect_ik(self) -> None:
        """Every pose goal's solutions (``settings.ik_solutions``), goal by goal in goal order. Collecting stops
        after the first goal none of whose solutions the arm can hold against gravity (static_torque): that
        stage fails there whatever the later goals hold (:meth:`filter_static_torque`); a solve that stops after
        the ik stage (``settings.stop_after``) collects every goal."""
        self._held = {}
        torque_next = self.settings.stop_after != "ik"
        for gid, search in self._searches.items():
            self.ik[gid] = search.run(self.settings.ik_solutions).solutions
            if torque_next and not self._holdable(gid)[0]:
                break
        self._searches = {}   # (their suspended loops hold the robot's kernels and buffers: let them go)

    def _holdable(self, gid: str) -> Tuple[List[np.ndarray], List[np.ndarray]]:
        """(the solutions of pose goal ``gid`` the arm holds at rest within its torque limits, |τ| of each
        solution), computed once."""
        hit = self._held.get(gid)
        if hit is None:
            limit = self._rest_limit()
            taus = [np.abs(self.robot.gravity_torque(q)) for q in self.ik[gid]]
            hit = self._held[gid] = ([q for q, tau in zip(self.ik[gid], taus) if np.all(tau <= limit)], taus)
        return hit

    def _tool_block(self):
        """:func:`robodesign.design.blocked.tool_block` of this design's end effector (its only one; the
        static obstacles alone decide it: other colliders only add to them)."""
        ms = self.robot.module_set
        eefs = [mid for mid in self.robot.assembly.module_ids if ms[mid].kind == "eef"]
        return tool_block(self.task, ms[eefs[0]]) if len(eefs) == 1 else None

    def _rest_limit(self) -> np.ndarray:
        """The torque each joint may spend holding a pose at rest: its limit (the Coulomb term vanishes, σ(0) = 0)."""
        r = self.robot
        return r.tau_max - r.friction_coulomb * 0

    def filter_static_torque(self) -> None:
        r = self.robot
        limit = self._rest_limit()
        for gid in list(self.ik):
            ok, taus = self._holdable(gid)
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
        actions: List[_Action] = []
        q = q0
        at_config: Dict[str, np.ndarray] = {}
        for g in self.order:
            if g.solver_kind == "pose":
                actions.append(("move", choice[g.id], g))
                q = choice[g.id]
            elif g.solver_kind == "hold":
                actions.append(("hold", cast(_HoldGoal, g).duration, g))
            elif g.solver_kind == "return":
                to = cast(_ReturnGoal, g).return_to
                target = q0 if to is None else at_config.get(to)
                if target is None:
                    raise _Fail(f"returnTo goal {g.id}: goal {to!r} has no configuration before it")
                actions.append(("move", target, g))
                q = target
            elif g.solver_kind == "poses":
                pts = self.follow_ik[g.id]
                actions.append(("move", pts[0], None))
                actions.append(("follow", pts, g))
                q = pts[-1]
            elif g.solver_kind == "leave":
                leave = cast(_LeaveGoal, g)
                q_out = self._leave_configuration(q, leave)
                actions.append(("move", q_out, None))
                actions.append(("hold", leave.duration, g))
                q = q_out
            at_config[g.id] = q
        self.actions = actions
        # plan every move
        self.paths: List[Optional[np.ndarray]] = []
        q = q0
        for i in range(len(self.actions)):
            kind, arg, goal = self.actions[i]  # an earlier move may have replaced a goal's configuration
            if kind == "move":
                if _same_configuration(arg, q):
                    self.paths.append(None)
                    continue
                r = self._plan(q, arg, self.settings.plan_time)
                if not r:
                    r, arg = self._plan_to_another_solution(q, arg, goal, r)
                if not r:
                    # the goals whose moves were planned: a search ranks plan failures by how far they got
                    self.res.goals_reached = len({gg.id for _, _, gg in self.actions[:i] if gg is not None})
                    raise _Fail(f"no collision-free path to {'goal ' + goal.id if goal else 'the next waypoint'} "
                                f"({r.stats.get('reason')})")
                self.paths.append(r.path)
                q = arg
            elif kind == "follow":
                from robodesign.solvers.planning import check_path
                assert goal is not None  # a follow action has its goal
                P = np.vstack(arg)
                ok, bad = check_path(self.robot, P, self.settings.resolution)
                if not ok:
                    raise _Fail(f"follow goal {goal.id}: the motion between poses {bad} and {bad + 1} collides")
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

    def _sequence_nodes(self) -> List[Node]:
        """The goal sequence as a chain for ``solvers.sequencing.choose``. A ``returnTo`` another at/reach
        goal than the first is left out of the objective (its target is chosen by its own neighbours)."""
        from robodesign.solvers.sequencing import Fixed, Free, Jump, Tied
        first = next((g for g in self.order if g.solver_kind in ("pose", "poses")), None)
        if first is None:
            return []
        nodes: List[Node] = [] if self.start is None else [Fixed(self.start)]
        for g in self.order:
            if g.solver_kind == "pose":
                nodes.append(Free(g.id, np.asarray(self.ik[g.id])))
            elif g.solver_kind == "poses":
                pts = self.follow_ik[g.id]
                nodes += [Fixed(pts[0]), Jump(pts[-1])]
            elif g.solver_kind == "return" and nodes:
                to = cast(_ReturnGoal, g).return_to
                if to is None and self.start is not None:
                    nodes.append(Tied())
                elif to is None:
                    nodes.append(Tied() if first.solver_kind == "pose" else Fixed(self.follow_ik[first.id][0]))
                elif to == first.id and first.solver_kind == "pose" and self.start is None:
                    nodes.append(Tied())
                elif to in self.follow_ik:
                    nodes.append(Fixed(self.follow_ik[to][-1]))
        return nodes

    def _free_configuration(self) -> np.ndarray:
        q = np.clip(np.zeros(self.robot.dof), self.robot.q_lower, self.robot.q_upper)
        for _ in range(200):
            if not self.robot.in_collision(q):
                return q
            q = self.robot.random_configuration(self.rng)
        raise _Fail("no collision-free start configuration found")

    def _leave_configuration(self, q: np.ndarray, g: _LeaveGoal) -> np.ndarray:
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
            return (Trajectory.at_rest(traj.q[0]).hold(n * dt, dt).concatenate(traj),
                    {k: v + n * dt for k, v in g2t.items()})

    def timed_motion(self, cost: Optional[CostFunction] = None, slow: Optional[Dict[str, float]] = None,
                     colliders: Sequence = ()):
        """The whole motion, sampled at the task's time step, and the goal times. With ``cost`` (trajectory
        optimization enabled) every rest-to-rest move is re-timed by CasADi/ipopt for that cost; a move
        whose optimization fails keeps its time-optimal TOPP-RA timing. ``slow`` maps goal IDs to a speed
        factor s < 1 for the motion of that goal (joint speed limits × s, accelerations × s²). Before each
        move the robot waits at rest until the move misses every timed collider of ``colliders``."""
        dt = self.task.dt
        traj = Trajectory.at_rest(self.q0)
        g2t: Dict[str, float] = {}
        slow = slow or {}
        for (kind, arg, g), path in zip(self.actions, self.paths):
            robot = self.robot if g is None or g.id not in slow else _SlowedRobot(self.robot, slow[g.id])
            if kind == "move":
                if path is not None:
                    seg = self._timed(robot, path, dt=dt, method=self.settings.timing, blend_radius=self.blend_radius)
                    if cost is not None and robot is self.robot:  # a slowed move keeps its slow timing
                        seg = self._optimize_move(seg, cost)
                    traj = self._append_after_wait(traj, seg, g, colliders)
                if g is not None:
                    g2t[g.id] = float(traj.t[-1])
            elif kind == "hold":
                assert g is not None  # a hold action has its goal
                self._check_hold(traj, arg, g, colliders)
                if arg > 0:
                    traj = traj.hold(arg, dt)
                g2t[g.id] = float(traj.t[-1])
                if g.solver_kind == "leave":
                    g2t[g.id] = float(traj.t[-1] - _ceil_to(arg, dt))
            elif kind == "follow":
                assert g is not None and path is not None  # a follow action has its goal and its path
                t_rel = cast(_FollowGoal, g).t
                if t_rel is None:
                    seg = self._timed(robot, path, dt=dt, method=self.settings.timing, blend_radius=0.0,
                                      stop_at=tuple(range(len(path))))
                else:
                    seg = timed_follow(path, t_rel, dt)
                traj = self._append_after_wait(traj, seg, g, colliders)
                g2t[g.id] = float(traj.t[-1])
        return traj, g2t

    def _timed(self, robot, path, **options):
        """``time_parameterize(robot, path, **options)``, remembered for the planner's own robot: a goal retry
        (solve._achieve_missed_goals) times every move again and slows only the missed goals' (a ``_SlowedRobot``),
        and a motion delayed as a whole is timed again without colliders: the same path, robot and options give
        the same trajectory. The remembered trajectory itself is returned: :meth:`timed_motion`, the only caller,
        reads it (concatenating it makes new arrays), so it stays as it was timed."""
        if robot is not self.robot:
            return time_parameterize(robot, path, **options)
        p = np.asarray(path, dtype=float)
        key = (p.shape, p.tobytes(), tuple(sorted(options.items())))
        memo = self._timed_memo
        if key not in memo:
            memo[key] = time_parameterize(robot, p, **options)
        return memo[key]

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


def _same_configuration(a: np.ndarray, b: np.ndarray) -> bool:
    """``np.allclose(a, b, atol=1e-12)`` of two configurations (vectors of the same length) element by element in
    Python floats: |a − b| ≤ 1e-12 + 1e-5·|b| where b is finite, or a == b (the same double operations)."""
    if np.shape(a) != np.shape(b) or np.ndim(a) != 1:
        return bool(np.allclose(a, b, atol=1e-12))
    return all((abs(x - y) <= 1e-12 + 1e-05 * abs(y) and math.isfinite(y)) or x == y
               for x, y in zip(np.asarray(a, dtype=float).tolist(), np.asarray(b, dtype=float).tolist()))


def _ceil_to(x: float, dt: float) -> float:
    return math.ceil(x / dt - 1e-9) * dt


def _translate(T: np.ndarray, d: np.ndarray) -> np.ndarray:
    T2 = T.copy()
    T2[:3, 3] += d
    return T2
