"""Certified collision checking of a joint-space motion, *including the motion between samples*.

By default the configuration moves linearly in joint space between two samples; the judge passes its own
motion (``SweepChecker.check(..., path=, at=)``, docs/checker.md "The motion"). For every collision pair p a
bound W_p · |Δq| on how far any point of one object can move relative to the other is precomputed from the
kinematic tree (lever arms from each joint to the farthest point of each downstream geometry; prismatic joints
count 1 m/m). Conservative advancement then certifies the motion: after an exact distance d at some instant,
the pair cannot touch until the accumulated bound exceeds d − margin, so most pairs need a distance query only
every few dozen samples, and a pair that comes close is advanced in sub-sample steps until it either clears or
touches. The result is exact up to ``tolerance`` metres (default 1e-6): a contact that lasts less than that is
not reported.

Bodies of revolution tighten the bounds: distances depend only on the space a body occupies, and a
sphere, cylinder, capsule or cone turning about its own axis of symmetry does not move that space. So
(1) a geometry that is a body of revolution about the axis of the revolute joint it hangs from does not
count that joint's motion (:func:`lever_arms`), and (2) for a self pair whose upper body is a body of
revolution about the axis of the first joint between the two, that joint does not count either: the
relative pose then changes only by a rotation the upper body does not see. Modular arms are built this
way (a joint housing coaxial with its joint), and links sliding past a housing at a few µm would
otherwise be advanced in µm steps (IMPROV: one PTP_3 check 4.8 s → 0.2 s).

With ``posed_arms`` (the judge's) the queries at the samples are scheduled with lever arms of the motion's own
poses (:class:`~robodesign.model.sweep_bounds.PosedArms`: each geometry's distance from each joint axis at the
samples, by batched forward kinematics, plus what the joints below can move it over the step), never larger than
the static ones, and a pair's certificate goes on past the end of the summed bounds while one geometry's
displacement from its pose at the query, relative to the other (at the samples, plus the step's bound), stays
below the clearance less 4·tolerance (:meth:`PosedArms.extend <robodesign.model.sweep_bounds.PosedArms.extend>`).
Inside a step the static bound stays: a contact is found in the same step, from a query at the same sample, as without
them. Only GJK's warm start (it follows the queries made before on the pair) can move the instant found inside
a grazing contact, by about the tolerance over the rate of approach. No pair is queried over the steps that lower
bounds of its clearance certify (:mod:`~robodesign.model.sweep_clearance`: the obstacles' distance fields, the
geometries' bounding spheres).
"""
from __future__ import annotations

import threading
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Callable, Collection, Iterable, List, Optional, Sequence, Set, Tuple

import numpy as np
import pinocchio as pin

from robodesign.model.revolution import _revolute_axis, _symmetric
from robodesign.model.robot import Robot, vector_norm
from robodesign.model.sweep_bounds import PosedArms, StaticSteps
from robodesign.model.sweep_clearance import DueQueue, open_steps, robot_spheres
from robodesign.model.sweep_rebase import keep, rebased
from robodesign.model.sweep_scratch import KeptScratch


@dataclass(frozen=True)
class CollisionEvent:
    sample: int  # segment start index
    s: float  # fraction of the segment [sample, sample+1] where contact happens (0 = at the sample)
    first: str  # object names
    second: str
    distance: float
    environment: bool  # robot–obstacle (True) or self (False)


def _shape_radius(geometry) -> float:
    geometry.computeLocalAABB()
    bb = geometry.aabb_local
    m = np.maximum(np.abs(np.asarray(bb.min_)), np.abs(np.asarray(bb.max_)))
    return float(np.linalg.norm(m))


#: how far SweepChecker._ahead queries: where the path bound from the last query reaches 1.6× its clearance (on
#: the 350-sample PTP_3 check: mesh queries 150 → 117; with 1.2: 133, 2: 174, 3: 249; a failed try costs one query)
_AHEAD = 1.6
_EXTEND_SELF = True  # extend the certificates of self pairs too (PosedArms.certify)


_RADII: dict = {}  # id(shape) → (shape, _shape_radius(shape)): the shapes are the module sets' (shared)


class _Tree:
    """The robot's joints and collision geometries read once from pinocchio (its accessors cost µs each)."""

    def __init__(self, robot: Robot):
        model, gm = robot.model, robot.geom_model
        self.nj = model.njoints
        joints = [model.joints[j] for j in range(self.nj)]
        self.parents = [int(p) for p in model.parents]
        self.idx_v = [int(jm.idx_v) for jm in joints]
        self.names = [jm.shortname() for jm in joints]
        self.axes: List[Optional[np.ndarray]] = [None]
        self.axes += [_revolute_axis(jm) for jm in joints[1:]]
        self.placements = [model.jointPlacements[j] for j in range(self.nj)]
        objs = [gm.geometryObjects[g] for g in range(robot.n_collision_geometries)]
        self.geom_joint = [int(o.parentJoint) for o in objs]
        self.geom_kind = [type(o.geometry).__name__ for o in objs]
        self.geom_placement = [o.placement for o in objs]
        self.geom_geometry = [o.geometry for o in objs]
        self.ext = [0.0] * self.nj  # stroke bound of prismatic joints
        self.prismatic = [False] * self.nj
        for j in range(1, self.nj):
            name = self.names[j]
            if "Prismatic" in name or name.endswith("PZ") or name.endswith("PX") or name.endswith("PY"):
                self.prismatic[j] = True
                k = joints[j].idx_q
                lo, hi = model.lowerPositionLimit[k], model.upperPositionLimit[k]
                self.ext[j] = max(abs(lo), abs(hi)) if np.isfinite(lo) and np.isfinite(hi) else 1e3

    @cached_property
    def radii(self) -> List[float]:
        """Per geometry, its radius about its frame's origin (:func:`_shape_radius`, computed once per shape: the
        module sets' shapes are shared by every robot built of them)."""
        out = []
        for geo in self.geom_geometry:
            hit = _RADII.get(id(geo))
            if hit is None or hit[0] is not geo:
                if len(_RADII) >= 4096:
                    _RADII.clear()
                hit = _RADII[id(geo)] = (geo, _shape_radius(geo))
            out.append(hit[1])
        return out

    @cached_property
    def _norms(self) -> Tuple[List[float], List[float]]:
        """|translation| of every joint placement and of every geometry placement."""
        return ([vector_norm(p.translation) for p in self.placements],
                [vector_norm(p.translation) for p in self.geom_placement])

    def own_axis_symmetric(self) -> List[bool]:
        return list(self._own_axis_symmetric)

    @cached_property
    def _own_axis_symmetric(self) -> List[bool]:
        out = []
        for g, j in enumerate(self.geom_joint):
            axis = self.axes[j] if j > 0 else None
            out.append(axis is not None and _symmetric(self.geom_kind[g], self.geom_placement[g], np.zeros(3), axis))
        return out

    def lever_arms(self, symmetry: bool, dof: int) -> np.ndarray:
        R = np.zeros((dof, len(self.geom_joint)))
        joint_norm, geom_norm = self._norms
        radii = self.radii
        for g, j in enumerate(self.geom_joint):
            reach = geom_norm[g] + radii[g]
            # walk up: reach = distance bound from joint j's origin to any point of g
            while j > 0:
                R[self.idx_v[j], g] = 1.0 if self.prismatic[j] else reach
                reach += joint_norm[j] + self.ext[j]
                j = self.parents[j]
        for g, sym in enumerate(self._own_axis_symmetric):
            if sym and symmetry:
                R[self.idx_v[self.geom_joint[g]], g] = 0.0
        return R

    def coaxial_child_joints(self) -> List[set]:
        out: List[Set[int]] = [set() for _ in self.geom_joint]
        for j in range(1, self.nj):
            axis = self.axes[j]
            if axis is None:
                continue
            M = self.placements[j]
            point, direction = np.asarray(M.translation, dtype=float), np.asarray(M.rotation, dtype=float) @ axis
            for g, gj in enumerate(self.geom_joint):
                if gj == self.parents[j] and _symmetric(self.geom_kind[g], self.geom_placement[g], point, direction):
                    out[g].add(j)
        return out

    def ancestors(self) -> List[Set[int]]:
        """Per geometry: the pinocchio joint ids it hangs from."""
        out = []
        for j in self.geom_joint:
            s = set()
            while j > 0:
                s.add(j)
                j = self.parents[j]
            out.append(s)
        return out


def own_axis_symmetric(robot: Robot) -> List[bool]:
    """Per robot geometry g: a body of revolution about the axis of the revolute joint it hangs from, so that
    this joint's motion does not move the space g occupies."""
    return _Tree(robot).own_axis_symmetric()


def lever_arms(robot: Robot, symmetry: bool = True) -> np.ndarray:
    """R[j, g]: bound on how far the space occupied by robot geometry g moves per unit motion of joint j
    (0 if g is not downstream of j). Joint indices are velocity indices (0..dof-1). It is the displacement
    bound of g's points, except that a geometry that is a body of revolution about the axis of its own
    (revolute) joint gets 0 for that joint: its points move but the space it fills does not, and distances
    depend only on that space (:func:`own_axis_symmetric`). ``symmetry=False``: the plain point bound."""
    return _Tree(robot).lever_arms(symmetry, robot.dof)


def coaxial_child_joints(robot: Robot) -> List[set]:
    """Per robot geometry g: the revolute joints hanging directly from g's joint whose axis (fixed in g's
    frame) g is a body of revolution about; the motion of such a joint does not change g's distance to
    anything that hangs below it."""
    return _Tree(robot).coaxial_child_joints()


def _pair_arms(tree: "_Tree", R: np.ndarray, ab: List[Tuple[int, int]], env: np.ndarray, symmetry: bool,
               dof: int) -> Tuple[np.ndarray, np.ndarray]:
    """(W, owner) (dof, P) of the pairs ``ab`` (geometry a, geometry or obstacle b; ``env``: b is an obstacle):
    a robot–obstacle pair has a's lever arms (owner a on every joint); a self pair the arms of the joints only a
    hangs from (owner a) and of those only b hangs from (owner b), 0 elsewhere (owner −1), and 0 for the first
    joint below the upper body when that body is a body of revolution about its axis (``symmetry``)."""
    G, P = R.shape[1], len(ab)
    A = np.array([a for a, _ in ab], dtype=int).reshape(P)
    B = np.array([b for _, b in ab], dtype=int).reshape(P)
    anc = np.zeros((G, dof), dtype=bool)  # anc[g, v]: g hangs from the joint of velocity index v
    cox = np.zeros((G, dof), dtype=bool)  # cox[g, v]: coaxial_child_joints of g
    for g, js in enumerate(tree.ancestors()):
        anc[g, [tree.idx_v[j] for j in js]] = True
    if symmetry:
        for g, js in enumerate(tree.coaxial_child_joints()):
            cox[g, [tree.idx_v[j] for j in js]] = True
    W, owner = np.zeros((dof, P)), np.full((dof, P), -1)
    W[:, env], owner[:, env] = R[:, A[env]], A[env]
    s = ~env
    a, b = A[s], B[s]
    only_a, only_b = (anc[a] & ~anc[b]).T, (anc[b] & ~anc[a]).T  # (dof, self pairs)
    Ws = np.where(only_a, R[:, a], np.where(only_b, R[:, b], 0.0))
    # the first joint below the upper body: a body of revolution about its axis sees no motion
    Ws[(cox[a].T & only_b) | (cox[b].T & only_a)] = 0.0
    W[:, s], owner[:, s] = Ws, np.where(only_a, a, np.where(only_b, b, -1))
    return W, owner


_SETUPS: dict = {}  # _setup_key → (module set, _setup's attributes): the set-up of robots built alike
_SETUPS_LOCK = threading.Lock()


def _setup_key(robot: Robot, flags: tuple) -> Optional[tuple]:
    """What the checker's set-up of ``robot`` depends on: its module set and assembly, base pose, safety margin
    and obstacles (their names; not their poses, which only the queries read), and the checker's flags. Robots
    built from the same of these are the same model and geometry (model.cell.build_robot, RobotPool). None: a
    robot without module set or assembly."""
    ms, assembly = getattr(robot, "module_set", None), getattr(robot, "assembly", None)
    if ms is None or assembly is None:
        return None
    return (id(ms), assembly.key(), np.asarray(robot.base_pose, dtype=float).tobytes(),
            float(getattr(robot, "safety_margin", 0.0)), tuple(o.name for o in getattr(robot, "obstacles", ())),
            robot.dof, robot.n_collision_geometries, len(robot.geom_model.collisionPairs), flags)


_ARMS: dict = {}  # _setup_key(robot, (symmetry,)) → (module set, _every_pairs_arms's)
#: the robots' every-pair arms kept: a new arm's set-ups follow each other within one evaluation (planner, judge),
#: and few kept keep few objects alive (the set-ups themselves are kept in _SETUPS)
_ARMS_KEPT = 8


def _every_pairs_arms(robot: Robot, symmetry: bool) -> tuple:
    """(tree, R, cps, is_env, W, owner) of every collision pair of ``robot``: its :class:`_Tree`, the lever arms,
    the pairs (geometry indices), whether each is a robot–obstacle pair, and :func:`_pair_arms` of them all (each
    pair's column depends on that pair alone), kept for robots built alike (:func:`_setup_key`; the
    :data:`_ARMS_KEPT` latest): a new arm's planner (:func:`pair_arms`) and judge (its obstacles, posed arms) take
    columns of the same."""
    def make() -> tuple:
        tree = _Tree(robot)
        R = tree.lever_arms(symmetry, robot.dof)
        cps = [(int(cp.first), int(cp.second)) for cp in robot.geom_model.collisionPairs]
        is_env = np.array([b >= robot.n_collision_geometries for _, b in cps], dtype=bool)
        return (tree, R, cps, is_env, *_pair_arms(tree, R, cps, is_env, symmetry, robot.dof))

    return _remembered(_ARMS, _ARMS_KEPT, _setup_key(robot, (symmetry,)), robot, make)


def _remembered(store: dict, limit: int, key: Optional[tuple], robot: Robot, make: Callable[[], Any]) -> Any:
    """``store[key]``'s value for robots built alike (:func:`_setup_key`; held with the robot's module set, so an
    entry of another module set at a reused id is made again), else ``make()``, kept there (the ``limit`` latest
    entries; none when ``key`` is None)."""
    hit = store.get(key) if key is not None else None
    if hit is None or hit[0] is not robot.module_set:
        hit = (getattr(robot, "module_set", None), make())
        if key is not None:
            with _SETUPS_LOCK:
                store[key] = hit
                while len(store) > limit:
                    store.pop(next(iter(store)))
    return hit[1]


def _setup(robot: Robot, check_self: bool, check_env: bool, obstacles: Optional[Collection[int]], symmetry: bool,
           posed_arms: bool) -> dict:
    """The checker's pairs, their bounds and names (SweepChecker.__init__), as attributes."""
    gm = robot.geom_model
    n_self = robot.n_self_collision_pairs
    tree, R, cps, every_env, every_W, every_owner = _every_pairs_arms(robot, symmetry)
    pairs: List[int] = []
    if check_self:
        pairs += list(range(n_self))
    if check_env:
        env: Sequence[int] = range(n_self, len(cps))
        if obstacles is not None:
            keep = {robot.obstacle_geometry_ids[i] for i in obstacles}
            env = [k for k in env if cps[k][1] in keep]
        pairs += list(env)
    n_robot = robot.n_collision_geometries
    margins = np.zeros(len(pairs))
    is_env, W, owner = every_env[pairs], every_W[:, pairs], every_owner[:, pairs]
    margins[is_env] = getattr(robot, "safety_margin", 0.0)
    posed = PosedArms(robot, tree, R) if posed_arms else None
    # per pair for the posed bounds' displacement (PosedArms.extend): the geometry that moves (the smaller box)
    # in the frame of the other (-1: an obstacle's, the world)
    mov: List[int] = []
    ref: List[int] = []
    obst = [cps[k][1] if b else -1 for k, b in zip(pairs, is_env)]  # the obstacle of a robot–obstacle pair
    if posed is not None:
        box = posed.box_half_diagonal
        for k in pairs:
            a, b = cps[k]
            m, r = (a, -1) if b >= n_robot else (a, b) if box[a] <= box[b] else (b, a)
            mov.append(m)
            ref.append(r)
        posed = posed.bound_to(None)  # (the template holds no robot)
    names = [o.name for o in gm.geometryObjects]
    return {"pairs": pairs,  # what distances() queries: collision pair indices here
            "margins": margins, "is_env": is_env, "W": W, "_owner": owner, "_posed": posed, "_mov": mov,
            "_ref": ref, "pair_names": [(names[cps[k][0]], names[cps[k][1]]) for k in pairs], "_obst": obst,
            "_spheres": robot_spheres(tree.geom_geometry) if posed is not None else None}


def _cached_setup(robot: Robot, check_self: bool, check_env: bool, obstacles: Optional[Collection[int]],
                  symmetry: bool, posed_arms: bool) -> dict:
    """:func:`_setup`, shared by robots built alike (:func:`_setup_key`; the 64 latest kept)."""
    key = _setup_key(robot, (check_self, check_env, None if obstacles is None else tuple(obstacles), symmetry,
                             posed_arms))

    def make() -> dict:
        setup = rebased(robot, key) if key is not None else None   # (a robot built alike at another base pose's)
        return setup if setup is not None else \
            keep(robot, key, _setup(robot, check_self, check_env, obstacles, symmetry, posed_arms))

    return _remembered(_SETUPS, 64, key, robot, make)


def pair_arms(robot: Robot) -> np.ndarray:
    """(dof, collision pairs) the static bounds W of :class:`SweepChecker` for every collision pair of the robot
    (column k: collision pair k): the distance of pair k changes by at most ``|q' − q| · W[:, k]`` between any two
    configurations q and q' (along the straight segment between them, every point of one body moves by at most that
    relative to the other; an obstacle stands still)."""
    return _cached_setup(robot, True, True, None, True, False)["W"]


def _picker(cols: Sequence[int], n: int) -> Callable:
    """x ↦ the items ``cols`` of x (a sequence of n, or an array of n along its first axis) as a new list or a new
    array laid out as numpy's fancy indexing lays it out (C order; SweepChecker.subset takes a matrix's columns
    through its transpose): a slice where ``cols`` is a range of step 1 within 0 … n (the judge's: the self pairs,
    the obstacle pairs), else item by item."""
    if isinstance(cols, range) and cols.step == 1 and 0 <= cols.start and cols.stop <= n:
        sl = slice(cols.start, max(cols.start, cols.stop))
        return lambda x: x[sl].copy() if isinstance(x, np.ndarray) else list(x[sl])
    idx = list(cols)
    return lambda x: x[idx] if isinstance(x, np.ndarray) else [x[c] for c in idx]


class SweepChecker:
    """Checks motions of one robot against itself and its obstacles (``robot.set_obstacles``)."""

    # the set-up (_setup, shared by robots built alike)
    pairs: Sequence[object]  # what distances() queries: collision pair indices here
    margins: np.ndarray
    is_env: np.ndarray
    W: np.ndarray
    _owner: np.ndarray
    _posed: Optional[PosedArms]
    _mov: List[int]
    _ref: List[int]
    _obst: List[int]  # the obstacle geometry of a robot–obstacle pair, −1 for a self pair
    _spheres: Optional[Tuple[np.ndarray, np.ndarray]]  # the robot geometries' spheres (sweep_clearance)
    pair_names: List[Tuple[str, str]]

    def __init__(self, robot: Robot, check_self: bool = True, check_env: bool = True, tolerance: float = 1e-6,
                 max_substeps: int = 2000, obstacles: Optional[Collection[int]] = None, symmetry: bool = True,
                 posed_arms: bool = False, scratch: Optional[KeptScratch] = None):
        """``obstacles``: indices into ``robot.obstacles`` whose robot–obstacle pairs are checked (None: all).
        ``symmetry``: use bodies of revolution to tighten the bounds (module docstring); False gives the plain
        lever-arm bounds (same verdicts, more distance queries). ``posed_arms``: schedule the distance queries
        with the lever arms of the motion's own poses (:class:`~robodesign.model.sweep_bounds.PosedArms`; the same
        events, fewer queries). ``scratch``: a kept scratch space of the robot's geometry, lent to this checker alone."""
        self.robot = robot
        self.tolerance = tolerance
        self.max_substeps = max_substeps
        gm = robot.geom_model
        self.__dict__.update(_cached_setup(robot, check_self, check_env, obstacles, symmetry, posed_arms))
        if self._posed is not None:  # the template's, bound to this robot (its motion caches empty)
            self._posed = self._posed.bound_to(robot)
        self._gm = gm  # (the robot's; its scratch space below)
        self._req = pin.GeometryData(gm) if scratch is None else scratch.lend()
        self._asked = None if scratch is None else scratch.asked   # (the pairs asked in a kept scratch space)
        self.queries = 0  # pair distances computed (a measure of the work, for benchmarks and tests)

    def subset(self, cols: Sequence[int]) -> "SweepChecker":
        """A checker of the pairs ``cols`` (indices into :attr:`pairs`, in that order) sharing this one's bounds
        and scratch space: its events are exactly those this checker reports for these pairs (each pair is
        advanced on its own), without building the bounds again."""
        out = object.__new__(type(self))
        out.__dict__.update(self.__dict__)
        pick = _picker(cols, len(self.pairs))
        out.pairs = pick(self.pairs)
        out.W = pick(self.W.T).T
        if getattr(self, "_owner", None) is not None:  # (RobotPairSweep has none)
            out._owner = pick(self._owner.T).T
        out.margins, out.is_env = pick(self.margins), pick(self.is_env)
        out.pair_names = pick(self.pair_names)
        if getattr(self, "_mov", None):
            out._mov, out._ref, out._obst = (pick(x) for x in (self._mov, self._ref, self._obst))
        out.queries = 0
        return out

    # ------------------------------------------------------------------------------------------
    def distances(self, q: np.ndarray, cols: Sequence[int]) -> np.ndarray:
        """Exact distances at configuration q of the checked pairs with indices ``cols``."""
        r, gm, gd, pairs = self.robot, self._gm, self._req, self.pairs
        pin.updateGeometryPlacements(r.model, r.data, gm, gd, q)
        distance = pin.computeDistance
        if self._asked is not None:   # (a kept scratch space: sweep_scratch)
            self._asked.update([pairs[c] for c in cols])
        out = np.array([distance(gm, gd, pairs[c]).min_distance for c in cols], dtype=float)
        self.queries += len(out)
        return out

    def distance(self, q: np.ndarray, c: int) -> float:
        """:meth:`distances` of the one pair with index c (the same number, without the array)."""
        return self._pair_query(c)(q)

    def _pair_query(self, c: int) -> Callable[[np.ndarray], float]:
        """The distance at a configuration of the pair with index c (:meth:`distances`'s number, counted in
        :attr:`queries`), with what the query reads looked up once (:meth:`_advance`'s sub-steps)."""
        model, data, gm, gd, pair = self.robot.model, self.robot.data, self._gm, self._req, self.pairs[c]
        place, distance = pin.updateGeometryPlacements, pin.computeDistance
        if self._asked is not None:
            self._asked.add(pair)

        def query(q: np.ndarray) -> float:
            place(model, data, gm, gd, q)
            self.queries += 1
            return distance(gm, gd, pair).min_distance
        return query

    def check(self, Q: np.ndarray, first_only: bool = True, path: Optional[np.ndarray] = None,
              at: Optional[Callable[[int, float], np.ndarray]] = None,
              poses: Optional[np.ndarray] = None) -> List[CollisionEvent]:
        """Collision events along a motion through the rows of Q: by default the piecewise-linear one.

        Another motion through the same samples is given by ``at(k, s)`` (q at fraction s ∈ [0, 1] of step k)
        and ``path`` (n−1, dof): per step and joint a bound on the joint's speed per unit of s, so that it moves
        at most ``path·|s' − s|`` between any two fractions s, s' of the step (|ΔQ| for the linear motion; the
        judge's motion: h·max|q̇|). Conservative advancement then certifies that motion: from an exact distance at
        an instant the pair stays free while the accumulated path bounds stay below the clearance.
        With ``first_only`` the search stops at the earliest event; otherwise one event is reported per pair
        and contact episode (the pair is re-armed once it separates again). ``poses``: ``robot.joint_poses_batch(Q)``
        if the caller has it (the posed bounds read it).
        """
        Q = np.asarray(Q, dtype=float)
        n = len(Q)
        P = len(self.pairs)
        if P == 0 or n == 0:
            return []
        if n == 1:
            return self._at_one_sample(Q[0], first_only)
        seg, sched, cum, cum_rows, TG = self._bounds(Q, path, poses)
        posed: Optional[PosedArms] = getattr(self, "_posed", None)  # (RobotPairSweep has none)
        ext = 4 * self.tolerance
        margins, is_env = self.margins.tolist(), self.is_env.tolist()
        events: List[CollisionEvent] = []
        skip = open_steps(self, TG, sched, seg.dQ, ext) if not first_only else None  # (sweep_clearance)
        queue = DueQueue(self, n, skip, cum_rows, TG, sched, ext, _EXTEND_SELF)  # every pair due at sample 0
        while True:
            k, due = queue.batch()
            if k < 0:
                break
            d = self.distances(Q[k], due)
            for c, dist, nxt in queue.settle(k, due, d):  # the pairs the queue does not reschedule itself
                free = dist - margins[c]
                if free <= 0:
                    events.append(CollisionEvent(k, 0.0, *self.pair_names[c], dist, bool(self.is_env[c])))
                    if first_only:
                        return events
                    again = self._rearm(Q, k, c, cum)
                    if again is not None:
                        queue.push(c, again)
                    continue
                # the pair is certified free until the accumulated bound exceeds `free`
                row = cum_rows[c]
                if nxt == -2:  # no posed bounds, or a clearance or bound that is no finite number
                    nxt = int(row.searchsorted(float(row[k]) + free, side="right")) - 1  # last sample certified
                    if TG is not None and posed is not None and nxt < n - 1 and (is_env[c] or _EXTEND_SELF):
                        nxt = posed.extend(TG, self._mov[c], self._ref[c], k, nxt, sched, cum_rows, c, free - ext)
                if nxt >= n - 1:
                    continue  # certified to the end
                if nxt > k:
                    ahead = is_env[c] and (skip is None or skip[c, nxt] == nxt)  # (not where the bounds go on)
                    nxt2 = self._ahead(Q, k, c, free, row, nxt) if ahead else nxt
                    if nxt2 is not None:
                        queue.push(c, nxt2)
                    continue
                # nxt == k: the very next segment moves more than the clearance → advance inside it
                hit = self._advance(Q[k], Q[k + 1], seg[k, c], c, free,
                                    None if at is None else (lambda s, k=k: at(k, s)))
                if hit is not None:
                    s, dist2 = hit
                    events.append(CollisionEvent(k, s, *self.pair_names[c], dist2, bool(self.is_env[c])))
                    if first_only:
                        continue  # another pair of this batch may touch earlier inside the same step
                    again = self._rearm(Q, k + 1, c, cum)
                    if again is not None:
                        queue.push(c, again)
                else:
                    queue.push(c, k + 1)
            if first_only and events:  # every pair was certified free up to sample k: the earliest is here
                return [min(events, key=lambda e: e.s)]
        events.sort(key=lambda e: (e.sample, e.s))
        return events

    def _at_one_sample(self, q: np.ndarray, first_only: bool) -> List[CollisionEvent]:
        """:meth:`check` of a motion of one sample: the pairs in contact there."""
        d = self.distances(q, range(len(self.pairs)))
        return [CollisionEvent(0, 0.0, *self.pair_names[c], float(d[c]), bool(self.is_env[c]))
                for c in np.nonzero(d <= self.margins)[0]][: 1 if first_only else None]

    def _bounds(self, Q: np.ndarray, path: Optional[np.ndarray], poses: Optional[np.ndarray] = None) -> tuple:
        """(seg, sched, cum, cum_rows, TG) of :meth:`check`: the step bounds (n−1, P), the schedule's (the posed
        ones where given), its running sums (n, P) and their rows per pair, and the geometry poses (None: no
        displacement extension)."""
        dQ = np.abs(np.diff(Q, axis=0)) if path is None else np.maximum(np.asarray(path, dtype=float),
                                                                           np.abs(np.diff(Q, axis=0)))
        posed = getattr(self, "_posed", None)  # (RobotPairSweep has none)
        # the schedule of the sample queries: the posed bounds where given; inside a step (_advance) always seg
        # (dQ @ W), so that every contact is found from the same sample with the same sub-steps (module docstring)
        seg = StaticSteps(dQ, self.W)
        if posed is None:
            sched = seg.array()
            cum = np.concatenate([np.zeros((1, len(self.pairs))), np.cumsum(sched, axis=0)])  # (n, P)
            cum_rows = np.ascontiguousarray(cum.T)  # per pair, contiguous (the same numbers): a fast searchsorted
        else:
            sched, cum_rows = posed.schedule(Q, dQ, self.W, self._owner, poses)
            sched, cum = np.ascontiguousarray(sched), cum_rows.T
        # with the posed bounds, a pair's certificate where the path bound ends is extended by the displacement from
        # the sample's pose (PosedArms.extend) while that stays below the clearance less 4·tolerance: such steps
        # keep more than the tolerance, so no sub-step query inside them finds a contact
        TG = posed.poses() if posed is not None and getattr(self, "_mov", None) else None
        return seg, sched, cum, cum_rows, TG

    def _ahead(self, Q, k: int, c: int, free: float, row: np.ndarray, nxt: int) -> Optional[int]:
        """Far from contact (pair c free by ``free`` at sample k, certified up to sample ``nxt``): one query at the
        sample m where the path bound from k reaches :data:`_AHEAD` × ``free``, to certify both before and after
        it. The pair's distance changes by at most the path bound between two points, and every point of a step
        is within its bound of both ends (linear in the fraction), so clearances free at k and free_m at m
        certify all of [k, m] when free + free_m ≥ row[m] − row[k]. Then the next query is where m's certificate
        ends (None: certified to the end); otherwise, as without this query, ``nxt``. Used for the
        robot–obstacle pairs, whose mesh queries cost ~15× a self pair's."""
        n = len(row)
        m = min(int(row.searchsorted(float(row[k]) + _AHEAD * free, side="right")) - 1, n - 1)
        if m <= nxt + 1:
            return nxt
        free_m = float(self.distances(Q[m], [c])[0]) - float(self.margins[c])
        if free_m <= 0 or free + free_m < float(row[m]) - float(row[k]):
            return nxt
        after = int(row.searchsorted(float(row[m]) + free_m, side="right")) - 1
        return None if m >= n - 1 or after >= n - 1 else max(after, m)

    def _rearm(self, Q, k, c, cum) -> Optional[int]:
        """After a contact, skip ahead to the first sample where the pair is free again."""
        n = len(Q)
        for kk in range(k + 1, n):
            dist = self.distances(Q[kk], [c])[0]
            if dist - self.margins[c] > 0:
                return kk
        return None

    def _advance(self, qa, qb, bound, c, free, at=None) -> Optional[tuple]:
        """Conservative advancement of pair c along qa→qb (displacement bound ``bound``; ``at(s)``: the
        configuration at fraction s, default the linear interpolation)."""
        s = 0.0
        tol, margin, query = self.tolerance, self.margins[c], self._pair_query(c)
        for _ in range(self.max_substeps):
            s += free / bound
            if s >= 1.0:
                return None
            dist = query(qa + s * (qb - qa) if at is None else at(s))
            free = dist - margin
            if free <= tol:
                return s, float(dist)
        return s, float(free + margin)  # could not certify: report as contact

    def in_contact(self, q: np.ndarray, names: Iterable[Tuple[str, str]]) -> Set[Tuple[str, str]]:
        """Which of the pairs named ``names`` are in contact (within their margin) at configuration q."""
        cols = [self.pair_names.index(p) for p in names]
        d = self.distances(np.asarray(q, dtype=float), cols)
        return {self.pair_names[c] for c, dist in zip(cols, d) if dist <= self.margins[c]}

    def sample_collisions(self, Q) -> np.ndarray:
        """Boolean per sample: in collision at the sample itself (no in-between reasoning)."""
        out = np.zeros(len(Q), dtype=bool)
        for k, q in enumerate(np.asarray(Q, dtype=float)):
            d = self.distances(q, range(len(self.pairs)))
            out[k] = bool(np.any(d <= self.margins))
        return out
