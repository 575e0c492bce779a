"""A random generator made when it is first used (:class:`LazyGenerator`)."""
from __future__ import annotations

from typing import Optional

import numpy as np


class LazyGenerator:
    """``np.random.default_rng(seed)``, made when it is first used (making one costs ~15–90 µs): the solve
    pipeline's IK-stage generator, which most candidates that fail there never draw from (the rank and reach
    tests come first). Every public attribute is the generator's, and :func:`robodesign.solvers.ik.solve_ik`
    takes it as the generator itself, so the draws are those of the generator made at once."""

    __slots__ = ("_seed", "_generator")

    def __init__(self, seed) -> None:
        self._seed = seed
        self._generator: Optional[np.random.Generator] = None

    @property
    def generator(self) -> np.random.Generator:
        if self._generator is None:
            self._generator = np.random.default_rng(self._seed)
        return self._generator

    def __getattr__(self, name: str):
        if name.startswith("_"):   # (its own slots before they are set, and the copy and pickle protocols)
            raise AttributeError(name)
        return getattr(self.generator, name)
