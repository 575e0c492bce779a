"""Random search: the baseline. Uniformly random valid module orders (under the search-space rules)
and base poses; never proposes the same candidate twice (up to ``max_duplicates`` retries)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

from robodesign.plugin import Candidate, Optimizer, option


class RandomSearch(Optimizer):
    name = "random"
    description = "uniformly random valid designs (baseline)"
    independent_asks = True  # ask() reads only its own random state and what it asked before

    @dataclass(frozen=True)
    class Options:
        max_duplicates: int = option(100, low=1, help="draws of an already asked design before ask gives up")

    def __init__(self, problem, seed: int = 0, **options):
        super().__init__(problem, seed, **options)
        self.seen = set()

    def ask(self) -> Optional[Candidate]:
        for _ in range(self.options.max_duplicates):
            c = self.space.random_candidate(self.rng)
            if c.key() not in self.seen:
                self.seen.add(c.key())
                return c
        return None
