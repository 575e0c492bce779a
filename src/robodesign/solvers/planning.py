"""Collision-free joint-space path planning with OMPL 2.x, plus a dense path checker.

:func:`plan_path` plans from ``q_start`` to ``q_goal`` for a :class:`~robodesign.model.robot.Robot` (with the
obstacles already set on it) and returns joint waypoints whose straight interpolation is collision-free.

Decisions:

* **Validity** of a configuration: within the joint limits and ``not robot.in_collision(q)`` (self +
  obstacles, with the robot's safety margin); with ``static_torque=True`` (what :func:`robodesign.design.solve.solve`
  asks for) also held against gravity within the torque limits, |g(q)| ≤ τ_max: a path through a pose
  the joints cannot hold standing still cannot be timed by slowing down; farther than ``REST_RADIUS`` from
  the start and the goals also |g(q)| + f_c ≤ τ_max (Coulomb friction while moving). The OMPL planner, the shortcuts
  and the final dense check all use this one test.
* **Resolution** is an absolute joint step (rad, or m for prismatic joints): no two consecutive checked
  states differ by more than ``resolution`` in any joint. OMPL's discrete motion validator steps by the
  *Euclidean* distance ``fraction × maximum extent``, so the fraction is ``resolution / extent``; its
  steps are then ≤ ``resolution`` in every joint (conservative by up to √dof). :func:`check_path` steps
  by the largest joint difference directly (``ceil(max|Δq| / resolution)`` sub-steps per segment).
* **Straight line first**: if the direct segment passes the dense check, no planner is called.
* **Several goals** (``other_goals``): any of a goal's IK solutions will do; OMPL gets every valid one as a goal
  state of one query (``GoalStates``: RRT-Connect grows its goal tree from all of them), and the path ends
  exactly at the one it reached (``stats["goal"]``). The solve pipeline asks this only after the chosen
  solution could not be reached (free space with the poses the joints can hold often falls apart into pieces).
* **Each state is evaluated once per call**: the validity verdicts are remembered by the configuration's
  exact bytes, so the shortcuts and the final dense check do not re-query states the planner's checks already
  decided (``stats["distinct_states"]`` counts the evaluated ones, ``lookups`` every verdict asked for).
* **Post-processing** (``simplify=True``): a greedy shortcut (from each kept waypoint jump to the
  farthest one reachable in a straight line), then 40 random partial shortcuts between points on two
  segments (seeded from ``seed``; a fixed count keeps the result deterministic), then collinear
  waypoints are dropped. OMPL's ``PathSimplifier.simplify`` was not used: with a Python validity
  checker its B-spline smoothing and Euclidean-resolution checks took 0.3–1.5 s per path. Finally the
  path is re-checked densely with :func:`check_path`; a path that fails is never returned (the raw
  planner path is tried next, else the result is a failure).
* **Work limit, not wall-clock time**: ``time_limit`` (s) is converted into a budget of validity checks,
  :data:`CHECKS_PER_SECOND` per second (the rate of one quiet core), and OMPL's solve stops when the budget
  is spent (the validity checker ends the solve's termination condition once the count is reached). A busy
  machine therefore takes longer but plans the same path, and a query that succeeds on a quiet machine
  succeeds under load too. A wall-clock cap of max(:data:`WALL_FACTOR`·time_limit, :data:`WALL_MIN`) + 50 ms
  stays as a safety net (the floor keeps short queries, such as the plan stage's half-effort fallback,
  deterministic on a machine loaded many times over)
  (the validity checker then reports every state invalid, which also stops planners that ignore the
  condition, such as FMT/BFMT sampling a fixed number of states). The straight-line check and post-
  processing come on top (the shortcuts are bounded by their count).
* **Determinism**: ``ou.RNG.setSeed(seed % (2³¹−2) + 1)`` before anything that samples is created
  (OMPL seeds each RNG instance from that generator; seed 0 is reserved by OMPL). The result is
  deterministic for a given seed (the work limit counts checks, not seconds); PRM/PRM* grow their roadmap
  in a second thread, so their check counts (not their paths, in our tests) vary.
* **Anytime planners** (rrtstar, prmstar, bitstar, informedrrtstar, sorrtstar, ...): by default the
  path-length objective gets an infinite cost threshold, so every planner returns its first solution;
  ``optimize=True`` lets them refine until ``time_limit``.
* Every OMPL object is local to the call (nanobind reports leaks for objects that outlive the module).
"""
from __future__ import annotations

import bisect
import difflib
import functools
import math
import time
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Sequence, Tuple, cast

import numpy as np

from robodesign.core.errors import InputError
from robodesign.model.collision_cull import culler_of
from robodesign.model.robot import Robot
from robodesign.solvers.ompl_motion import PLANNERS_TWO_STATE, motion_validator, set_start_and_goals
from robodesign.solvers.pair_certificates import PairCertificates
from robodesign.solvers.static_validity import REST_RADIUS, static_validator

__all__ = ["PlanResult", "plan_path", "check_path", "available_planners", "planner_name", "PLANNERS", "CHECKS_PER_SECOND",
           "REST_RADIUS"]

#: validity checks per second of ``time_limit``: what one quiet core does on IMPROV and built-in arms
#: (5–7k per CPU second measured with other jobs on the machine); the planner's work limit
CHECKS_PER_SECOND = 8000
#: the wall-clock safety net, as a multiple of ``time_limit`` (reached only on a machine ~10x slower)
WALL_FACTOR = 10.0
WALL_MIN = 10.0  # s: the wall-clock cap's floor

# name → OMPL class name (only the classes present in the installed OMPL are offered)
PLANNERS: Dict[str, str] = {
    "rrtconnect": "RRTConnect", "rrt": "RRT", "rrtstar": "RRTstar", "prm": "PRM", "prmstar": "PRMstar",
    "bitstar": "BITstar", "kpiece": "KPIECE1", "bkpiece": "BKPIECE1", "lbkpiece": "LBKPIECE1",
    "fmt": "FMT", "bfmt": "BFMT", "informedrrtstar": "InformedRRTstar", "sorrtstar": "SORRTstar",
    "aorrtc": "AORRTC",
}
_SHORTCUT_TRIES = 40
_SHORTCUT_SAFETY_SECONDS = 120.0
_GOAL_TOL = 1e-9            # OMPL goal threshold (the last waypoint is then set to q_goal exactly)


@dataclass
class PlanResult:
    """``path``: (K, dof) waypoints from q_start to q_goal (exactly), empty (0, dof) on failure."""
    path: np.ndarray
    success: bool
    stats: Dict[str, object] = field(default_factory=dict)

    def __bool__(self) -> bool:
        return self.success


def available_planners() -> List[str]:
    """Planner names :func:`plan_path` accepts with the installed OMPL."""
    try:
        from ompl import geometric as og
    except ImportError:  # pragma: no cover - OMPL is a hard dependency of planning
        return []
    return [k for k, v in PLANNERS.items() if hasattr(og, v)]


def planner_name(planner: str) -> str:
    """The canonical (lower-case) name of ``planner``, one of :func:`available_planners`; an unknown name is
    an :class:`InputError` suggesting the closest known one."""
    name = str(planner).lower()
    avail = available_planners()
    if name not in avail:
        close = difflib.get_close_matches(name, avail, n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise InputError(f"unknown planner {planner!r}{hint}; available: {', '.join(avail)}")
    return name


# ---------------------------------------------------------------------------------------------------------
# Dense checking
# ---------------------------------------------------------------------------------------------------------
def _config_validator(robot, static_torque: bool = False, rest: Sequence = ()):
    """Joint limits and collisions; with ``static_torque`` also that the joints hold the configuration
    against gravity within their torque limits (|g(q)| ≤ τ_max), so that a path never needs more torque
    standing still than the joints have: time scaling cannot repair such a path by slowing down. With
    ``rest`` (the configurations where the motion stands still: its start and goals) a state farther than
    :data:`REST_RADIUS` from all of them must also leave room for Coulomb friction, |g(q)| + f_c ≤ τ_max:
    the robot moves through it, and however slowly it moves, friction adds f_c."""
    static_ok = static_validator(robot, static_torque, rest)
    in_collision = robot.in_collision

    def valid(q: np.ndarray) -> bool:
        return static_ok(q) and not in_collision(q)
    valid.static_ok = static_ok  # type: ignore[attr-defined]  # read by _Memoized.first_invalid
    return valid


class _Memoized:
    """``valid`` remembering its verdict per configuration (by its exact bytes) for one planning call: the
    shortcuts and the final dense check revisit states the planner's checks already decided (the same
    interpolation formula gives the same floats), and a verdict never changes within a call. ``memo``: the
    verdicts by state, ``lookups``: the verdicts asked for.

    :meth:`first_invalid` decides many states (a segment's) at once with the same verdicts: the torque tests
    per state, the collision queries through :class:`~robodesign.model.collision_cull.CollisionCuller`
    (coal asked only about the pairs its bounds do not clear, less the pairs a distance computed at another
    state proves free: :mod:`~robodesign.solvers.pair_certificates`) when ``robot`` is given and ``valid`` came
    from :func:`_config_validator`."""

    def __init__(self, valid: Callable[[np.ndarray], bool], robot=None):
        self.valid = valid
        self.memo: Dict[bytes, bool] = {}
        self.lookups = 0
        self.static_ok = getattr(valid, "static_ok", None)
        self.robot = robot if self.static_ok is not None else None
        self._culler = None
        self.certificates: Optional[PairCertificates] = None   # (with the culler, for a Robot)

    def __call__(self, q: np.ndarray) -> bool:
        self.lookups += 1
        key = q.tobytes()
        v = self.memo.get(key)
        if v is None:
            v = self.memo[key] = self.valid(q)
        return v

    def culler(self):
        """The robot's CollisionCuller (built on first use), or None where it does not apply."""
        if self._culler is None and self.robot is not None:
            try:
                self._culler = culler_of(self.robot)
            except (AttributeError, NotImplementedError):  # a robot without coal geometry or batched FK
                self.robot = None
            if isinstance(self.robot, Robot):
                self.certificates = PairCertificates.of(self.robot, self._culler)
        return self._culler

    def first_invalid(self, Q: np.ndarray, counter: Optional[List[int]] = None,
                      gate: Optional[Callable[[], bool]] = None) -> int:
        """The first row of ``Q`` that is invalid, or -1: the verdicts (and counts) of asking ``self(q)`` row
        by row until then; ``counter[0]`` grows by the rows asked. ``gate``: asked after each row is counted and
        before its verdict; False makes that row invalid unasked (the planner's work limit). With the collision
        culler, ``gate.room()`` tells how many of the next rows it lets through (it then is asked only at the row
        where it stops)."""
        culler = self.culler()
        if culler is None:
            for i, q in enumerate(Q):
                if counter is not None:
                    counter[0] += 1
                if gate is not None and not gate():
                    return i
                if not self(q):
                    return i
            return -1
        start = 0
        for size in _CHUNKS:   # a segment that collides early pays for few states' bounds
            i = self._chunk_first_invalid(culler, Q[start:start + size], counter, gate)
            if i >= 0:
                return start + i
            start += size
            if start >= len(Q):
                break
        return -1

    def _chunk_first_invalid(self, culler, rows: np.ndarray, counter: Optional[List[int]],
                             gate: Optional[Callable[[], bool]]) -> int:
        """:meth:`first_invalid` of one block of rows, their bounds and torque tests made at once. Only the rows
        whose verdict can be False are visited one by one (those the memo holds invalid, new ones that fail the
        torque test or have a pair the bounds do not clear); the others are valid. A ``gate`` is asked only at the
        row its ``room()`` says it stops (no earlier row can end the block there). The rows decided are remembered
        in row order and counted up to the first invalid row (its index, or -1)."""
        memo, static_ok, certs = self.memo, self.static_ok, self.certificates
        assert static_ok is not None  # a culler only with _config_validator's valid
        keys = _row_keys(rows)
        seen = list(map(memo.get, keys))
        new = [i for i, v in enumerate(seen) if v is None]               # rows not remembered
        bad = [i for i, v in enumerate(seen) if v is not None and not v]  # remembered invalid
        R = rows[new]
        S = culler.survivors(R)
        if certs is not None:     # (the self pairs a distance certifies free not asked)
            S = certs.pending(R, S)
        ok = static_ok.rows(R)  # type: ignore[attr-defined]
        near = S.any(axis=1)      # rows with a pair the bounds do not clear
        at = dict(zip(new, range(len(new))))
        flagged = [new[j] for j in (~ok | near).nonzero()[0].tolist()]
        limit = len(rows) if gate is None else max(0, min(len(rows), gate.room()))  # type: ignore[attr-defined]
        got: Dict[bytes, bool] = {}   # the verdicts made here (remembered in row order at the end)
        stop, n = -1, limit           # the first invalid row; the rows decided
        for i in sorted(flagged + bad) if bad else flagged:
            if i >= limit:
                break
            key = keys[i]
            v = memo.get(key)
            if v is None:
                v = got.get(key)      # (an earlier row of this block may be the same state)
            if v is None:
                j = at[i]
                v = bool(ok[j])
                if v and near[j]:
                    ks = S[j].nonzero()[0] if certs is None else certs.ask(S, R, j)
                    v = not (len(ks) and culler.collides(rows[i], ks))
                got[key] = v
            if not v:
                stop, n = i, i + 1
                break
        if counter is not None:
            counter[0] += n
        self.lookups += n
        if stop < 0 and gate is not None and limit < len(rows):   # the row the gate stops: counted, then asked
            if counter is not None:
                counter[0] += 1
            gate()   # (False: the work limit is spent, the planner's solve ends)
            stop = limit
        memo.update(dict.fromkeys([keys[i] for i in new[:bisect.bisect_left(new, n)]], True))
        memo.update(got)   # (the rows visited: each one of those just remembered)
        return stop


def _row_keys(rows: np.ndarray) -> List[bytes]:
    """``[q.tobytes() for q in rows]`` (the memo's keys) in one pass: each row's bytes as a void scalar of its
    length (kept whole, trailing zero bytes included)."""
    rows = np.ascontiguousarray(rows)
    return rows.view(np.dtype((np.void, rows.dtype.itemsize * rows.shape[1]))).ravel().tolist()


#: the row blocks :meth:`_Memoized.first_invalid` bounds at once (the last one takes the rest)
_CHUNKS = (4, 28, 1 << 62)


def _segment_ok(valid, a: np.ndarray, b: np.ndarray, resolution: float, counter: Optional[List[int]] = None,
                include_start: bool = False) -> bool:
    """Check the states of a→b at steps of at most ``resolution`` per joint (end included).

    The sub-states are checked in a coarse-to-fine (van der Corput) order, so a collision in the
    middle is found after few checks; the set of checked states is the same as a sequential sweep.
    A :class:`_Memoized` ``valid`` decides them together (:meth:`_Memoized.first_invalid`: the same verdicts
    and counts, the collision queries culled).
    """
    d = b - a
    n = max(1, int(math.ceil(float(np.max(np.abs(d))) / resolution - 1e-12))) if d.size else 1
    T = np.array(_bisection_order(n), dtype=float) / n   # (k / n, as Python's float division gives it)
    states = np.concatenate([a[None, :]] * include_start + [b[None, :], a[None, :] + d[None, :] * T[:, None]])
    if isinstance(valid, _Memoized):
        return valid.first_invalid(states, counter) < 0
    for q in states:
        if counter is not None:
            counter[0] += 1
        if not valid(q):
            return False
    return True


@functools.lru_cache(maxsize=1024)
def _bisection_order(n: int) -> Tuple[int, ...]:
    """1..n-1 ordered coarse to fine (midpoints first); remembered."""
    out: List[int] = []
    seen = set()
    step = 1
    while step < n:
        step *= 2
    while step >= 1:
        for k in range(step, n, step):
            if k not in seen:
                seen.add(k)
                out.append(k)
        step //= 2
    return tuple(out)


def check_path(robot, path, resolution: float = 0.01, static_torque: bool = False,
               _valid=None) -> Tuple[bool, int]:
    """Dense check of a joint path (K×dof waypoints, linearly interpolated).

    Returns ``(True, -1)`` if every waypoint and every interpolated state (steps of at most
    ``resolution`` in each joint) is within the joint limits and collision-free (and, with
    ``static_torque``, held against gravity within the torque limits); otherwise
    ``(False, i)`` where ``i`` is the first waypoint that is invalid itself or whose segment to
    waypoint ``i + 1`` contains an invalid state.
    """
    P = np.asarray(path, dtype=float)
    if P.ndim != 2 or P.shape[1] != robot.dof:
        raise InputError(f"path must be a (K, {robot.dof}) array, got shape {P.shape}")
    if not (resolution > 0 and math.isfinite(resolution)):
        raise InputError(f"resolution must be a positive number, got {resolution!r}")
    if len(P) == 0:
        return True, -1
    if not np.all(np.isfinite(P)):
        bad = int(np.nonzero(~np.all(np.isfinite(P), axis=1))[0][0])
        return False, bad
    valid = _Memoized(_config_validator(robot, static_torque), robot) if _valid is None else _valid
    if not valid(P[0]):
        return False, 0
    for i in range(len(P) - 1):
        a, b = P[i], P[i + 1]
        if not _interior_ok(valid, a, b, resolution):
            return False, i
        if not valid(b):
            return False, i + 1
    return True, -1


def _interior_ok(valid, a, b, resolution) -> bool:
    d = b - a
    n = max(1, int(math.ceil(float(np.max(np.abs(d))) / resolution - 1e-12)))
    if n > 1 and isinstance(valid, _Memoized):   # in order: the first bad state is the one nearest to a
        return valid.first_invalid(np.array([a + d * (k / n) for k in range(1, n)])) < 0
    for k in range(1, n):          # sequential: the first bad state is the one nearest to a
        if not valid(a + d * (k / n)):
            return False
    return True


def _shortcut(valid, P: np.ndarray, resolution: float, counter: List[int]) -> np.ndarray:
    """Greedy shortcutting: from each kept waypoint jump to the farthest directly reachable one."""
    if len(P) <= 2:
        return P
    out = [P[0]]
    i = 0
    K = len(P)
    while i < K - 1:
        j = K - 1
        while j > i + 1 and not _segment_ok(valid, P[i], P[j], resolution, counter):
            j -= 1
        out.append(P[j])
        i = j
    return np.array(out)


def _partial_shortcuts(valid, P: np.ndarray, resolution: float, counter: List[int], rng: np.random.Generator,
                       tries: int, deadline: float) -> np.ndarray:
    """Random shortcuts between points *on* two different segments (not only waypoints)."""
    pts = [np.asarray(p, dtype=float) for p in P]
    for _ in range(tries):
        if len(pts) < 3 or time.perf_counter() > deadline:
            break
        i, j = sorted(rng.choice(len(pts) - 1, size=2, replace=False))
        if j == i:
            continue
        ta, tb = rng.uniform(), rng.uniform()
        a = pts[i] + ta * (pts[i + 1] - pts[i])
        b = pts[j] + tb * (pts[j + 1] - pts[j])
        old = sum(float(np.linalg.norm(pts[k + 1] - pts[k])) for k in range(i + 1, j)) \
            + float(np.linalg.norm(pts[i + 1] - a)) + float(np.linalg.norm(b - pts[j]))
        if float(np.linalg.norm(b - a)) >= old - 1e-9:
            continue
        if _segment_ok(valid, a, b, resolution, counter, include_start=True):
            pts = pts[:i + 1] + [a, b] + pts[j + 1:]
    # drop waypoints that lie on the straight line between their neighbours
    out = [pts[0]]
    for k in range(1, len(pts) - 1):
        u, v = pts[k] - out[-1], pts[k + 1] - pts[k]
        nu, nv = float(np.linalg.norm(u)), float(np.linalg.norm(v))
        if nu < 1e-12 or (nv > 1e-12 and float(u @ v) > (1 - 1e-12) * nu * nv):
            continue
        out.append(pts[k])
    out.append(pts[-1])
    return np.array(out)


# ---------------------------------------------------------------------------------------------------------
# Planning
# ---------------------------------------------------------------------------------------------------------
def plan_path(robot, q_start, q_goal, planner: str = "rrtconnect", time_limit: float = 1.0, seed: int = 0,
              resolution: float = 0.01, simplify: bool = True, optimize: bool = False,
              static_torque: bool = False, other_goals: Sequence = ()) -> PlanResult:
    """A collision-free joint path from ``q_start`` to ``q_goal`` (both kept exactly).

    ``other_goals``: further configurations any of which will do as well (a goal's other IK solutions): the
    planner grows its goal tree from all the valid ones at once, and the path ends exactly at the one it
    connected to; ``stats["goal"]`` says which (0: ``q_goal``, k: ``other_goals[k − 1]``; the straight line is
    tried to ``q_goal`` only).

    ``planner``: one of :func:`available_planners` (case-insensitive). ``time_limit`` (s) bounds the
    OMPL solve as a work limit of ``time_limit`` × :data:`CHECKS_PER_SECOND` validity checks (the same path on
    a quiet and on a busy machine). ``seed``: OMPL's and the shortcutting RNG seed. ``resolution``: largest joint step (rad
    or m) between checked states. ``simplify``: shortcut the planner's path. ``optimize``: let anytime
    planners refine the path length until ``time_limit`` instead of returning their first solution.
    ``static_torque``: every state must also be held against gravity within the torque limits (see
    :func:`check_path`). ``stats``: planner, straight_line, time, plan_time, simplify_time,
    checks, raw_waypoints, waypoints, length (Euclidean joint-space length), reason
    ("straight_line" | "planned" | "invalid_start" | "invalid_goal" | "no_solution" | "final_check_failed").
    """
    t0 = time.perf_counter()
    name = planner_name(planner)
    if not (resolution > 0 and math.isfinite(resolution)):
        raise InputError(f"resolution must be a positive number, got {resolution!r}")
    if not (time_limit > 0 and math.isfinite(time_limit)):
        raise InputError(f"time_limit must be a positive number of seconds, got {time_limit!r}")
    n = robot.dof
    qs = np.asarray(q_start, dtype=float).reshape(-1)
    qg = np.asarray(q_goal, dtype=float).reshape(-1)
    for label, q in (("q_start", qs), ("q_goal", qg)):
        if q.shape != (n,) or not np.all(np.isfinite(q)):
            raise InputError(f"{label} must be {n} finite joint values, got {np.asarray(q).tolist()}")
    counter = [0]
    rest = [qs, qg, *[np.asarray(q, dtype=float).reshape(-1) for q in other_goals]] if static_torque else []
    valid = _Memoized(_config_validator(robot, static_torque, rest), robot)
    stats: Dict[str, object] = {"planner": name, "straight_line": False, "time": 0.0, "plan_time": 0.0,
                                "simplify_time": 0.0, "checks": 0, "raw_waypoints": 0, "waypoints": 0,
                                "length": 0.0, "reason": ""}

    def done(path: Optional[np.ndarray], reason: str) -> PlanResult:
        stats["reason"] = reason
        stats["checks"] = counter[0]
        stats["lookups"] = valid.lookups                # validity verdicts asked for, the final check's included
        stats["distinct_states"] = len(valid.memo)      # states actually evaluated (the lookups revisit some)
        stats["time"] = time.perf_counter() - t0
        if path is None:
            return PlanResult(np.zeros((0, n)), False, stats)
        stats["waypoints"] = len(path)
        stats["length"] = float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1))) if len(path) > 1 else 0.0
        return PlanResult(path, True, stats)

    counter[0] += 1
    if not valid(qs):
        return done(None, "invalid_start")
    goals: List[Optional[np.ndarray]] = [qg]
    for q in other_goals:
        q = np.asarray(q, dtype=float).reshape(-1)
        if q.shape != (n,) or not np.all(np.isfinite(q)):
            raise InputError(f"other_goals must be {n} finite joint values each, got {q.tolist()}")
        goals.append(q)
    stats["goal"] = 0
    counter[0] += 1
    if not valid(qg):
        if len(goals) == 1:
            return done(None, "invalid_goal")
        goals[0] = None  # not a goal state; the others still are
    ok_goals = [k for k, q in enumerate(goals) if q is not None and (k == 0 or valid(q))]
    if not ok_goals:
        return done(None, "invalid_goal")
    direct = np.array([qs, qg])
    if goals[0] is not None and _segment_ok(valid, qs, qg, resolution, counter):
        stats["straight_line"] = True
        stats["raw_waypoints"] = 2
        return done(direct, "straight_line")      # also for q_start == q_goal: always [start, goal]

    G = np.vstack([cast(np.ndarray, goals[k]) for k in ok_goals])  # ok_goals: indices of goals not None
    raw = _plan_ompl(robot, valid, qs, G, name, time_limit, seed, resolution, optimize, counter, stats)
    if raw is None:
        return done(None, "no_solution")
    reached = ok_goals[int(np.argmin(np.max(np.abs(G - raw[-1]), axis=1)))]
    stats["goal"] = reached
    raw[0], raw[-1] = qs, goals[reached]
    candidates = [raw]
    if simplify:
        ts = time.perf_counter()
        P = _shortcut(valid, raw, resolution, counter)
        rng = np.random.default_rng(seed)
        # a fixed number of tries keeps the result deterministic; the time cap is only a safety net, far
        # beyond what 40 tries take even on a machine loaded many times over (a cap of 1 s cut the tries
        # short under load and made the same seed give different paths, and `optimize --workers 2` differ
        # from `--workers 1`)
        P = _partial_shortcuts(valid, P, resolution, counter, rng, _SHORTCUT_TRIES,
                               ts + _SHORTCUT_SAFETY_SECONDS)
        stats["simplify_time"] = time.perf_counter() - ts
        candidates.insert(0, P)
    for P in candidates:
        ok, _ = check_path(robot, P, resolution, static_torque, _valid=valid)
        if ok:
            return done(P, "planned")
    return done(None, "final_check_failed")


def _plan_ompl(robot, valid, qs, G, name, time_limit, seed, resolution, optimize, counter, stats):
    """OMPL's path from ``qs`` to any row of ``G`` (one or more goal configurations), or None."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    n = robot.dof
    G = np.atleast_2d(np.asarray(G, dtype=float))
    lo = np.asarray(robot.q_lower, dtype=float).copy()
    hi = np.asarray(robot.q_upper, dtype=float).copy()
    lo = np.where(np.isfinite(lo), lo, np.minimum(-math.pi, np.minimum(qs, G.min(axis=0))))
    hi = np.where(np.isfinite(hi), hi, np.maximum(math.pi, np.maximum(qs, G.max(axis=0))))
    hi = np.where(hi > lo, hi, lo + 1e-9)

    level = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_NONE)  # setSeed logs an error once sampling has started; the reseed still works
    try:
        ou.RNG.setSeed(int(seed) % 2147483646 + 1)
        space = ob.RealVectorStateSpace(n)
        bounds = ob.RealVectorBounds(n)
        for i in range(n):
            bounds.setLow(i, float(lo[i]))
            bounds.setHigh(i, float(hi[i]))
        space.setBounds(bounds)
        ss = og.SimpleSetup(space)
        rng_idx = range(n)

        hard_deadline = [math.inf]   # set when solving starts
        budget = [math.inf]          # the last check count the planner may reach
        stop: list = []              # the solve's termination condition, ended from the validity checker

        def within_budget() -> bool:
            """After a state is counted: False (and OMPL told to end the solve) once the work limit is spent."""
            if counter[0] >= budget[0] or time.perf_counter() > hard_deadline[0]:
                if stop:
                    stop[0].terminate()   # the work limit is spent: OMPL ends the solve
                return False         # and planners that ignore the condition (FMT) stop soon
            return True

        def room() -> float:
            """How many more states ``within_budget`` lets through, each counted before it is asked (none past
            the wall-clock cap)."""
            return 0 if time.perf_counter() > hard_deadline[0] else budget[0] - counter[0] - 1
        within_budget.room = room  # type: ignore[attr-defined]  # read by _Memoized.first_invalid

        def is_valid(s) -> bool:
            counter[0] += 1
            if not within_budget():
                return False
            return valid(np.array([s[i] for i in rng_idx]))   # the same test as the dense checks

        ss.setStateValidityChecker(is_valid)
        si = ss.getSpaceInformation()
        si.setStateValidityCheckingResolution(min(1.0, resolution / space.getMaximumExtent()))
        if name in PLANNERS_TWO_STATE and isinstance(valid, _Memoized) and valid.culler() is not None:
            # each motion's states at once, in OMPL's order, with the same verdicts and counts (solvers/ompl_motion.py)
            si.setMotionValidator(motion_validator(ob, space, si, n, lambda Q: valid.first_invalid(Q, counter,
                                                                                                    within_budget)))
        set_start_and_goals(ob, ss, space, si, qs, G, _GOAL_TOL)
        obj = ob.PathLengthOptimizationObjective(si)
        if not optimize:
            obj.setCostThreshold(obj.infiniteCost())
        ss.setOptimizationObjective(obj)
        ss.setPlanner(getattr(og, PLANNERS[name])(si))
        ss.setup()
        budget[0] = counter[0] + max(1, int(float(time_limit) * CHECKS_PER_SECOND))
        wall = max(WALL_FACTOR * float(time_limit), WALL_MIN)
        hard_deadline[0] = time.perf_counter() + wall + 0.05
        # a C++ condition (a Python one would be called from PRM's roadmap thread and deadlock on the GIL)
        stop.append(ob.timedPlannerTerminationCondition(wall))
        ss.solve(stop[0])
        stats["plan_time"] = ss.getLastPlanComputationTime()
        if not ss.haveExactSolutionPath():
            return None
        path = ss.getSolutionPath()
        raw = np.array([[s[i] for i in rng_idx] for s in path.getStates()], dtype=float)
        stats["raw_waypoints"] = len(raw)
        return raw
    finally:
        ou.setLogLevel(level)
