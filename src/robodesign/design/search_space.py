"""The design space an optimizer searches: module orders (under rules) × base poses.

A :class:`SearchSpace` knows the module set, the rules (DoF range, at most ``max_links_between``
passive link modules between two joint modules, allowed bases/end effectors) and the base-pose
bounds derived from the task's base-placement tolerance. It offers what optimizer plugins need:
validity checks with reasons, successors of a partial order (for tree search), random candidates,
exhaustive enumeration and base-pose parameters ↔ 4x4 poses. For informed search it also offers
per-module data (:meth:`SearchSpace.module_info`), counts and lightest completions of partial orders,
an admissible lower bound of a cost for every completion of a partial order
(:meth:`SearchSpace.cost_lower_bound`) and the reach stage's reach bound of a candidate
(:meth:`SearchSpace.reach_bound`).

Chaining: a serial order attaches each module to a *free* connector of the previous one (the one not
used by its own attachment); ``successors`` applies the rule of :func:`robodesign.formats.assembly.chain_step`,
the one :meth:`Assembly.from_order` applies, so every order it generates assembles.

A :class:`Candidate` is plain data: ``order`` (module IDs, base first) and ``base`` (offsets
x, y, z [m], yaw [rad] relative to the nominal base pose; empty when the base is fixed).
"""
from __future__ import annotations

import math
import weakref
from dataclasses import dataclass, field
from functools import lru_cache
from typing import FrozenSet, Iterator, List, Optional, Sequence, Tuple, cast

import numpy as np

from robodesign.core.errors import AssemblyError, InputError
from robodesign.design.base_bounds import BaseBounds, BaseProposals, beyond_reach, clearance_spheres  # noqa: F401 - BaseBounds: its import path
from robodesign.formats.assembly import Assembly, chain_pairs, chain_step, free_connectors, next_compatible
from robodesign.formats.geometry import contains_point
from robodesign.formats.module_spec import ModuleSet
from robodesign.model.extent import module_extent

BASE_PARAMS = ("x", "y", "z", "yaw")
_NO_MODULE = object()  # free connectors of a prefix whose first module is not in the module set
_MISS = object()
_DEAD_END: Tuple[Tuple[str, ...], dict, tuple, dict] = ((), {}, (), {})  # SearchSpace._step of a state that nothing may follow
_CACHE_LIMIT = 1 << 16  # entries of a per-order/per-prefix memo before it is cleared

@dataclass(frozen=True)
class ModuleInfo:
    """What an optimizer may know about one module: ``kind`` ('base', 'joint', 'link' or 'eef'), ``dof``
    (actuated joints), ``mass`` [kg] (sum of its bodies, as in the checker's ``mass`` cost), ``torque`` [Nm]
    (the largest torque limit of its actuated joints, 0 without one) and ``span`` [m] (an upper bound of the
    distance it spans in a chain, over every joint position: :func:`~robodesign.model.extent.module_extent`)."""
    id: str
    name: str
    kind: str
    dof: int
    mass: float
    torque: float = 0.0
    span: float = 0.0


@dataclass(frozen=True)
class Candidate:
    order: Tuple[str, ...]
    base: Tuple[float, ...] = ()

    def key(self) -> str:
        b = ",".join(f"{v:.6f}" for v in self.base)
        return ",".join(self.order) + (f"@{b}" if b else "")

    def to_json(self) -> dict:
        return {"order": list(self.order), "base": list(self.base)}


@dataclass(frozen=True, eq=False)
class SearchSpace:
    module_set: ModuleSet
    min_dof: int = 6
    max_dof: int = 6
    max_links_between: int = 1
    max_modules: int = 16
    bases: Optional[Tuple[str, ...]] = None  # allowed base modules (None: all)
    end_effectors: Optional[Tuple[str, ...]] = None
    exclude: Tuple[str, ...] = ()
    base_bounds: BaseBounds = field(default_factory=BaseBounds)
    #: the task's goal positions as (x, y, z, position tolerance) in the world (for :meth:`sample_base`,
    #: :meth:`reach_shortfall`, :meth:`informed_candidate`; empty: no geometric guidance)
    goals: Tuple[Tuple[float, float, float, float], ...] = ()
    #: the static obstacles' collision geometry (GeometrySpec); a sampled base position stays out of them
    obstacles: Tuple = ()
    #: the pose directions a goal fixes that a design's tool must move in (6 when a goal fixes position and
    #: orientation, solvers.ik.fixes_full_pose; 0: none) — :meth:`rank_deficit`, :meth:`informed_candidate`
    goal_rank: int = 0

    # -- module orders ------------------------------------------------------------------------
    def _allowed(self, mid: str) -> bool:
        if mid in self.exclude:
            return False
        m = self.module_set[mid]
        if m.kind == "base" and self.bases is not None:
            return mid in self.bases
        if m.kind == "eef" and self.end_effectors is not None:
            return mid in self.end_effectors
        return True

    @property
    def base_modules(self) -> Tuple[str, ...]:
        return tuple(m.id for m in self.module_set.of_kind("base") if self._allowed(m.id))

    def _followers(self, mid: str) -> Tuple[str, ...]:
        cache = self._cache("_memo_followers")
        out = cache.get(mid)
        if out is None:
            out = cache[mid] = _followers(self.module_set, mid, self.exclude, self.bases, self.end_effectors)
        return out

    def _state(self, prefix: Sequence[str]) -> Tuple[int, int, bool]:
        """(dof so far, links since the last joint, complete)"""
        if not prefix:
            return 0, 0, False
        _, _, dof, links, _, complete = self._prefix_state(tuple(map(str, prefix)))
        return dof, links, complete

    def successors(self, prefix: Sequence[str]) -> List[str]:
        """Modules that may follow ``prefix`` (a valid partial order) under the rules: the next module
        must mate (exactly one connector pair) with a free connector of the last module."""
        if not prefix:
            return list(self.base_modules)
        last, free, dof, links, n, complete = self._prefix_state(tuple(map(str, prefix)))
        if complete:
            return []
        if free is _NO_MODULE:  # the first module is not in the module set
            free_connectors(self.module_set, str(prefix[0]))  # raises the KeyError
        if free is None:
            return []
        return list(self._step((last, free, dof, links, n))[0])

    # -- chaining (internal) -------------------------------------------------------------------------
    def _prefix_state(self, prefix: Tuple[str, ...]):
        """(last module, its free connectors, dof, links since the last joint, length, complete) of a non-empty
        ``prefix`` of module IDs, computed step by step from its parent's and memoized. Free connectors are
        None once a step does not mate with exactly one connector pair (chaining stops there), and
        ``_NO_MODULE`` when the first module is unknown; an unknown later module raises KeyError (as
        ``_state`` did). Any prefix is accepted, not only valid ones: dof and links count joint and link
        modules after the first one, whatever the rules say."""
        cache = self._cache("_memo_prefix")
        st = cache.get(prefix)
        if st is not None:
            return st
        # the longest memoized proper prefix, then one step per module after it
        i = len(prefix) - 1
        while i > 0 and prefix[:i] not in cache:
            i -= 1
        ms = self.module_set
        if i == 0:
            mid = prefix[0]
            st = (mid, free_connectors(ms, mid) if mid in ms else _NO_MODULE, 0, 0, 1, False)
            i = 1
            new = [(prefix[:1], st)]
        else:
            st = cache[prefix[:i]]
            new = []
        for j in range(i, len(prefix)):
            prev, free, dof, links, n, _ = st
            mid = prefix[j]
            m = ms[mid]
            k = m.kind
            if k == "joint":
                dof += m.dof
                links = 0
            elif k == "link":
                links += 1
            if free is not None and free is not _NO_MODULE:  # then the free connectors (mypy cannot narrow it)
                free = _mate_step(ms, prev, cast(Tuple[str, ...], free), mid)
            st = (mid, free, dof, links, n + 1, k == "eef")
            new.append((prefix[:j + 1], st))
        if len(cache) + len(new) > _CACHE_LIMIT:
            cache.clear()
        cache.update(new)
        return st

    def _next(self, state) -> List[Tuple[str, Optional[tuple]]]:
        """(module, state after appending it or None when it completes the order) for every module that may
        follow a partial order in ``state`` = (last module, its free connectors, dof, links since the last
        joint, number of modules)."""
        return list(self._step(state)[2])

    def _step(self, state):
        """``_next(state)`` memoized per state, as (module IDs, {module ID: state after it}, the (module, state)
        pairs, {module ID: modules that would mate with a connector ``state``'s last module keeps free once
        that module is attached}); see :meth:`random_order` for the last one."""
        cache = self._cache("_memo_next")
        hit = cache.get(state)
        if hit is not None:
            return hit
        last, free, dof, links, n = state
        out = []
        if n < self.max_modules:
            ms = self.module_set
            for nxt in self._followers(last):
                nfree = _mate_step(ms, last, free, nxt)
                if nfree is None:
                    continue
                m = ms[nxt]
                if m.kind == "eef":
                    if self.min_dof <= dof <= self.max_dof:
                        out.append((nxt, None))
                elif m.kind == "joint":
                    if dof + m.dof <= self.max_dof:
                        out.append((nxt, (nxt, nfree, dof + m.dof, 0, n + 1)))
                elif m.kind == "link":
                    if links < self.max_links_between and n + 2 <= self.max_modules:
                        out.append((nxt, (nxt, nfree, dof, links + 1, n + 1)))
        after, blocks = {}, {}
        for nxt, st in out:
            if nxt not in after:
                after[nxt] = st
                (c_old, _), = chain_pairs(self.module_set, last, free, nxt)  # exactly one: _mate_step mated
                blocks[nxt] = self._mating(last, tuple(c for c in free if c != c_old.id))
        hit = cache[state] = (tuple(nxt for nxt, _ in out), after, tuple(out), blocks)
        return hit

    def _mating(self, mid: str, free: Tuple[str, ...]) -> frozenset:
        """IDs of the modules that some connector pair would mate to ``mid`` over its ``free`` connectors."""
        cache = self._cache("_memo_mating")
        key = (mid, free)
        out = cache.get(key)
        if out is None:
            ms = self.module_set
            out = cache[key] = frozenset(m.id for m in ms if free and chain_pairs(ms, mid, free, m.id))
        return out

    def _cache(self, name: str) -> dict:
        """A memo dict stored on the (frozen) instance; not pickled (see ``__getstate__``)."""
        memo = self.__dict__.get(name)
        if memo is None:
            memo = {}
            object.__setattr__(self, name, memo)
        return memo

    def _memo(self) -> dict:
        return self._cache("_memo_cache")

    def __getstate__(self):
        # memo caches are rebuilt on demand: a space sent to a worker process carries only its fields
        return {k: v for k, v in self.__dict__.items() if not k.startswith("_memo")}

    def _completion(self, state) -> Tuple[int, float]:
        """(number of completions, mass of the lightest completion) of a partial order in ``state``."""
        memo = self._memo()
        hit = memo.get(state)
        if hit is not None:
            return hit
        count, lightest = 0, math.inf
        for nxt, st in self._step(state)[2]:
            mass = self.module_info(nxt).mass
            if st is None:
                count += 1
                lightest = min(lightest, mass)
            else:
                c, l = self._completion(st)
                count += c
                lightest = min(lightest, mass + l)
        memo[state] = (count, lightest)
        return count, lightest

    def _prefix_completion(self, prefix: Sequence[str]) -> Tuple[int, float]:
        prefix = tuple(str(x) for x in prefix)
        if not prefix:
            out = [self._prefix_completion((b,)) for b in self.base_modules]
            return (sum(c for c, _ in out),
                    min((self.module_info(b).mass + l for b, (_, l) in zip(self.base_modules, out)), default=math.inf))
        failed, state, _ = self._walk(prefix)
        if failed is not None:
            return 0, math.inf
        if state is None:  # complete
            return 1, 0.0
        return self._completion(state)

    # -- informed search ---------------------------------------------------------------------------
    def module_info(self, mid: str) -> ModuleInfo:
        """Kind, DoF and mass of module ``mid``."""
        cache = self._cache("_memo_info")
        info = cache.get(mid)
        if info is None:
            m = self.module_set[str(mid)]
            torque = max((j.limits.torque for j in m.joints if j.actuated), default=0.0)
            info = cache[mid] = ModuleInfo(id=m.id, name=m.name, kind=m.kind, dof=m.dof, mass=m.mass,
                                           torque=float(torque), span=module_extent(m))
        return info

    def count_completions(self, prefix: Sequence[str]) -> int:
        """Number of valid complete orders that start with ``prefix`` (1 for a complete order, 0 for a dead
        end or an invalid prefix; ``count_completions(())`` == :meth:`count_orders`)."""
        return self._prefix_completion(prefix)[0]

    def lightest_completion(self, prefix: Sequence[str]) -> float:
        """Smallest total mass [kg] of the modules that must be appended to ``prefix`` to make a valid
        complete order (0 for a complete order, ``inf`` when there is none). For ``()`` it is the mass of
        the lightest valid order."""
        return self._prefix_completion(prefix)[1]

    def cost_lower_bound(self, prefix: Sequence[str], cost) -> float:
        """A lower bound of cost ``cost`` (a CostFunction, e.g. ``problem.cost``, or a descriptor such as
        ``"Whit2"``, ``"mass"``, ``"cyc"``) of
        every feasible design whose order starts with ``prefix`` (any base pose; ``inf`` if ``prefix`` has no
        valid completion).

        Only quantities fixed by the order are bounded: ``mass`` by the prefix mass plus
        :meth:`lightest_completion` (exact for a complete order), ``numJ`` by max(DoF so far, ``min_dof``).
        The other built-in terms are ≥ 0 and contribute 0 (``fulfillP`` ≤ 1 contributes its weight when the
        weight is negative). A negative weight on an unbounded term, or an unknown (custom) term, makes
        the bound ``-inf``. So for ``mass``, ``numJ`` and ``Whit2`` the bound of a complete order *is* its cost.
        """
        from robodesign.formats.costs import cost_terms
        prefix = tuple(str(x) for x in prefix)
        terms = cost.terms if hasattr(cost, "terms") else _cost_terms(str(cost))
        count, lightest = self._prefix_completion(prefix)
        if count == 0:
            return math.inf
        mass = sum(self.module_info(m).mass for m in prefix)
        dof = self._state(prefix)[0] if prefix else 0
        lb = 0.0
        for name, w in terms:
            if w == 0:
                continue
            if name == "mass" and w > 0:
                lb += w * (mass + lightest)
            elif name == "numJ":
                lb += w * (max(dof, self.min_dof) if w > 0 else self.max_dof)
            elif name == "fulfillP" and w < 0:
                lb += w
            elif cost_terms()[name].non_negative and w > 0:  # contributes ≥ 0
                pass
            else:
                return -math.inf
        return lb

    def reach_bound(self, candidate: "Candidate") -> Tuple[np.ndarray, float]:
        """(o, R) exactly as the pipeline's ``reach`` stage computes them for ``candidate``: o is the world
        position of the first joint (it depends on the base pose and on the modules up to the first joint),
        R bounds the distance of every reachable TCP position from o. The reach stage fails iff some goal
        position is farther than R + (its position tolerance) from o. Costs one robot build (~ms)."""
        from robodesign.model.robot import Robot
        robot = Robot.from_order(self.module_set, tuple(candidate.order), base_pose=self.base_pose(candidate))
        o, R = robot.reach_bound()
        return np.asarray(o, dtype=float), float(R)

    # -- reach, torque and the base pose (geometry-informed search) --------------------------------------
    def max_reach(self) -> float:
        """An upper bound [m] of the distance from the base pose to the TCP of every valid order under the
        rules, at every joint position: the largest sum of :attr:`ModuleInfo.span` along a valid order
        (dynamic programming over the same states as :meth:`count_orders`). ``inf`` for prismatic joints
        without finite limits; 0 when the space has no valid order."""
        return self.longest_order()[0]

    def longest_order(self) -> Tuple[float, Tuple[str, ...]]:
        """(:meth:`max_reach`, an order whose spans sum to it: the longest arm; ``()`` without a valid order)."""
        memo = self._cache("_memo_longest")
        if "()" not in memo:
            best: Tuple[float, Tuple[str, ...]] = (-math.inf, ())
            for b in self.base_modules:
                state, _ = self._root(b)
                length, tail = self._longest(state)
                if self.module_info(b).span + length > best[0]:
                    best = (self.module_info(b).span + length, (b,) + tail)
            memo["()"] = (max(0.0, best[0]), best[1])
        return memo["()"]

    def _longest(self, state) -> Tuple[float, Tuple[str, ...]]:
        """The largest span sum of the modules that complete a partial order in ``state`` (-inf: none), and
        those modules."""
        memo = self._cache("_memo_longest")
        hit = memo.get(state)
        if hit is not None:
            return hit
        best: Tuple[float, Tuple[str, ...]] = (-math.inf, ())
        for nxt, st in self._step(state)[2]:
            span = self.module_info(nxt).span
            if st is None:
                cand = (span, (nxt,))
            else:
                length, tail = self._longest(st)
                cand = (span + length, (nxt,) + tail)
            if cand[0] > best[0]:
                best = cand
        memo[state] = best
        return best

    def _order_reach(self, order: Tuple[str, ...]) -> Tuple[np.ndarray, float]:
        """(first-joint position in the frame of the base parameters' origin, reach radius R) of ``order``:
        the reach stage's bound, from one robot build per order (memoized)."""
        return self._order_geometry(order)[:2]

    def _order_geometry(self, order: Tuple[str, ...]) -> Tuple[np.ndarray, float, int]:
        """:meth:`_order_reach` and the order's :meth:`~robodesign.model.robot.Robot.generic_rank` (computed
        only when the goals need it, :attr:`goal_rank`; else 6), from one robot build per order (memoized)."""
        cache = self._cache("_memo_reach")
        hit = cache.get(order)
        if hit is None:
            from robodesign.model.cell import kinematic_robot  # kept for the evaluation of the order to adopt
            pose0 = self.base_bounds.pose(tuple(0.0 for _ in self.base_bounds.free))
            robot = kinematic_robot(self.module_set, order, base_pose=pose0)
            o, R = robot.reach_bound()
            o_local = np.linalg.solve(pose0, np.append(np.asarray(o, dtype=float), 1.0))[:3]
            rank = robot.generic_rank() if self.goal_rank else 6
            if len(cache) >= _CACHE_LIMIT:
                cache.clear()
            hit = cache[order] = (o_local, float(R), int(rank))
        return hit

    def rank_deficit(self, order: Sequence[str]) -> int:
        """How many pose directions the goals fix that ``order``'s tool cannot move in (``goal_rank`` minus the
        order's generic Jacobian rank, at least 0): such a design fails the IK stage at once (design.solve)."""
        if not self.goal_rank:
            return 0
        return max(0, int(self.goal_rank) - self._order_geometry(tuple(str(m) for m in order))[2])

    def _goal_array(self) -> np.ndarray:
        """The goals as rows (x, y, z, slack), made once (read-only)."""
        memo = self._memo()
        G = memo.get("goal_array")
        if G is None:
            G = memo["goal_array"] = np.asarray(self.goals, dtype=float).reshape(-1, 4)
            G.flags.writeable = False
        return G

    def _shortfall(self, order: Tuple[str, ...], params: Sequence[float], pose: Optional[np.ndarray] = None) -> float:
        if not self.goals:
            return 0.0
        o_local, R = self._order_reach(order)
        T = self.base_bounds.pose(params) if pose is None else pose
        return beyond_reach(self._goal_rows(), R, T, np.append(o_local, 1.0))

    def _inverse_nominal(self) -> np.ndarray:
        """The inverse of the nominal base pose (made once)."""
        memo = self._memo()
        inv = memo.get("inverse_nominal")
        if inv is None:
            inv = memo["inverse_nominal"] = np.linalg.inv(self.base_bounds.nominal)
        return inv

    def _goal_rows(self) -> Tuple[Tuple[float, float, float, float], ...]:
        """:meth:`_goal_array`'s rows as Python floats (:func:`~robodesign.design.base_bounds.beyond_reach`'s)."""
        memo = self._memo()
        rows = memo.get("goal_rows")
        if rows is None:
            rows = memo["goal_rows"] = tuple(tuple(float(v) for v in r) for r in self._goal_array())
        return rows

    def reach_shortfall(self, candidate: "Candidate") -> float:
        """How many metres the farthest goal lies beyond ``candidate``'s reach bound (the reach stage's test:
        0 when the reach stage passes, > 0 by exactly the amount it fails by; 0 without goals)."""
        return self._shortfall(tuple(candidate.order), tuple(candidate.base))

    def torque_penalty(self, order: Sequence[str]) -> float:
        """How far ``order`` is from "strong joints near the base, light ones at the tip": the sum over pairs
        of joint modules (i before j) of max(0, torque_j − torque_i), in units of the set's largest joint
        torque limit (0 for a non-increasing torque profile)."""
        taus = [self.module_info(m).torque for m in order if self.module_info(m).kind == "joint"]
        top = max(taus, default=0.0)
        if top <= 0 or not math.isfinite(top):
            return 0.0
        return float(sum(max(0.0, b - a) for i, a in enumerate(taus) for b in taus[i + 1:]) / top)

    def _clear(self, params: Sequence[float], pose: Optional[np.ndarray] = None) -> bool:
        """Whether the base position of ``params`` (``pose``: made already) lies outside every primitive obstacle
        (meshes are left to the pipeline's collision checks)."""
        if not self.obstacles:
            return True
        p = (self.base_bounds.pose(params) if pose is None else pose)[:3, 3]
        x, y, z = float(p[0]), float(p[1]), float(p[2])
        for g, c, r2 in self._obstacle_spheres():
            if r2 is not None and (x - c[0]) ** 2 + (y - c[1]) ** 2 + (z - c[2]) ** 2 > r2:
                continue  # farther from its centre than any point of it: outside (no need to solve for its frame)
            if contains_point(g, p):
                return False
        return True

    def _obstacle_spheres(self) -> list:
        """:func:`~robodesign.design.base_bounds.clearance_spheres` of the obstacles (made once)."""
        memo = self._memo()
        out = memo.get("obstacle_spheres")
        if out is None:
            out = memo["obstacle_spheres"] = clearance_spheres(self.obstacles)
        return out

    def sample_base(self, rng, order: Sequence[str], tries: int = 64) -> Tuple[float, ...]:
        """Base parameters for ``order`` chosen from the goals' geometry: proposals put the first joint at a
        random point 20–75 % of the order's reach radius R away from a random goal (the yaw, and a fixed x/y/z,
        drawn in the bounds) or draw the parameters uniformly in the bounds; the first proposal that is valid, whose
        base position is clear of the obstacles and whose reach bound covers every goal is returned, else the
        valid proposal with the smallest :meth:`reach_shortfall`. Without free base parameters: ``()``;
        without goals: :meth:`BaseBounds.sample`."""
        bb = self.base_bounds
        free = bb.free
        if not free:
            return ()
        if not self.goals:
            return bb.sample(rng)
        order = tuple(str(m) for m in order)
        o_local, R = self._order_reach(order)
        rows = self._goal_rows()
        propose = BaseProposals(bb, rows, o_local, R, self._inverse_nominal())
        o_h = np.append(o_local, 1.0)
        best, best_s = None, math.inf
        for k in range(tries):
            params = propose.geometric(rng) if k % 2 == 0 else propose.uniform(rng)
            if not bb.within(params):
                continue
            T = bb.pose(params)   # (one pose for the shortfall, the tolerance and the clearance)
            s = beyond_reach(rows, R, T, o_h)
            if s != 0.0 and s >= best_s:
                continue   # neither returned nor the best so far (its tolerance and clearance do not matter)
            if bb.tolerance is not None and not bb.tolerance.valid(T) or not self._clear(params, T):
                continue
            if s == 0.0:
                return params
            best, best_s = params, s   # (s < best_s)
        return best if best is not None else bb.sample(rng)

    def informed_candidate(self, rng, orders: int = 8) -> "Candidate":
        """A candidate that knows reach, dexterity and torque: ``orders`` random valid orders, each with a base
        from :meth:`sample_base`; among those whose tool can move in every direction the goals fix (smallest
        :meth:`rank_deficit`), the one whose reach bound covers the goals (smallest :meth:`reach_shortfall`)
        and, among those, whose joints are strongest near the base (smallest :meth:`torque_penalty`) wins
        (ties: the first drawn). With ``orders=1`` the order is uniformly random."""
        best: Optional[Candidate] = None
        best_key = None
        for _ in range(max(1, int(orders))):
            order = self.random_order(rng)
            base = self.sample_base(rng, order)
            key = (self.rank_deficit(order), self._shortfall(order, base), self.torque_penalty(order))
            if best_key is None or key < best_key:
                best, best_key = Candidate(order, base), key
        assert best is not None  # at least one order was drawn
        return best

    def validate_order(self, order: Sequence[str]) -> Optional[str]:
        """None if ``order`` is a complete valid design under the rules, else the reason."""
        order = tuple(str(x) for x in order)
        cache = self._cache("_memo_valid")
        hit = cache.get(order, _MISS)
        if hit is not _MISS:
            return hit
        why = self._validate_order(order)
        if len(cache) >= _CACHE_LIMIT:
            cache.clear()
        cache[order] = why
        return why

    def _validate_order(self, order: Tuple[str, ...]) -> Optional[str]:
        if not order:
            return "empty order"
        failed, _, clash = self._walk(order)
        if failed is not None:
            mid = order[failed]
            if mid not in self.module_set:
                return f"module {mid!r} is not in the module set"
            return f"module {mid!r} may not follow {list(order[:failed])} under the rules"
        if not (len(order) > 1 and self.module_set[order[-1]].kind == "eef"):
            return "the order does not end with an end effector"
        return self._assembly_error(order) if clash else None

    def _walk(self, order: Tuple[str, ...]):
        """Check ``order[i] in successors(order[:i])`` for i = 0, 1, ... along the state machine of _next (each
        prefix checked so far is valid, so its state is the one _next gives). Returns (index of the first
        module that fails, else None; the state after ``order`` (None when it is complete); whether a module
        clashes with a connector an earlier module than its predecessor left free, see random_order)."""
        ms = self.module_set
        state = None  # state of order[:i] (None: complete, nothing may follow)
        clash = False
        blocked: FrozenSet[str] = frozenset()
        for i, mid in enumerate(order):
            if mid not in ms:
                return i, None, clash
            if i == 0:
                if mid not in self.base_modules:
                    return i, None, clash
                state, clash = self._root(mid)
            else:
                _, after, _, blocks = self._step(state) if state is not None else _DEAD_END
                if mid not in after:
                    return i, None, clash
                state = after[mid]
                hit, blocked = _block(blocked, blocks, mid)
                clash = clash or hit
        return None, state, clash

    def _assembly_error(self, order: Tuple[str, ...]) -> Optional[str]:
        """The message of the AssemblyError that ``Assembly.from_order`` raises for ``order`` (None if it
        assembles), memoized per order."""
        cache = self._cache("_memo_assembly")
        hit = cache.get(order, _MISS)
        if hit is not _MISS:
            return hit
        try:
            Assembly.from_order(self.module_set, order)
            why = None
        except AssemblyError as e:
            why = str(e)
        if len(cache) >= _CACHE_LIMIT:
            cache.clear()
        cache[order] = why
        return why

    def random_order(self, rng, max_tries: int = 200) -> Tuple[str, ...]:
        # Walks the state machine of _next: at each step the choices are exactly successors(order), in the
        # same order, and one rng.integers(len(choices)) is drawn, as in
        #     while succ := self.successors(order): order.append(succ[rng.integers(len(succ))])
        # followed by validate_order(order). For a walked order only the Assembly check of validate_order
        # can fail, and only there the whole order matters, so it is memoized per order. Assembly.from_order
        # accepts a walked order iff its first module has one base connector and no module mates with
        # a connector that a module before its predecessor left free (each step mates with its predecessor
        # by exactly one pair): `clash` tracks that along the walk, and the Assembly check runs only if
        # it finds a clash (it then gives the verdict), so the result is the one of validate_order.
        bases = self.base_modules
        step = self._step
        for _ in range(max_tries):
            if not bases:
                continue  # validate_order(()) fails: "empty order"
            mid = bases[int(rng.integers(len(bases)))]
            order = [mid]
            state, clash = self._root(mid)
            blocked: FrozenSet[str] = frozenset()  # modules that would mate with an earlier module than the last one
            while state is not None:
                names, after, _, blocks = step(state)
                if not names:
                    break
                mid = names[int(rng.integers(len(names)))]
                order.append(mid)
                hit, blocked = _block(blocked, blocks, mid)
                clash = clash or hit
                state = after[mid]
            if state is None and (not clash or self._assembly_error(tuple(order)) is None):
                return tuple(order)  # ended with an end effector and assembles
        raise InputError("the search space contains no valid module order under its rules")

    def _root(self, mid: str):
        """(state of the one-module order ``(mid,)``, whether Assembly.from_order may reject an order starting
        with it: its base connectors are not exactly one)."""
        return (mid, free_connectors(self.module_set, mid), 0, 0, 1), not self._one_base_connector(mid)

    def _one_base_connector(self, mid: str) -> bool:
        cache = self._cache("_memo_base")
        ok = cache.get(mid)
        if ok is None:
            ok = cache[mid] = sum(1 for c in self.module_set[mid].connectors if c.type == "base") == 1
        return ok

    def random_candidate(self, rng) -> Candidate:
        return Candidate(self.random_order(rng), self.base_bounds.sample(rng))

    def enumerate_orders(self, limit: Optional[int] = None) -> Iterator[Tuple[str, ...]]:
        """Every valid complete order (depth-first, deterministic order)."""
        count = 0
        stack: List[Tuple[str, ...]] = [(b,) for b in reversed(self.base_modules)]
        while stack:
            prefix = stack.pop()
            succ = self.successors(prefix)
            if not succ:
                if self._state(prefix)[2]:  # ends with an end effector; every step mated by construction
                    yield prefix
                    count += 1
                    if limit is not None and count >= limit:
                        return
                continue
            for s in reversed(succ):
                stack.append(prefix + (s,))

    def count_orders(self) -> int:
        """Number of valid orders (dynamic programming over (last module, free connectors, dof, links, length))."""
        return self.count_completions(())

    # -- candidates ----------------------------------------------------------------------------
    def validate(self, c: Candidate) -> Optional[str]:
        r = self.validate_order(c.order)
        if r:
            return r
        if not self.base_bounds.valid(c.base):
            return f"base parameters {list(c.base)} outside the base-placement bounds"
        return None

    def base_pose(self, c: Candidate) -> np.ndarray:
        return self.base_bounds.pose(c.base)

    @property
    def base_dims(self) -> int:
        return len(self.base_bounds.free)

    def nominal_candidate(self, order: Sequence[str]) -> Candidate:
        return Candidate(tuple(order), tuple(0.0 if self.base_bounds.lower[i] <= 0 <= self.base_bounds.upper[i]
                                             else 0.5 * (self.base_bounds.lower[i] + self.base_bounds.upper[i])
                                             for i in self.base_bounds.free))


def _block(blocked: frozenset, blocks: dict, mid: str):
    """One step of the clash tracking of :meth:`SearchSpace.random_order`: (``mid`` mates with a connector an
    earlier module than its predecessor left free, the modules blocked after it)."""
    b = blocks[mid]
    return mid in blocked, (blocked | b if b else blocked)


@lru_cache(maxsize=4096)
def _followers_cached(ms_id: int, mid: str, exclude, bases, eefs, ms_ref) -> Tuple[str, ...]:
    ms = ms_ref()
    return tuple(m for m in next_compatible(ms, mid) if m not in exclude
                 and not (ms[m].kind == "eef" and eefs is not None and m not in eefs))


def _followers(ms: ModuleSet, mid: str, exclude, bases, eefs) -> Tuple[str, ...]:
    return _followers_cached(id(ms), mid, tuple(exclude), bases, eefs, weakref.ref(ms))


@lru_cache(maxsize=65536)
def _mate_step_cached(ms_id: int, prev: str, free: Tuple[str, ...], mid: str, ms_ref) -> Optional[Tuple[str, ...]]:
    return chain_step(ms_ref(), prev, free, mid)


def _mate_step(ms: ModuleSet, prev: str, free: Tuple[str, ...], mid: str) -> Optional[Tuple[str, ...]]:
    """:func:`robodesign.formats.assembly.chain_step`, cached per module set."""
    return _mate_step_cached(id(ms), prev, tuple(free), mid, weakref.ref(ms))


@lru_cache(maxsize=256)
def _cost_terms(cost: str) -> Tuple[Tuple[str, float], ...]:
    from robodesign.formats.costs import parse_cost
    return tuple(parse_cost(cost).terms)
