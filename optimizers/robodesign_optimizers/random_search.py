"""Random search: the baseline. Uniformly random valid module orders (under the search-space rules) and
base poses; never proposes the same candidate twice (up to ``max_duplicates`` retries).

With a free base, the base of each order is placed from the goals' geometry (``space.sample_base``: its
reach bound covers the goals when some pose in the bounds does) unless ``informed=false`` (then uniform in
the bounds). A fixed base asks exactly what it asked before."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Set

from robodesign.plugin import Candidate, Optimizer, option


class RandomSearch(Optimizer):
    name = "random"
    description = "uniformly random valid designs (baseline)"
    independent_asks = True  # ask() reads only its own random state and what it asked before

    @dataclass(frozen=True)
    class Options:
        max_duplicates: int = option(100, low=1, help="draws of an already asked design before ask gives up")
        informed: bool = option(True, help="place a free base from the goals' geometry (space.sample_base); "
                                           "false: uniformly in the bounds")

    def __init__(self, problem, seed: int = 0, **options):
        super().__init__(problem, seed, **options)
        self.seen: Set[str] = set()   # keys of the candidates asked

    def ask(self) -> Optional[Candidate]:
        for _ in range(self.options.max_duplicates):
            if self.options.informed and self.space.base_dims:
                order = self.space.random_order(self.rng)
                c = Candidate(order, self.space.sample_base(self.rng, order))
            else:
                c = self.space.random_candidate(self.rng)
            if c.key() not in self.seen:
                self.seen.add(c.key())
                return c
        return None
