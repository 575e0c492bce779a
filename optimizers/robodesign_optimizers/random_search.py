"""Random search: the baseline. Uniformly random valid module orders (under the search-space rules)
and base poses; never proposes the same candidate twice (up to ``max_duplicates`` retries)."""
from __future__ import annotations

from typing import Optional

from robodesign.optimize import Optimizer
from robodesign.search_space import Candidate


class RandomSearch(Optimizer):
    name = "random"
    description = "uniformly random valid designs (baseline)"

    def __init__(self, space, seed: int = 0, max_duplicates: int = 100, **options):
        super().__init__(space, seed, **options)
        self.max_duplicates = int(max_duplicates)
        self.seen = set()

    def ask(self) -> Optional[Candidate]:
        for _ in range(self.max_duplicates):
            c = self.space.random_candidate(self.rng)
            if c.key() not in self.seen:
                self.seen.add(c.key())
                return c
        return None
