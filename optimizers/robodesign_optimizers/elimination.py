"""Hierarchical elimination (Althoff et al. 2019; Liu & Althoff 2020): exhaustive enumeration of every
valid module order under the search-space rules, evaluated from the cheapest bound up, with candidates
eliminated stage by stage as soon as a cheap test proves that they cannot be better.

Enumeration order:

* with ``cost_bound`` (default) and ``order_by="bound"`` (default): complete orders in non-decreasing
  :meth:`SearchSpace.cost_lower_bound` of the study's cost (``self.cost``, from the problem), a
  best-first traversal of the tree of partial orders: the bound of a prefix is the mass so far plus the
  lightest completion, plus the DoF term; it never decreases along a branch, so orders come out sorted
  without materialising the whole list. For ``mass``, ``numJ`` and ``Whit2`` the bound *is* the cost of
  a feasible order, so the first feasible order found is optimal. Ties: deeper prefix first, then
  enumeration order.
* otherwise (``cost_bound=false``, a cost whose bound is ``-inf`` because of a reward term with a
  negative weight, ``order_by="enumeration"``): the space's deterministic depth-first ``enumerate_orders``.

Each order is evaluated at the nominal base pose, or (``base_grid`` = k ≥ 2) at the nominal pose and then
at every point of a k^d grid over the d free base dims (``linspace(lower, upper, k)`` per dim; points
outside ``base_bounds.valid`` are skipped since they fail the ``base`` stage).

Pruning rules (a candidate is skipped without being asked). All of them are *sound*: a skipped
candidate provably fails, or provably cannot score strictly better than the best feasible one found.

1. **bound**: ``cost_lower_bound(order) ≥ best feasible score`` (with ``cost_bound``; sound because the
   bound is of the cost the study evaluates). In bound order every later order is pruned too, so the
   enumeration ends (None).
2. **base**: a candidate whose evaluation failed at stage ``base`` had base parameters outside the task's
   base-placement tolerance; that stage depends only on the base pose, so every untried candidate with
   the same base parameters is skipped.
3. **assembly**: the ``assembly`` stage depends only on the module order: an order that failed there is
   not tried with other base poses.
4. **reach** (``reach_pruning``): the reach stage fails iff some goal lies farther than R + slack from o,
   where (o, R) = :meth:`SearchSpace.reach_bound` (first-joint position in the world and a reach radius;
   deterministic, no randomness). If candidate A failed there, a goal g has |p_g − o_A| > R_A + s_g.
   A candidate B with R_B + |o_B − o_A| ≤ R_A then has |p_g − o_B| ≥ |p_g − o_A| − |o_B − o_A| >
   R_A − |o_B − o_A| + s_g ≥ R_B + s_g, so B fails reach as well. (E.g. the same base, base pose and
   modules up to the first joint — hence the same o — with shorter links or a shorter wrist.)

No rule is applied to the ``ik``, ``static_torque``, ``plan``, ``timing`` or ``check`` stages: those
stages are randomised (IK restarts, sampling planners) and depend on the whole design, so a failure
does not prove anything about another candidate. Pruned candidates are counted per rule in
``self.pruned`` (``keep_pruned=True`` also keeps their keys in ``self.pruned_candidates``).

Options (``--opt key=value``; ``robodesign optimizers --verbose`` lists them): ``base_grid`` (1: nominal
base only), ``order_by`` (``bound`` or ``enumeration``), ``cost_bound`` (rule 1 and bound order),
``reach_pruning`` (rule 4), ``keep_pruned`` (keep (key, rule) of every pruned candidate in
``self.pruned_candidates``).

``ask`` returns None when the enumeration is exhausted (and from then on).
"""
from __future__ import annotations

import heapq
import itertools
import math
from collections import Counter, deque
from dataclasses import dataclass
from typing import Deque, Dict, Iterator, List, Optional, Set, Tuple

import numpy as np

from robodesign.plugin import AssemblyError, Candidate, Optimizer, option

#: (o, R) of the reach bound of a candidate, or (None, None) when its order does not assemble
_Reach = Tuple[Optional[np.ndarray], Optional[float]]


class HierarchicalElimination(Optimizer):
    name = "elimination"
    description = "exhaustive enumeration in cost-bound order with sound stage-by-stage pruning"

    @dataclass(frozen=True)
    class Options:
        base_grid: int = option(1, low=1, help="grid points per free base dim (1: the nominal base only)")
        order_by: str = option("bound", choices=("bound", "enumeration"),
                               help="complete orders by non-decreasing cost bound, or depth-first")
        cost_bound: bool = option(True, help="order and prune by the lower bound of the study's cost (rule 1)")
        reach_pruning: bool = option(True, help="skip designs that provably fail the reach stage (rule 4)")
        keep_pruned: bool = option(False, help="keep (key, rule) of every pruned candidate in pruned_candidates")

    def __init__(self, problem, seed: int = 0, **options):
        super().__init__(problem, seed, **options)
        o = self.options
        # the bound is usable unless a negative weight makes it -inf
        self.use_bound = (o.cost_bound and self.cost is not None
                          and math.isfinite(self.space.cost_lower_bound((), self.cost)))
        self.order_by = o.order_by if self.use_bound else "enumeration"
        self.invalid_base_points = 0
        self._orders = self._bound_order() if self.order_by == "bound" else self._enumeration_order()
        self._bases = self._base_points()
        self._queue: Deque[Candidate] = deque()
        self._queue_lb = -math.inf
        self.best_score = math.inf                      # best feasible score told so far
        self._bad_bases: Set[Tuple[float, ...]] = set()
        self._bad_orders: Set[Tuple[str, ...]] = set()
        self._reach_o: List[np.ndarray] = []            # (o, R) of candidates that failed at reach
        self._reach_R: List[float] = []
        self._reach_cache: Dict[str, _Reach] = {}      # key → (o, R) computed at ask time
        self.pruned: Counter = Counter()
        self.pruned_candidates: List[Tuple[str, str]] = []
        self.orders_enumerated = 0
        self._exhausted = False

    # -- enumeration --------------------------------------------------------------------------------
    def _enumeration_order(self) -> Iterator[Tuple[float, Tuple[str, ...]]]:
        for order in self.space.enumerate_orders():
            lb = self.space.cost_lower_bound(order, self.cost) if self.use_bound else -math.inf
            yield lb, order

    def _bound_order(self) -> Iterator[Tuple[float, Tuple[str, ...]]]:
        """Complete orders in non-decreasing cost lower bound (best-first over prefixes; the bound is
        monotone along a branch, so a complete order popped from the heap is never beaten by a later one)."""
        sp, cost = self.space, self.cost
        seq = itertools.count()
        heap: List[Tuple[float, int, int, Tuple[str, ...]]] = []   # (bound, -length, tie-break, prefix)
        for b in sp.successors(()):
            lb = sp.cost_lower_bound((b,), cost)
            if lb < math.inf:
                heapq.heappush(heap, (lb, -1, next(seq), (b,)))
        while heap:
            lb, _, _, prefix = heapq.heappop(heap)
            if sp.module_info(prefix[-1]).kind == "eef":
                yield lb, prefix
                continue
            for m in sp.successors(prefix):
                child = prefix + (m,)
                clb = sp.cost_lower_bound(child, cost)
                if clb < math.inf:  # inf: a dead end (no valid completion)
                    heapq.heappush(heap, (clb, -len(child), next(seq), child))

    def _base_points(self) -> List[Tuple[float, ...]]:
        """Base parameter tuples tried for every order: nominal first, then the grid (valid points only)."""
        sp = self.space
        bb = sp.base_bounds
        free = bb.free
        nominal = sp.nominal_candidate(()).base if free else ()
        points = [nominal]
        if free and self.options.base_grid >= 2:
            axes = [np.linspace(bb.lower[i], bb.upper[i], self.options.base_grid) for i in free]
            seen = {Candidate((), nominal).key()}
            for p in itertools.product(*axes):
                p = tuple(float(v) for v in p)
                k = Candidate((), p).key()
                if k in seen:
                    continue
                seen.add(k)
                if bb.valid(p):
                    points.append(p)
                else:  # would fail the base stage: never generated
                    self.invalid_base_points += 1
        return points

    # -- ask / tell -----------------------------------------------------------------------------------
    def _prune(self, c: Candidate, rule: str) -> None:
        self.pruned[rule] += 1
        if self.options.keep_pruned:
            self.pruned_candidates.append((c.key(), rule))

    def ask(self) -> Optional[Candidate]:
        if self._exhausted:
            return None
        while True:
            if not self._queue:
                nxt = next(self._orders, None)
                if nxt is None:
                    self._exhausted = True
                    return None
                lb, order = nxt
                self.orders_enumerated += 1
                self._queue_lb = lb
                self._queue = deque(Candidate(order, b) for b in self._bases)
            c = self._queue.popleft()
            if self._queue_lb >= self.best_score:                       # rule 1
                self._prune(c, "bound")
                if self.order_by == "bound":
                    # every later order has a bound ≥ this one: nothing left can be better
                    for rest in self._queue:
                        self._prune(rest, "bound")
                    self._queue.clear()
                    self._exhausted = True
                    return None
                continue
            if c.base in self._bad_bases:                                # rule 2
                self._prune(c, "base")
                continue
            if c.order in self._bad_orders:                              # rule 3
                self._prune(c, "assembly")
                continue
            if self.options.reach_pruning and self._reach_R and self._reach_dominated(c):  # rule 4
                self._reach_cache.pop(c.key(), None)
                self._prune(c, "reach")
                continue
            return c

    def _reach(self, c: Candidate) -> _Reach:
        k = c.key()
        hit = self._reach_cache.get(k)
        if hit is None:
            try:
                hit = self.space.reach_bound(c)
            except AssemblyError:  # the order does not assemble: the evaluation will say so
                hit = (None, None)
            self._reach_cache[k] = hit
        return hit

    def _reach_dominated(self, c: Candidate) -> bool:
        o, R = self._reach(c)
        if o is None or R is None:
            return False
        O = np.asarray(self._reach_o)
        RA = np.asarray(self._reach_R)
        d = np.linalg.norm(O - o, axis=1)
        return bool(np.any(R + d <= RA - 1e-9))

    def tell(self, evaluation) -> None:
        c = evaluation.candidate
        if evaluation.feasible:
            self.best_score = min(self.best_score, float(evaluation.score))
        elif evaluation.stage == "base":
            self._bad_bases.add(tuple(c.base))
        elif evaluation.stage == "assembly":
            self._bad_orders.add(tuple(c.order))
        elif evaluation.stage == "reach" and self.options.reach_pruning:
            o, R = self._reach(c)
            if o is not None and R is not None:
                self._reach_o.append(o)
                self._reach_R.append(R)
        self._reach_cache.pop(c.key(), None)
