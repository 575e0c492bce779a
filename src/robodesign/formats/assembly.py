"""Assemblies: which module instances are connected through which connectors.

An :class:`Assembly` is plain data (module IDs per instance, connections, base connector).
It is built either from a serial *module order* (the shortcut behind CoBRA solutions'
``moduleOrder``) or from an explicit connection graph (``moduleConnection``/``baseConnection``).
Connector rules (the CoBRA paper): types and sizes equal, genders f–m or h–h; mated frames
have aligned x-axes and anti-parallel z-axes (the transform between them is Rx(π)).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, List, NoReturn, Optional, Sequence, Tuple

from robodesign.core.errors import AssemblyError
from robodesign.formats.module_spec import Connector, ModuleSet

Connection = Tuple[int, str, int, str]  # (instance a, connector of a, instance b, connector of b)
_ORDERS: Dict[Tuple[int, Tuple[str, ...]], Tuple[ModuleSet, "Assembly"]] = {}  # Assembly.from_order's memo


@dataclass(frozen=True)
class Assembly:
    module_ids: Tuple[str, ...]
    connections: Tuple[Connection, ...]
    base: Tuple[int, str]  # (instance, connector id) that attaches to the world

    @property
    def order(self) -> Tuple[str, ...]:
        return self.module_ids

    def key(self) -> str:
        """A stable text key (for caches and databases; made once per assembly)."""
        k = self.__dict__.get("_key")
        if k is None:
            con = ";".join(f"{a}:{ca}-{b}:{cb}" for a, ca, b, cb in self.connections)
            k = self.__dict__["_key"] = f"{','.join(self.module_ids)}|{con}|{self.base[0]}:{self.base[1]}"
        return k

    def is_serial(self) -> bool:
        return all(b == a - 1 for a, _, b, _ in self.connections) and self.base[0] == 0

    # -- construction -----------------------------------------------------------------------
    @staticmethod
    def from_order(ms: ModuleSet, order: Sequence) -> "Assembly":
        """The serial assembly of ``order`` (AssemblyError if its modules do not chain); remembered per module set
        and order (a search builds the same orders again and again)."""
        key = (id(ms), tuple(str(x) for x in order))
        hit = _ORDERS.get(key)
        if hit is not None and hit[0] is ms:
            return hit[1]
        asm = Assembly._from_order(ms, key[1])
        if len(_ORDERS) >= 4096:
            _ORDERS.clear()
        _ORDERS[key] = (ms, asm)
        return asm

    @staticmethod
    def _from_order(ms: ModuleSet, order: Sequence) -> "Assembly":
        order = [str(x) for x in order]
        if not order:
            raise AssemblyError("module order is empty")
        modules = ms.modules
        for i, mid in enumerate(order):
            if mid not in modules:
                raise AssemblyError(f"module {mid!r} at position {i} is not in module set {ms.name!r} "
                                    f"(IDs: {', '.join(sorted(ms.ids, key=_natural))})")
        first = modules[order[0]]
        bases = [c for c in first.connectors if c.type == "base"]
        if len(bases) != 1:
            raise AssemblyError(f"the first module {order[0]!r} ({first.name}) must have exactly one base connector, "
                                f"it has {len(bases)}")
        free = [_free(ms, order[0])]  # per instance: connectors a later module may attach to
        open_ = [0] if free[0] else []  # the instances with a free connector, in order
        connections: List[Connection] = []
        for i in range(1, len(order)):
            step = _step(ms, order, i, open_, free)
            if step is None:
                _no_step(ms, order, i, open_, free)
            p, old_id, new_id, free_k, free_i = step
            k = open_[p]
            free[k] = free_k
            if not free_k:
                del open_[p]
            free.append(free_i)
            if free_i:
                open_.append(i)
            connections.append((i, new_id, k, old_id))
        return Assembly(tuple(order), tuple(connections), (0, bases[0].id))

    @staticmethod
    def from_graph(ms: ModuleSet, module_ids: Sequence, connections: Sequence[Sequence],
                   base: Optional[Sequence] = None) -> "Assembly":
        ids = [str(x) for x in module_ids]
        for i, mid in enumerate(ids):
            if mid not in ms:
                raise AssemblyError(f"module {mid!r} at position {i} is not in module set {ms.name!r}")
        used: Dict[Tuple[int, str], int] = {}
        cons: List[Connection] = []
        for n, c in enumerate(connections):
            if len(c) != 4:
                raise AssemblyError(f"connection {n} must be [i_a, connector_a, i_b, connector_b], got {list(c)}")
            a, ca, b, cb = int(c[0]), str(c[1]), int(c[2]), str(c[3])
            for i, con in ((a, ca), (b, cb)):
                if not 0 <= i < len(ids):
                    raise AssemblyError(f"connection {n} names module index {i}, but there are {len(ids)} modules")
                try:
                    ms[ids[i]].connector(con)
                except KeyError:
                    raise AssemblyError(f"connection {n}: module {ids[i]!r} (index {i}) has no connector {con!r}") from None
                if (i, con) in used:
                    raise AssemblyError(f"connection {n}: connector {con!r} of module index {i} is already used by "
                                        f"connection {used[(i, con)]}")
                used[(i, con)] = n
            if a == b:
                raise AssemblyError(f"connection {n} connects module index {a} to itself")
            ok, why = ms[ids[a]].connector(ca).mates_with(ms[ids[b]].connector(cb))
            if not ok:
                raise AssemblyError(f"connection {n}: {ids[a]}.{ca} ↔ {ids[b]}.{cb} do not connect: {why}")
            cons.append((a, ca, b, cb))
        if base is None or len(base) == 0:
            free = [(i, c.id) for i, mid in enumerate(ids) for c in ms[mid].connectors
                    if c.type == "base" and (i, c.id) not in used]
            if len(free) != 1:
                raise AssemblyError(f"expected exactly one free base connector, found {len(free)}; give baseConnection")
            base_t = free[0]
        else:
            base_t = (int(base[0]), str(base[1]))
            if not 0 <= base_t[0] < len(ids):
                raise AssemblyError(f"baseConnection names module index {base_t[0]}, but there are {len(ids)} modules")
            try:
                ms[ids[base_t[0]]].connector(base_t[1])
            except KeyError:
                raise AssemblyError(f"baseConnection: module {ids[base_t[0]]!r} has no connector {base_t[1]!r}") from None
            if base_t in used:
                raise AssemblyError(f"baseConnection: connector {base_t[1]!r} is already used by a connection")
        # connectivity
        adj: Dict[int, set] = {i: set() for i in range(len(ids))}
        for a, _, b, _ in cons:
            adj[a].add(b)
            adj[b].add(a)
        seen, stack = {base_t[0]}, [base_t[0]]
        while stack:
            for nb in adj[stack.pop()]:
                if nb not in seen:
                    seen.add(nb)
                    stack.append(nb)
        if len(seen) != len(ids):
            missing = sorted(set(range(len(ids))) - seen)
            raise AssemblyError(f"modules at indices {missing} are not connected to the base")
        if len(cons) != len(ids) - 1:
            raise AssemblyError("the connection graph has a loop; only tree-shaped assemblies are supported")
        return Assembly(tuple(ids), tuple(cons), base_t)

    def to_json(self) -> dict:
        """The CoBRA solution fields describing this assembly."""
        out: dict = {"moduleOrder": list(self.module_ids)}
        if not self.is_serial():
            out["moduleConnection"] = [[a, ca, b, cb] for a, ca, b, cb in self.connections]
            out["baseConnection"] = [[self.base[0], self.base[1], 0]]
        return out


_STEPS: Dict[tuple, Tuple[ModuleSet, Optional[tuple]]] = {}   # _step's memo


def _step(ms: ModuleSet, order: List[str], i: int, open_: List[int], free: List[Tuple[str, ...]]) -> Optional[tuple]:
    """How module ``i`` of a module order attaches (the serial-chaining rule, :func:`chain_pairs`, over the free
    connectors ``free[k]`` of the instances ``open_``): (its instance's position in ``open_``, the connector of that
    instance, the module's connector, that instance's free connectors after, the module's), or None where it does not
    attach to the previous module in exactly one way (:func:`_no_step` says why). It depends only on the modules
    and free connectors of the open instances, which is the previous one, and module ``i``: remembered per module set
    and those (a search meets the same few steps at every position of every order)."""
    key = (id(ms), order[i], tuple([(order[k], free[k], k == i - 1) for k in open_]))
    hit = _STEPS.get(key)
    if hit is not None and hit[0] is ms:
        return hit[1]
    cands = [(p, c_old, c_new) for p, k in enumerate(open_) for c_old, c_new in chain_pairs(ms, order[k], free[k], order[i])]
    step = None
    if len(cands) == 1 and open_[cands[0][0]] == i - 1:
        p, c_old, c_new = cands[0]
        step = (p, c_old.id, c_new.id, tuple(c for c in free[i - 1] if c != c_old.id),
                tuple(c for c in _free(ms, order[i]) if c != c_new.id))   # (free_connectors, used=(c_new.id,))
    if len(_STEPS) >= 65536:
        _STEPS.clear()
    _STEPS[key] = (ms, step)   # (the module set held: its id is not reused while the entry lives)
    return step


def _no_step(ms: ModuleSet, order: List[str], i: int, open_: List[int], free: List[Tuple[str, ...]]) -> NoReturn:
    """The AssemblyError of module ``i`` of a module order that does not attach to the previous module in exactly
    one way (:func:`_step` is None)."""
    cands = [(k, c_old, c_new) for k in open_ for c_old, c_new in chain_pairs(ms, order[k], free[k], order[i])]
    if len(cands) != 1:
        _not_one(ms, order, i, free, cands)
    k = cands[0][0]
    raise AssemblyError(f"module {order[i]!r} at position {i} would connect to module {order[k]!r} at "
                        f"position {k}, not to the previous module {order[i-1]!r}: a module order must "
                        f"form a chain")


def _not_one(ms: ModuleSet, order: List[str], i: int, free: List[Tuple[str, ...]], cands: list) -> None:
    """The AssemblyError of module ``i`` of a module order that attaches in no way or in several ways."""
    new, prev = ms[order[i]], ms[order[i - 1]]
    if not cands:
        reasons = [f"{c_new.id} ({_cdesc(c_new)}) vs {c_old.id} ({_cdesc(c_old)}): "
                   f"{c_new.mates_with(c_old)[1]}"
                   for c_old in prev.connectors if c_old.id in free[i - 1] for c_new in new.connectors]
        detail = "; ".join(reasons[:4]) or f"module {order[i-1]!r} has no free connector left"
        raise AssemblyError(f"modules {order[i-1]!r} ({prev.name}) → {order[i]!r} ({new.name}) at positions "
                            f"{i-1}→{i} do not connect: {detail}")
    desc = ", ".join(f"{c_new.id}↔{order[k]}.{c_old.id}" for k, c_old, c_new in cands)
    raise AssemblyError(f"module {order[i]!r} ({new.name}) at position {i} can be connected in "
                        f"{len(cands)} ways ({desc}); use an explicit moduleConnection")


def _cdesc(c: Connector) -> str:
    return f"{c.type}/{list(c.size)}/{c.gender}"


def _natural(s: str):
    return (0, int(s), "") if s.isdigit() else (1, 0, s)


# -- the serial-chaining rule (module orders; used by Assembly.from_order and the search space) ------------
def free_connectors(ms: ModuleSet, module_id: str, used: Sequence[str] = ()) -> Tuple[str, ...]:
    """IDs of the connectors of ``module_id`` that a later module of a serial order may attach to: all but
    its base connector and the ``used`` ones."""
    return tuple(c.id for c in ms[module_id].connectors if c.type != "base" and c.id not in used)


_FREE: Dict[Tuple[int, str], Tuple[ModuleSet, Tuple[str, ...]]] = {}   # (id(ms), module id) → (ms, free_connectors)


def _free(ms: ModuleSet, module_id: str) -> Tuple[str, ...]:
    """:func:`free_connectors` of ``module_id`` (no ``used``), remembered per module set."""
    hit = _FREE.get((id(ms), module_id))
    if hit is None or hit[0] is not ms:
        if len(_FREE) >= 65536:
            _FREE.clear()
        hit = _FREE[(id(ms), module_id)] = (ms, free_connectors(ms, module_id))   # (ms held: its id is not reused)
    return hit[1]


def chain_pairs(ms: ModuleSet, prev_id: str, free: Sequence[str], next_id: str) -> List[Tuple[Connector, Connector]]:
    """The serial-chaining rule: the (connector of ``prev_id``, connector of ``next_id``) pairs that mate, over
    the ``free`` connectors of ``prev_id``. In a module order, a module attaches to the previous one iff
    exactly one pair mates (and none with an earlier module); its free connectors are then the others.
    Remembered per module set and arguments (a search asks the same few again and again)."""
    key = (id(ms), prev_id, tuple(free), next_id)
    hit = _PAIRS.get(key)
    if hit is not None and hit[0] is ms:
        return list(hit[1])
    new = ms[next_id]
    pairs = [(c_old, c_new) for c_old in ms[prev_id].connectors if c_old.id in free and c_old.type != "base"
             for c_new in new.connectors if c_new.mates_with(c_old)[0]]
    if len(_PAIRS) >= 65536:
        _PAIRS.clear()
    _PAIRS[key] = (ms, tuple(pairs))   # the module set is held: its id is not reused while the entry lives
    return pairs


_PAIRS: Dict[Tuple[int, str, Tuple[str, ...], str], Tuple[ModuleSet, Tuple[Tuple[Connector, Connector], ...]]] = {}


def chain_step(ms: ModuleSet, prev_id: str, free: Sequence[str], next_id: str) -> Optional[Tuple[str, ...]]:
    """Free connectors of ``next_id`` after attaching it to ``prev_id`` (whose free connectors are ``free``)
    by the chaining rule; None if it does not attach with exactly one connector pair (none: it does not
    connect; several: ambiguous, :meth:`Assembly.from_order` rejects it)."""
    pairs = chain_pairs(ms, prev_id, free, next_id)
    if len(pairs) != 1:
        return None
    return free_connectors(ms, next_id, used=(pairs[0][1].id,))


def next_compatible(ms: ModuleSet, module_id: str, exclude_kinds: Sequence[str] = ("base",)) -> List[str]:
    """IDs of modules that can follow ``module_id`` in a serial order (one connector pair mates)."""
    free = free_connectors(ms, module_id)
    return [m.id for m in ms if m.kind not in exclude_kinds and chain_pairs(ms, module_id, free, m.id)]


def random_serial_order(ms: ModuleSet, rng, dof: int = 6, max_links_between: int = 1,
                        max_tries: int = 1000) -> List[str]:
    """A random valid serial module order (base, joint/link modules, end effector) with ``dof`` joints.

    At most ``max_links_between`` link modules stand between two joint modules. Validity is
    checked with :meth:`Assembly.from_order`; raises :class:`AssemblyError` if none is found.
    """
    bases = [m.id for m in ms.of_kind("base")]
    if not bases:
        raise AssemblyError(f"module set {ms.name!r} has no base module")
    # (last module, joints left, a link allowed) → the modules that may come next, made once per call
    options: Dict[Tuple[str, int, bool], List[str]] = {}
    for _ in range(max_tries):
        order = [bases[rng.integers(len(bases))]]
        d, links = 0, 0
        ok = True
        while True:
            key = (order[-1], dof - d, links < max_links_between)
            cands = options.get(key)
            if cands is None:
                cands = next_compatible(ms, order[-1])
                if d >= dof:
                    cands = [c for c in cands if ms[c].kind == "eef"]
                else:
                    cands = [c for c in cands if ms[c].kind != "eef" and ms[c].dof <= dof - d
                             and (ms[c].kind == "joint" or links < max_links_between)]
                options[key] = cands
            if not cands:
                ok = False
                break
            nxt = cands[rng.integers(len(cands))]
            order.append(nxt)
            if ms[nxt].kind == "eef":
                break
            if ms[nxt].kind == "joint":
                d += ms[nxt].dof
                links = 0
            else:
                links += 1
        if not ok:
            continue
        try:
            Assembly.from_order(ms, order)
        except AssemblyError:
            continue
        return order
    raise AssemblyError(f"no valid serial order with {dof} DoF found in module set {ms.name!r}")
