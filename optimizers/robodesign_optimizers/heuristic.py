"""Heuristic tree search over partial assemblies: iterative-widening beam search.

States are prefixes (partial module orders, base first); a prefix is expanded with
``space.successors``. The search runs in *passes*: a pass starts at the root and goes level by level;
at every level the children of the current beam are ranked and the best ``beam_width`` are kept
(level-synchronous beam search). Complete orders that make it into a beam are asked. The next pass
starts again at the root with what the tells have taught; when a pass finds nothing new and its beam
cut something, the beam is widened (× ``widen``); when nothing was cut the tree is exhausted and
``ask`` returns None.

Ranking key of a prefix p (smaller first):

0. demoted(p): p has ``demote_after`` or more evaluated designs below it and none of them was feasible
   (learned from tells; a demoted prefix only competes with other demoted prefixes, so each subtree
   gets a few tries before the beam moves on to its siblings; ``demote_after=0`` disables it).
1. f(p) = g(p) + h(p): :meth:`SearchSpace.cost_lower_bound` of p for the study's cost (``self.cost``)
   — g is the cost of the modules so far (e.g. mass so far), h the cheapest completion (e.g. the
   lightest completion; ``numJ`` at least ``min_dof``); admissible: it never exceeds the cost of any
   feasible design below p. For costs without order-determined terms (``cyc``, ``mechEnergy``, …) and
   with ``cost_bound=false`` it is 0 for every prefix: the lower bound of a cycle time is 0.
2. est(p): the best score told so far among the evaluated designs below p (or below its deepest
   ancestor that has any), i.e. what this subtree is known to achieve; infeasible designs score by the
   stage they reached, so subtrees whose designs fail early sink.
3. a random rank (from ``self.rng``, redrawn each pass) for diversity among ties.

Tells prune: (1) **bound pruning** (sound): a prefix with f(p) ≥ the best feasible score is never
expanded again (the bound is of the study's cost, so nothing below it can be better); (2) **learned
ranking** (heuristic, not sound): subtrees whose designs failed early rank low (est) and a narrow beam
drops them; demoted prefixes (rule 0) make room for untried siblings; widening brings everything back,
so the search is complete. Fully explored subtrees are closed
and no longer take beam slots.

Base poses: each complete order is first asked at its nominal base pose. With free base dims a
promising order (one that stays in the beam) is asked again in later passes with another base pose —
a Gaussian step (σ = ``base_sigma`` · range) from the order's best base pose so far — up to
``base_samples`` poses per order.

Options (``--opt key=value``; ``robodesign optimizers --verbose`` lists them): ``beam_width``, ``widen``,
``base_samples``, ``base_sigma``, ``demote_after`` and ``cost_bound`` (f and bound pruning; on by default,
with the study's cost from the problem).

Deterministic for a seed; never asks a candidate twice.
"""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Deque, Dict, List, Optional, Set, Tuple

import numpy as np

from robodesign.plugin import Candidate, Optimizer, option

Prefix = Tuple[str, ...]


class HeuristicSearch(Optimizer):
    name = "heuristic"
    description = "beam search over partial assemblies with an admissible cost bound and learned ranking"

    @dataclass(frozen=True)
    class Options:
        beam_width: int = option(16, low=1, help="prefixes kept per level in the first pass")
        widen: float = option(2.0, low=1.01, help="beam growth factor when a pass finds nothing new")
        base_samples: int = option(3, low=1, help="base poses tried per order (free base dims only)")
        base_sigma: float = option(0.15, low=0.0, help="sigma of the base-pose steps, as a fraction of each range")
        demote_after: int = option(3, low=0, help="infeasible designs below a prefix (none feasible) that demote it; "
                                                  "0: never")
        cost_bound: bool = option(True, help="rank by and prune with the lower bound of the study's cost")

    def __init__(self, problem, seed: int = 0, **options):
        super().__init__(problem, seed, **options)
        o = self.options
        self._free = tuple(self.space.base_bounds.free)
        self.base_samples = o.base_samples if self._free else 1
        self.use_bound = (o.cost_bound and self.cost is not None
                          and math.isfinite(self.space.cost_lower_bound((), self.cost)))
        self.width = o.beam_width
        self.best_score = math.inf
        self.passes = 0
        self._lb: Dict[Prefix, float] = {}
        self._count: Dict[Prefix, int] = {}
        self._est: Dict[Prefix, float] = {}            # best score below a prefix (incl. complete orders)
        self._tried: Dict[Prefix, List[int]] = {}      # prefix → [evaluated designs below, feasible ones]
        self._progress: Dict[Prefix, int] = {}         # prefix → furthest stage index reached below it
        self._bases: Dict[Prefix, List[Tuple[float, ...]]] = {}  # order → base params asked
        self._best_base: Dict[Prefix, Tuple[float, Tuple[float, ...]]] = {}
        self._closed: Dict[Prefix, int] = {}           # prefix → closed orders below it
        self._asked: Set[str] = set()  # keys of the candidates asked
        self._queue: Deque[Candidate] = deque()
        self._exhausted = False

    # -- cached static quantities ------------------------------------------------------------------------
    def _f(self, p: Prefix) -> float:
        v = self._lb.get(p)
        if v is None:
            if self.use_bound:
                v = self.space.cost_lower_bound(p, self.cost)
            else:
                v = 0.0 if self.space.count_completions(p) > 0 else math.inf
            self._lb[p] = v
        return v

    def _n(self, p: Prefix) -> int:
        v = self._count.get(p)
        if v is None:
            v = self._count[p] = self.space.count_completions(p)
        return v

    def _bound_pruned(self, f: float) -> bool:
        """Sound bound pruning: nothing below a prefix with f ≥ the best feasible score can be better."""
        return self.use_bound and f >= self.best_score

    def _complete(self, p: Prefix) -> bool:
        return self.space.module_info(p[-1]).kind == "eef"

    def _is_closed(self, p: Prefix) -> bool:
        return self._closed.get(p, 0) >= self._n(p)

    def _close(self, order: Prefix) -> None:
        for k in range(1, len(order) + 1):
            self._closed[order[:k]] = self._closed.get(order[:k], 0) + 1

    def _demoted(self, p: Prefix) -> bool:
        n, feasible = self._tried.get(p, (0, 0))
        return self.options.demote_after > 0 and n >= self.options.demote_after and feasible == 0

    def _progress_of(self, p: Prefix) -> int:
        for k in range(len(p), -1, -1):
            v = self._progress.get(p[:k])
            if v is not None:
                return v
        return 0

    def _estimate(self, p: Prefix) -> float:
        for k in range(len(p), -1, -1):
            v = self._est.get(p[:k])
            if v is not None:
                return v
        return 0.0

    # -- passes -------------------------------------------------------------------------------------------
    def _pass(self) -> Tuple[List[Candidate], bool]:
        """One beam sweep from the root: (new candidates, whether the beam cut any open prefix)."""
        self.passes += 1
        out: List[Candidate] = []
        cut = False
        level: List[Prefix] = [()]
        while level:
            children = []
            for p in level:
                for m in self.space.successors(p):
                    c = p + (m,)
                    f = self._f(c)
                    if f == math.inf or self._bound_pruned(f) or self._is_closed(c):
                        continue
                    children.append(c)
            if not children:
                break
            rnd = self.rng.random(len(children))
            keys = [(-self._progress_of(c), self._demoted(c), self._f(c), self._estimate(c), float(r))
                    for c, r in zip(children, rnd)]
            ranked = [c for _, c in sorted(zip(keys, children), key=lambda t: t[0])]
            if len(ranked) > self.width:
                cut = True
                ranked = ranked[:self.width]
            level = []
            for c in ranked:
                if self._complete(c):
                    cand = self._next_candidate(c)
                    if cand is not None:
                        out.append(cand)
                else:
                    level.append(c)
        return out, cut

    def _next_candidate(self, order: Prefix) -> Optional[Candidate]:
        asked = self._bases.setdefault(order, [])
        cand = None
        if not asked:
            cand = self.space.nominal_candidate(order)
        else:
            bb = self.space.base_bounds
            center = self._best_base.get(order, (None, asked[0]))[1]
            for _ in range(30):
                p = [float(np.clip(v + self.rng.normal(0.0, self.options.base_sigma * (bb.upper[i] - bb.lower[i])),
                                   bb.lower[i], bb.upper[i])) for i, v in zip(self._free, center)]
                c = Candidate(order, tuple(p))
                if bb.valid(p) and c.key() not in self._asked:
                    cand = c
                    break
        if cand is None or cand.key() in self._asked:
            self._close(order)  # no new base pose found: give up on this order
            return None
        asked.append(cand.base)
        self._asked.add(cand.key())
        if len(asked) >= self.base_samples:
            self._close(order)
        return cand

    # -- ask / tell ---------------------------------------------------------------------------------------
    def ask(self) -> Optional[Candidate]:
        if self._exhausted:
            return None
        while True:
            while self._queue:
                c = self._queue.popleft()
                if self._bound_pruned(self._f(c.order)):  # the incumbent improved since the pass
                    continue
                return c
            new, cut = self._pass()
            if new:
                self._queue.extend(new)
                continue
            if cut:
                self.width = int(math.ceil(self.width * self.options.widen))
                continue
            self._exhausted = True
            return None

    def tell(self, evaluation) -> None:
        c = evaluation.candidate
        order = tuple(c.order)
        s = float(evaluation.score)
        if evaluation.feasible:
            self.best_score = min(self.best_score, s)
        for k in range(0, len(order) + 1):
            p = order[:k]
            if s < self._est.get(p, math.inf):
                self._est[p] = s
            self._progress[p] = max(self._progress.get(p, 0), int(evaluation.stage_index))
            t = self._tried.setdefault(p, [0, 0])
            t[0] += 1
            t[1] += bool(evaluation.feasible)
        if s < self._best_base.get(order, (math.inf, None))[0]:
            self._best_base[order] = (s, tuple(c.base))
        if evaluation.stage == "assembly" and not self._is_closed(order):
            self._close(order)  # the order itself is broken: no other base pose can help
