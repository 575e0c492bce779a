"""The design space an optimizer searches: module orders (under rules) × base poses.

A :class:`SearchSpace` knows the module set, the rules (DoF range, at most ``max_links_between``
passive link modules between two joint modules, allowed bases/end effectors) and the base-pose
bounds derived from the task's base-placement tolerance. It offers what optimizer plugins need:
validity checks with reasons, successors of a partial order (for tree search), random candidates,
exhaustive enumeration and base-pose parameters ↔ 4x4 poses.

A :class:`Candidate` is plain data: ``order`` (module IDs, base first) and ``base`` (offsets
x, y, z [m], yaw [rad] relative to the nominal base pose; empty when the base is fixed).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Dict, Iterator, List, Optional, Sequence, Tuple

import numpy as np

from .assembly import Assembly
from .errors import AssemblyError, InputError
from .module_spec import ModuleSet
from .spatial import homogeneous, rot_z

BASE_PARAMS = ("x", "y", "z", "yaw")


@dataclass(frozen=True)
class Candidate:
    order: Tuple[str, ...]
    base: Tuple[float, ...] = ()

    def key(self) -> str:
        b = ",".join(f"{v:.6f}" for v in self.base)
        return ",".join(self.order) + (f"@{b}" if b else "")

    @staticmethod
    def from_key(key: str) -> "Candidate":
        order, _, base = key.partition("@")
        return Candidate(tuple(order.split(",")), tuple(float(x) for x in base.split(",")) if base else ())

    def to_json(self) -> dict:
        return {"order": list(self.order), "base": list(self.base)}


@dataclass(frozen=True)
class BaseBounds:
    """Box bounds on (x, y, z, yaw) offsets from ``nominal``; a parameter with lo == hi is fixed."""
    nominal: np.ndarray = field(default_factory=lambda: np.eye(4))
    lower: Tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    upper: Tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    tolerance: object = None  # ToleratedPose that a base pose must satisfy (None: any)

    @property
    def free(self) -> Tuple[int, ...]:
        return tuple(i for i in range(4) if self.upper[i] > self.lower[i])

    def pose(self, params: Sequence[float]) -> np.ndarray:
        full = [0.0, 0.0, 0.0, 0.0]
        for i, v in zip(self.free, params):
            full[i] = float(v)
        return self.nominal @ homogeneous(rot_z(full[3]), full[:3])

    def valid(self, params: Sequence[float]) -> bool:
        free = self.free
        if len(params) != len(free):
            return False
        for i, v in zip(free, params):
            if not (self.lower[i] - 1e-12 <= v <= self.upper[i] + 1e-12):
                return False
        return self.tolerance is None or self.tolerance.valid(self.pose(params))

    def sample(self, rng, max_tries: int = 1000) -> Tuple[float, ...]:
        free = self.free
        for _ in range(max_tries):
            p = tuple(float(rng.uniform(self.lower[i], self.upper[i])) for i in free)
            if self.valid(p):
                return p
        return tuple(0.0 for _ in free)

    @staticmethod
    def from_tolerance(tp, default_span: float = 0.0) -> "BaseBounds":
        """Bounds from a base-placement ToleratedPose: x/y/z intervals (nominal or world frame), r_cyl or
        r_sph as a box, yaw from N_z or Theta_R. An unconstrained tolerance gives a fixed base."""
        if tp is None:
            return BaseBounds()
        nominal = np.array(tp.nominal, dtype=float)
        if getattr(tp, "is_unconstrained", False):
            return BaseBounds(nominal=nominal, tolerance=None)
        lo = [0.0, 0.0, 0.0, 0.0]
        hi = [0.0, 0.0, 0.0, 0.0]
        for name, (a, b), _frame in tp.entries:
            if name in ("x", "y", "z"):
                i = "xyz".index(name)
                lo[i], hi[i] = max(lo[i], a) if lo[i] else a, min(hi[i], b) if hi[i] else b
            elif name in ("r_cyl", "r_sph"):
                for i in (0, 1) if name == "r_cyl" else (0, 1, 2):
                    lo[i], hi[i] = -b, b
            elif name in ("N_z", "Y", "Alpha"):
                lo[3], hi[3] = a, b
            elif name == "Theta_R":
                lo[3], hi[3] = -b, b
        lo = [max(-10.0, v) for v in lo]
        hi = [min(10.0, v) for v in hi]
        return BaseBounds(nominal=nominal, lower=tuple(lo), upper=tuple(hi), tolerance=tp)


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
        return _followers(self.module_set, mid, self.exclude, self.bases, self.end_effectors)

    def _state(self, prefix: Sequence[str]) -> Tuple[int, int, bool]:
        """(dof so far, links since the last joint, complete)"""
        ms = self.module_set
        dof, links = 0, 0
        for mid in prefix[1:]:
            k = ms[mid].kind
            if k == "joint":
                dof += ms[mid].dof
                links = 0
            elif k == "link":
                links += 1
        complete = len(prefix) > 1 and ms[prefix[-1]].kind == "eef"
        return dof, links, complete

    def successors(self, prefix: Sequence[str]) -> List[str]:
        """Modules that may follow ``prefix`` (a valid partial order) under the rules."""
        if not prefix:
            return list(self.base_modules)
        dof, links, complete = self._state(prefix)
        if complete or len(prefix) >= self.max_modules:
            return []
        out = []
        for nxt in self._followers(prefix[-1]):
            m = self.module_set[nxt]
            if m.kind == "eef":
                if self.min_dof <= dof <= self.max_dof:
                    out.append(nxt)
            elif m.kind == "joint":
                if dof + m.dof <= self.max_dof:
                    out.append(nxt)
            elif m.kind == "link":
                if links < self.max_links_between and len(prefix) + 2 <= self.max_modules:
                    out.append(nxt)
        return out

    def is_complete(self, order: Sequence[str]) -> bool:
        return self.validate_order(order) is None

    def validate_order(self, order: Sequence[str]) -> Optional[str]:
        """None if ``order`` is a complete valid design under the rules, else the reason."""
        order = tuple(str(x) for x in order)
        if not order:
            return "empty order"
        for i, mid in enumerate(order):
            if mid not in self.module_set:
                return f"module {mid!r} is not in the module set"
            allowed = self.successors(order[:i])
            if mid not in allowed:
                return f"module {mid!r} may not follow {list(order[:i])} under the rules"
        dof, _, complete = self._state(order)
        if not complete:
            return "the order does not end with an end effector"
        try:
            Assembly.from_order(self.module_set, order)
        except AssemblyError as e:
            return str(e)
        return None

    def random_order(self, rng, max_tries: int = 200) -> Tuple[str, ...]:
        for _ in range(max_tries):
            order: List[str] = []
            while True:
                succ = self.successors(order)
                if not succ:
                    break
                # prefer finishing once the DoF target is met, else continue
                order.append(succ[int(rng.integers(len(succ)))])
            if self.validate_order(order) is None:
                return tuple(order)
        raise InputError("the search space contains no valid module order under its rules")

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

    def count_orders(self, limit: int = 10 ** 7) -> int:
        """Number of valid orders (dynamic programming over (last module, dof, links))."""
        ms = self.module_set

        @lru_cache(maxsize=None)
        def count(last: str, dof: int, links: int, n: int) -> int:
            total = 0
            for nxt in self.successors(_fake_prefix(last, dof, links, n)):
                m = ms[nxt]
                if m.kind == "eef":
                    total += 1
                elif m.kind == "joint":
                    total += count(nxt, dof + m.dof, 0, n + 1)
                else:
                    total += count(nxt, dof, links + 1, n + 1)
            return total

        def _fake_prefix(last, dof, links, n):
            return _Prefix(last, dof, links, n)

        self_state = self._state

        class _Prefix(tuple):
            def __new__(cls, last, dof, links, n):
                obj = super().__new__(cls, ("?",) * (n - 1) + (last,))
                obj.state = (dof, links, False)
                return obj

        def patched(prefix):
            return prefix.state if isinstance(prefix, _Prefix) else self_state(prefix)
        object.__setattr__(self, "_state", patched)
        try:
            return sum(count(b, 0, 0, 1) for b in self.base_modules)
        finally:
            object.__delattr__(self, "_state")

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


@lru_cache(maxsize=4096)
def _followers_cached(ms_id: int, mid: str, exclude, bases, eefs, ms_ref) -> Tuple[str, ...]:
    ms = ms_ref()
    prev = ms[mid]
    out = []
    for m in ms:
        if m.kind == "base" or m.id in exclude:
            continue
        if m.kind == "eef" and eefs is not None and m.id not in eefs:
            continue
        if any(c_new.mates_with(c_old)[0] for c_old in prev.connectors if c_old.type != "base"
               for c_new in m.connectors):
            out.append(m.id)
    return tuple(out)


def _followers(ms: ModuleSet, mid: str, exclude, bases, eefs) -> Tuple[str, ...]:
    import weakref
    return _followers_cached(id(ms), mid, tuple(exclude), bases, eefs, weakref.ref(ms))
