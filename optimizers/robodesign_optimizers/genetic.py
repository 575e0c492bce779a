"""Genetic algorithm (DEAP) over variable-length module orders and base parameters.

Genome: the module order (a list of module IDs, base first, end effector last) plus the free base
parameters (``space.base_bounds.free``: x, y, z [m], yaw [rad] offsets from the nominal base pose).

Operators (all keep the genome a valid design under the search-space rules; an offspring that
cannot be made valid is rejected and the parent kept):

* **connector-aware replacement**: module i is replaced by another module from
  ``space.successors(order[:i])`` such that the rest of the chain stays valid;
* **insertion / deletion of a link module** (respecting ``max_links_between``);
* **insertion / deletion of a joint module** when the DoF range allows it, and a **joint move**
  (delete a joint here, insert one there) that keeps the DoF when ``min_dof == max_dof``;
* **one-point crossover at compatible junctions**: cut after module i of A and j of B, children
  ``A[:i+1] + B[j+1:]`` and ``B[:j+1] + A[i+1:]``; a cut is used only if ``B[j+1]`` is in
  ``successors(A[:i+1])`` (and vice versa) and both children pass ``space.validate_order``
  (otherwise the cut is rejected; no repair);
* **Gaussian mutation of the base parameters** (σ = ``base_sigma`` · range, clipped to the bounds,
  resampled until ``base_bounds.valid``), uniform crossover of the base parameters.

Selection: tournament (``tournament_size``) with elitism (the ``elite`` best survive unchanged).

Generation-synchronous ask/tell: ``ask`` returns the current generation's unevaluated individuals
one by one; when every one of them has been told, the next generation is bred. A candidate whose key
was evaluated before (cache key → score) is never asked again: it gets its cached score and counts as
evaluated. Offspring that duplicate an evaluated candidate are mutated again (a few times) and
otherwise replaced by a random immigrant. If the study asks more candidates than the generation has
left before telling (``batch_size`` > remaining), the extra candidates are random immigrants that
join the current generation (so every evaluation is used for selection).

Options (``--opt key=value``; ``robodesign optimizers --verbose`` lists them with their defaults and
ranges): ``population_size``, ``generations``, ``tournament_size``, ``elite``, ``crossover_prob``,
``mutation_prob``, ``base_mutation_prob``, ``base_sigma``, ``max_idle_generations``, ``informed``,
``informed_share``.

Seeding: a share (``informed_share``, default 0.5) of the initial population and of the immigrants are
``space.informed_candidate`` designs (option ``informed``, default 2: the best of 2 random orders, each
with a base placed from the goals' geometry, ranked by reach shortfall, then by torque profile — strong
joints near the base); the others have a uniformly random order, with a free base placed from the goals'
geometry (``space.sample_base``); with ``informed=0`` all are uniform (``space.random_candidate``).

Deterministic for a seed: every random choice comes from ``self.rng``; DEAP's selection operators,
which draw from Python's ``random`` module, run with a private ``random`` state seeded from the
optimizer's seed (the global state is saved and restored around each call).
"""
from __future__ import annotations

import contextlib
import random
from collections import deque
from dataclasses import dataclass
from typing import Deque, Dict, List, Optional, Sequence, Tuple

import numpy as np
from deap import base as deap_base
from deap import tools

from robodesign.plugin import Candidate, Optimizer, option


class _Fitness(deap_base.Fitness):
    weights = (-1.0,)  # minimise the score


class Individual(list):
    """A genome: the module order (list of IDs) with its ``base`` parameters and a DEAP fitness."""

    def __init__(self, order: Sequence[str] = (), base: Sequence[float] = ()):
        super().__init__(order)
        self.base: Tuple[float, ...] = tuple(float(v) for v in base)
        self.fitness = _Fitness()

    def candidate(self) -> Candidate:
        return Candidate(tuple(self), self.base)

    def key(self) -> str:
        return self.candidate().key()

    def copy(self) -> "Individual":
        ind = Individual(self, self.base)
        if self.fitness.valid:
            ind.fitness.values = self.fitness.values
        return ind


class GeneticOptimizer(Optimizer):
    name = "genetic"
    description = "genetic algorithm (DEAP): connector-aware mutation/crossover of module orders + base pose"

    @dataclass(frozen=True)
    class Options:
        population_size: int = option(20, low=2, help="individuals per generation")
        generations: Optional[int] = option(None, low=1, help="stop after this many generations (none: never)")
        tournament_size: int = option(3, low=1, help="tournament size of the selection")
        elite: int = option(2, low=0, help="best individuals copied unchanged into the next generation "
                                           "(at most population_size - 1)")
        crossover_prob: float = option(0.7, low=0.0, high=1.0, help="probability that a pair of parents is crossed")
        mutation_prob: float = option(0.5, low=0.0, high=1.0, help="probability that an offspring's order mutates")
        base_mutation_prob: float = option(0.5, low=0.0, high=1.0,
                                           help="probability that an offspring's base parameters mutate")
        base_sigma: float = option(0.1, low=0.0,
                                   help="sigma of the Gaussian base mutation, as a fraction of each range")
        max_idle_generations: int = option(25, low=1, help="stop after this many generations without a new candidate")
        informed: int = option(2, low=0, help="the initial population and immigrants: the best of this many "
                                              "random orders by reach (a base from the goals' geometry whose "
                                              "reach bound covers them) and torque profile "
                                              "(space.informed_candidate); 0: uniformly random designs")
        informed_share: float = option(0.5, low=0.0, high=1.0,
                                       help="share of the new designs (initial population, immigrants) that are "
                                            "informed; the others have a uniformly random order (diversity)")

    def __init__(self, problem, seed: int = 0, **options):
        super().__init__(problem, seed, **options)
        self.elite = min(self.options.elite, self.options.population_size - 1)
        self._free = tuple(self.space.base_bounds.free)
        self._dofs: Dict[str, int] = {}
        self._py_random_state = random.Random(self.seed).getstate()
        self.toolbox = deap_base.Toolbox()
        self.toolbox.register("select", tools.selTournament, tournsize=self.options.tournament_size)
        self.toolbox.register("elite", tools.selBest)
        self.toolbox.register("mate", self._crossover)
        self.toolbox.register("mutate", self._mutate)
        self.cache: Dict[str, float] = {}          # key → score of every evaluated candidate
        self.generation = 0                         # index of the current generation
        self.population: List[Individual] = []
        self._to_ask: Deque[Individual] = deque()
        self._waiting: Dict[str, List[Individual]] = {}  # asked, not yet told
        self._idle = 0
        self._done = False

    # -- ask / tell ---------------------------------------------------------------------------------
    def ask(self) -> Optional[Candidate]:
        if self._done:
            return None
        if not self.population:
            self.population = self._initial_population()
            self._to_ask = deque(self.population)
        while True:
            while self._to_ask:
                ind = self._to_ask.popleft()
                k = ind.key()
                if k in self.cache:  # evaluated before: counts as evaluated without asking
                    ind.fitness.values = (self.cache[k],)
                    continue
                if k in self._waiting:  # the same candidate is already being evaluated
                    self._waiting[k].append(ind)
                    continue
                self._waiting[k] = [ind]
                return ind.candidate()
            if self._waiting:
                # asked ahead of the tells (batch): a random immigrant joins the current generation
                imm = self._immigrant(set(self._waiting))
                if imm is None:
                    self._done = True
                    return None
                self.population.append(imm)
                self._waiting[imm.key()] = [imm]
                return imm.candidate()
            # the generation is complete: breed the next one
            if self.options.generations is not None and self.generation + 1 >= self.options.generations:
                self._done = True
                return None
            fresh = self._breed()
            self._idle = 0 if fresh else self._idle + 1
            if self._idle >= self.options.max_idle_generations:
                self._done = True
                return None

    def tell(self, evaluation) -> None:
        k = evaluation.candidate.key()
        self.cache[k] = float(evaluation.score)
        for ind in self._waiting.pop(k, []):
            ind.fitness.values = (float(evaluation.score),)

    # -- generations ----------------------------------------------------------------------------------
    def _initial_population(self) -> List[Individual]:
        pop: List[Individual] = []
        seen = set()
        for _ in range(20 * self.options.population_size):
            if len(pop) >= self.options.population_size:
                break
            c = self._random_candidate()
            if c.key() in seen:
                continue
            seen.add(c.key())
            pop.append(Individual(c.order, c.base))
        return pop

    def _breed(self) -> int:
        """Replace the population by the next generation; returns how many offspring are new candidates."""
        pop = [ind for ind in self.population if ind.fitness.valid]
        if not pop:
            return 0
        elites = [ind.copy() for ind in self.toolbox.elite(pop, self.elite)]
        n = self.options.population_size - len(elites)
        with self._deap_random():
            parents = self.toolbox.select(pop, n)
        offspring = [p.copy() for p in parents]
        for a, b in zip(offspring[::2], offspring[1::2]):
            if self.rng.random() < self.options.crossover_prob:
                self.toolbox.mate(a, b)
        for ind in offspring:
            self.toolbox.mutate(ind, p_order=self.options.mutation_prob, p_base=self.options.base_mutation_prob)
        # duplicates of evaluated candidates (or of each other) are mutated again, then replaced by immigrants
        taken = {e.key() for e in elites}
        fresh = 0
        for i, ind in enumerate(offspring):
            for _ in range(5):
                if ind.key() not in self.cache and ind.key() not in taken:
                    break
                self.toolbox.mutate(ind)
            if ind.key() in self.cache or ind.key() in taken:
                imm = self._immigrant(taken)
                if imm is not None:
                    ind = offspring[i] = imm
            taken.add(ind.key())
            if ind.key() not in self.cache:
                fresh += 1
            else:
                ind.fitness.values = (self.cache[ind.key()],)
        self.population = elites + offspring
        self._to_ask = deque(offspring)
        self.generation += 1
        return fresh

    def _immigrant(self, taken, tries: int = 200) -> Optional[Individual]:
        for _ in range(tries):
            c = self._random_candidate()
            k = c.key()
            if k not in self.cache and k not in taken:
                return Individual(c.order, c.base)
        return None

    def _random_candidate(self) -> Candidate:
        """A new design: informed by reach and torque (option ``informed``), else uniformly random."""
        if self.options.informed and self.rng.random() < self.options.informed_share:
            return self.space.informed_candidate(self.rng, orders=self.options.informed)
        if self.options.informed and self.space.base_dims:  # a uniform order, its base from the goals' geometry
            order = self.space.random_order(self.rng)
            return Candidate(order, self.space.sample_base(self.rng, order))
        return self.space.random_candidate(self.rng)

    @contextlib.contextmanager
    def _deap_random(self):
        """Run DEAP operators (which use the ``random`` module) on this optimizer's own random state."""
        saved = random.getstate()
        random.setstate(self._py_random_state)
        try:
            yield
        finally:
            self._py_random_state = random.getstate()
            random.setstate(saved)

    # -- variation operators ---------------------------------------------------------------------------
    def _valid(self, order: Sequence[str]) -> bool:
        return self.space.validate_order(order) is None

    def _kind(self, mid: str) -> str:
        return self.space.module_info(mid).kind

    def _dof(self, order: Sequence[str]) -> int:
        dofs, total = self._dofs, 0   # module ID → its DoF (space.module_info), asked once per module
        for m in order:
            d = dofs.get(m)
            if d is None:
                d = dofs[m] = self.space.module_info(m).dof
            total += d
        return total

    def _dof_prefixes(self, order: Sequence[str]) -> List[int]:
        """[DoF of order[:k] for k = 0 … len(order)]."""
        out = [0]
        for m in order:
            out.append(out[-1] + self._dof((m,)))
        return out

    def _shuffled(self, items: list) -> list:
        return [items[i] for i in self.rng.permutation(len(items))] if items else []

    def _first_valid(self, variants, limit: int = 30) -> Optional[List[str]]:
        for v in self._shuffled(variants)[:limit]:
            if self._valid(v):
                return v
        return None

    def _replace_variants(self, order: List[str]) -> list:
        out = []
        for i in range(len(order)):
            for m in self.space.successors(order[:i]):
                if m == order[i]:
                    continue
                new = order[:i] + [m] + order[i + 1:]
                if i + 1 < len(order) and new[i + 1] not in self.space.successors(new[:i + 1]):
                    continue
                out.append(new)
        return out

    def _insert_variants(self, order: List[str], kind: str) -> list:
        out = []
        for i in range(1, len(order)):
            for m in self.space.successors(order[:i]):
                if self._kind(m) == kind:
                    out.append(order[:i] + [m] + order[i:])
        return out

    def _delete_variants(self, order: List[str], kind: str) -> list:
        return [order[:i] + order[i + 1:] for i in range(1, len(order) - 1) if self._kind(order[i]) == kind]

    def _move_joint_variants(self, order: List[str], limit: int = 6) -> list:
        out = []
        dels = self._shuffled(self._delete_variants(order, "joint"))[:limit]
        for d in dels:
            out += [v for v in self._insert_variants(d, "joint") if v != order]
        return out

    def _mutate_order(self, ind: Individual) -> bool:
        order = list(ind)
        sp = self.space
        dof = self._dof(order)
        ops = ["replace", "insert_link", "delete_link", "move_joint"]
        if dof < sp.max_dof:
            ops.append("insert_joint")
        if dof > sp.min_dof:
            ops.append("delete_joint")
        for op in self._shuffled(ops):
            if op == "replace":
                variants = self._replace_variants(order)
            elif op == "insert_link":
                variants = self._insert_variants(order, "link")
            elif op == "delete_link":
                variants = self._delete_variants(order, "link")
            elif op == "insert_joint":
                variants = self._insert_variants(order, "joint")
            elif op == "delete_joint":
                variants = self._delete_variants(order, "joint")
            else:
                variants = self._move_joint_variants(order)
            new = self._first_valid(variants)
            if new is not None:
                ind[:] = new
                return True
        return False

    def _mutate_base(self, ind: Individual) -> bool:
        bb = self.space.base_bounds
        if not self._free:
            return False
        for _ in range(10):
            new = []
            for i, v in zip(self._free, ind.base):
                lo, hi = bb.lower[i], bb.upper[i]
                new.append(float(np.clip(v + self.rng.normal(0.0, self.options.base_sigma * (hi - lo)), lo, hi)))
            if bb.valid(new):
                ind.base = tuple(new)
                return True
        return False

    def _mutate(self, ind: Individual, p_order: float = 1.0, p_base: float = 1.0) -> Individual:
        """Mutate, in place, the order (one connector-aware operator, with probability ``p_order``) and the
        base parameters (Gaussian, with probability ``p_base``, when the space has free base dims)."""
        changed = False
        if self.rng.random() < p_order:
            changed = self._mutate_order(ind)
        if self._free and self.rng.random() < p_base:
            changed = self._mutate_base(ind) or changed
        if changed:
            del ind.fitness.values
        return ind

    def _crossover(self, a: Individual, b: Individual) -> Tuple[Individual, Individual]:
        """One-point crossover at compatible junctions (orders) + uniform crossover (base), in place."""
        A, B = list(a), list(b)
        sp = self.space
        lo, hi = sp.min_dof, sp.max_dof
        cuts = []
        pa, pb = self._dof_prefixes(A), self._dof_prefixes(B)   # pa[k]: the DoF of A[:k]
        succ_b: Dict[int, set] = {}   # j → the modules that may follow B[:j + 1]
        for i in range(len(A) - 1):
            succ_a = set(sp.successors(A[:i + 1]))
            for j in range(len(B) - 1):
                if B[j + 1] not in succ_a:
                    continue
                c1, c2 = A[:i + 1] + B[j + 1:], B[:j + 1] + A[i + 1:]
                if c1 in (A, B) or c2 in (A, B):
                    continue
                d1 = pa[i + 1] + pb[-1] - pb[j + 1]
                d2 = pb[j + 1] + pa[-1] - pa[i + 1]
                if not (lo <= d1 <= hi and lo <= d2 <= hi):
                    continue
                if j not in succ_b:
                    succ_b[j] = set(sp.successors(B[:j + 1]))
                if A[i + 1] in succ_b[j]:
                    cuts.append((c1, c2))
        changed = False
        for c1, c2 in self._shuffled(cuts)[:30]:
            if self._valid(c1) and self._valid(c2):
                a[:], b[:] = c1, c2
                changed = True
                break
        if self._free:
            na, nb = list(a.base), list(b.base)
            for k in range(len(na)):
                if self.rng.random() < 0.5:
                    na[k], nb[k] = nb[k], na[k]
            bb = sp.base_bounds
            if (na != list(a.base)) and bb.valid(na) and bb.valid(nb):
                a.base, b.base = tuple(na), tuple(nb)
                changed = True
        if changed:
            del a.fitness.values
            del b.fitness.values
        return a, b
