"""SearchSpace's memoized walk (successors, validate_order, random_order) against independent references.

``ref_successors`` / ``ref_validate`` are the straightforward algorithms written from the assembly
primitives (chain_step, next_compatible, Assembly.from_order), recomputed from scratch for every prefix.
``ref_random_order`` is the plain loop over the public ``successors`` + ``validate_order``. The fast
``random_order`` must return the same orders *and* leave the numpy Generator in the same state, so seeded
optimization runs do not change.
"""
from __future__ import annotations

import json
import math
import pickle

import numpy as np
import pytest
from conftest import IMPROV, PRIMITIVES, ROOT, TASKS, toy_module_set

from robodesign.core.errors import AssemblyError, InputError
from robodesign.design.optimize import create_optimizer
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate, SearchSpace
from robodesign.formats.assembly import Assembly, chain_step, free_connectors, next_compatible
from robodesign.formats.module_io import load_module_set

SETS = {"IMPROV": IMPROV, "primitives": PRIMITIVES, "robodesign_arm": ROOT / "assets" / "modules" / "robodesign_arm"}
RULES = {
    "default": {},
    "loose": dict(min_dof=3, max_dof=6, max_links_between=2),  # dead ends: random_order retries
    "short": dict(min_dof=1, max_dof=4, max_modules=6),
}


# -- references ------------------------------------------------------------------------------------------
def ref_successors(sp: SearchSpace, prefix):
    """The successors rule from scratch: dof/links of prefix[1:], chain the connectors, filter followers."""
    ms = sp.module_set
    prefix = [str(x) for x in prefix]
    if not prefix:
        return list(sp.base_modules)
    dof = links = 0
    for mid in prefix[1:]:
        m = ms[mid]
        if m.kind == "joint":
            dof, links = dof + m.dof, 0
        elif m.kind == "link":
            links += 1
    if len(prefix) > 1 and ms[prefix[-1]].kind == "eef":
        return []
    free = free_connectors(ms, prefix[0])
    for prev, mid in zip(prefix, prefix[1:]):
        free = chain_step(ms, prev, free, mid)
        if free is None:
            return []
    n = len(prefix)
    if n >= sp.max_modules:
        return []
    out = []
    for nxt in next_compatible(ms, prefix[-1]):
        m = ms[nxt]
        if nxt in sp.exclude or (m.kind == "eef" and sp.end_effectors is not None and nxt not in sp.end_effectors):
            continue
        if chain_step(ms, prefix[-1], free, nxt) is None:
            continue
        if m.kind == "eef":
            ok = sp.min_dof <= dof <= sp.max_dof
        elif m.kind == "joint":
            ok = dof + m.dof <= sp.max_dof
        elif m.kind == "link":
            ok = links < sp.max_links_between and n + 2 <= sp.max_modules
        else:
            ok = False
        if ok:
            out.append(nxt)
    return out


def ref_validate(sp: SearchSpace, order, successors=None):
    successors = successors or (lambda p: ref_successors(sp, p))
    order = tuple(str(x) for x in order)
    if not order:
        return "empty order"
    for i, mid in enumerate(order):
        if mid not in sp.module_set:
            return f"module {mid!r} is not in the module set"
        if mid not in successors(order[:i]):
            return f"module {mid!r} may not follow {list(order[:i])} under the rules"
    if not (len(order) > 1 and sp.module_set[order[-1]].kind == "eef"):
        return "the order does not end with an end effector"
    try:
        Assembly.from_order(sp.module_set, order)
    except AssemblyError as e:
        return str(e)
    return None


def ref_random_order(successors, validate_order, rng, max_tries: int = 200):
    """SearchSpace.random_order as it was: walk with successors(), then validate_order()."""
    for _ in range(max_tries):
        order = []
        while True:
            succ = successors(order)
            if not succ:
                break
            order.append(succ[int(rng.integers(len(succ)))])
        if validate_order(order) is None:
            return tuple(order)
    raise InputError("the search space contains no valid module order under its rules")


def _space(set_name, rules_name) -> SearchSpace:
    return SearchSpace(load_module_set(SETS[set_name]), **RULES[rules_name])


def _draws(fn, rng, n):
    out = []
    for _ in range(n):
        try:
            out.append(fn(rng))
        except InputError as e:
            out.append(str(e))
    return out


# -- random_order -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("rules_name", sorted(RULES))
@pytest.mark.parametrize("set_name", sorted(SETS))
def test_random_order_same_orders_and_draws_as_the_plain_loop(set_name, rules_name):
    sp, ref = _space(set_name, rules_name), _space(set_name, rules_name)  # no shared memo
    seeds = 300 if rules_name == "default" else 100
    for seed in range(seeds):
        rng_new, rng_ref = np.random.default_rng(seed), np.random.default_rng(seed)
        got = _draws(sp.random_order, rng_new, 3)
        want = _draws(lambda r: ref_random_order(ref.successors, ref.validate_order, r), rng_ref, 3)
        assert got == want, (set_name, rules_name, seed)
        assert rng_new.bit_generator.state == rng_ref.bit_generator.state, (set_name, rules_name, seed)


@pytest.mark.parametrize("set_name", sorted(SETS))
def test_random_order_matches_the_from_scratch_reference(set_name):
    sp, ref = _space(set_name, "loose"), _space(set_name, "loose")
    for seed in range(40):
        rng_new, rng_ref = np.random.default_rng(seed), np.random.default_rng(seed)
        want = ref_random_order(lambda p: ref_successors(ref, p), lambda o: ref_validate(ref, o), rng_ref)
        assert sp.random_order(rng_new) == want
        assert rng_new.bit_generator.state == rng_ref.bit_generator.state


def test_random_order_with_few_tries_and_no_valid_order():
    sp = _space("primitives", "short")
    for seed in range(100):  # often every try dead-ends: the same InputError after the same draws
        rng_new, rng_ref = np.random.default_rng(seed), np.random.default_rng(seed)
        got = _draws(lambda r: sp.random_order(r, max_tries=1), rng_new, 4)
        want = _draws(lambda r: ref_random_order(sp.successors, sp.validate_order, r, max_tries=1), rng_ref, 4)
        assert got == want
        assert rng_new.bit_generator.state == rng_ref.bit_generator.state
    none = SearchSpace(load_module_set(SETS["IMPROV"]), min_dof=7, max_dof=7, max_modules=4)
    rng = np.random.default_rng(0)
    with pytest.raises(InputError):
        none.random_order(rng)
    rng_ref = np.random.default_rng(0)
    with pytest.raises(InputError):
        ref_random_order(none.successors, none.validate_order, rng_ref)
    assert rng.bit_generator.state == rng_ref.bit_generator.state


def test_seeded_random_search_asks_the_same_candidates():
    problem = Problem.build(TASKS / "simple" / "PTP_3.json", IMPROV, "cyc")
    for seed in (2, 7):
        opt = create_optimizer("random", problem, seed=seed)
        got = [opt.ask().key() for _ in range(200)]
        ref_space = SearchSpace(problem.space.module_set, **{k: getattr(problem.space, k) for k in (
            "min_dof", "max_dof", "max_links_between", "max_modules", "bases", "end_effectors", "exclude")},
            base_bounds=problem.space.base_bounds)
        rng, seen, want = np.random.default_rng(seed), set(), []
        while len(want) < 200:  # RandomSearch.ask with the plain loop
            c = Candidate(ref_random_order(ref_space.successors, ref_space.validate_order, rng),
                          ref_space.base_bounds.sample(rng))
            if c.key() not in seen:
                seen.add(c.key())
                want.append(c.key())
        assert got == want
        assert opt.rng.bit_generator.state == rng.bit_generator.state


# -- successors / validate_order ----------------------------------------------------------------------------
def _probe_orders(sp: SearchSpace, rng, n=150):
    """Walked orders, their prefixes and mutations of them (replaced, inserted, deleted, swapped modules),
    valid or not."""
    ids = [m.id for m in sp.module_set]
    out = []
    for _ in range(n):
        order = []
        while True:
            s = ref_successors(sp, order)
            if not s:
                break
            order.append(s[int(rng.integers(len(s)))])
        out.append(tuple(order))
        o = list(order)
        if not o:
            continue
        i = int(rng.integers(len(o)))
        op = int(rng.integers(4))
        if op == 0:
            o[i] = ids[int(rng.integers(len(ids)))]
        elif op == 1:
            o.insert(i, ids[int(rng.integers(len(ids)))])
        elif op == 2:
            del o[i]
        elif len(o) > 1:
            j = int(rng.integers(len(o)))
            o[i], o[j] = o[j], o[i]
        out.append(tuple(o))
    return out


@pytest.mark.parametrize("rules_name", sorted(RULES))
@pytest.mark.parametrize("set_name", sorted(SETS))
def test_successors_and_validate_order_match_the_reference(set_name, rules_name):
    sp = _space(set_name, rules_name)
    rng = np.random.default_rng(11)
    for order in _probe_orders(sp, rng):
        assert sp.validate_order(order) == ref_validate(sp, order), order
        assert sp.validate_order(list(order)) == ref_validate(sp, order), order  # memoized answer
        for i in range(len(order) + 1):
            assert sp.successors(order[:i]) == ref_successors(sp, order[:i]), order[:i]
    assert sp.validate_order(()) == "empty order"
    assert sp.validate_order(("nope",)) == ref_validate(sp, ("nope",))
    with pytest.raises(KeyError):
        sp.successors(("nope", sp.base_modules[0]))
    with pytest.raises(KeyError):
        sp.successors((sp.base_modules[0], "nope"))


def _branching_set(tmp_path):
    """The toy set plus a link L with two distal connectors (types t and u) and an end effector X whose
    second connector (u) mates with L's: in B,L,J,X the end effector mates with J (its predecessor, one
    pair, so the walk allows it) and also with L's free u connector, which Assembly.from_order rejects."""
    folder = toy_module_set(tmp_path)
    data = json.loads((folder / "modules.json").read_text())
    eye = np.eye(4).tolist()
    flip = np.diag([1.0, -1.0, -1.0, 1.0]).tolist()
    body = lambda bid, cons: {"ID": bid, "mass": 0.3, "r_com": [0, 0, 0.05], "inertia": np.diag([1e-3] * 3).tolist(),
                              "connectors": cons, "collision": []}
    con = lambda cid, pose, g, t: {"ID": cid, "pose": pose, "gender": g, "type": t, "size": [1] if t != "eef" else []}
    up = np.eye(4)
    up[2, 3] = 0.1
    data["modules"] += [
        {"header": {"ID": "L", "name": "branch"}, "bodies": [body("l", [
            con("in", flip, "f", "t"), con("a", up.tolist(), "m", "t"), con("b", eye, "m", "u")])], "joints": []},
        {"header": {"ID": "X", "name": "eef-u"}, "bodies": [body("x", [
            con("in", flip, "f", "t"), con("side", eye, "f", "u"), con("tcp", up.tolist(), "m", "eef")])],
         "joints": []},
    ]
    (folder / "modules.json").write_text(json.dumps(data))
    return load_module_set(folder)


def test_assembly_check_of_walked_orders(tmp_path):
    ms = _branching_set(tmp_path)
    sp = SearchSpace(ms, min_dof=1, max_dof=2, max_links_between=1, max_modules=6)
    why = sp.validate_order(("B", "L", "J", "X"))
    assert why is not None and "ways" in why and why == ref_validate(sp, ("B", "L", "J", "X"))
    assert sp.validate_order(("B", "J", "L", "J", "E")) is None
    assert sp.validate_order(("B", "L", "J", "E")) is None
    orders = {o: ref_validate(sp, o) for o in _probe_orders(sp, np.random.default_rng(3), 300)}
    assert any(w is not None and "ways" in w for w in orders.values())  # the Assembly check rejects some
    for o, w in orders.items():
        assert sp.validate_order(o) == w, o
    ref = SearchSpace(ms, min_dof=1, max_dof=2, max_links_between=1, max_modules=6)
    for seed in range(200):
        rng_new, rng_ref = np.random.default_rng(seed), np.random.default_rng(seed)
        assert _draws(lambda r: sp.random_order(r, max_tries=3), rng_new, 3) == \
            _draws(lambda r: ref_random_order(ref.successors, ref.validate_order, r, max_tries=3), rng_ref, 3)
        assert rng_new.bit_generator.state == rng_ref.bit_generator.state


# -- memo caches -------------------------------------------------------------------------------------------------
def test_memo_caches_are_not_pickled():
    sp = _space("IMPROV", "default")
    bare = len(pickle.dumps(sp))
    rng = np.random.default_rng(0)
    for _ in range(200):
        sp.random_order(rng)
    sp.count_orders()
    assert any(k.startswith("_memo") for k in vars(sp))
    data = pickle.dumps(sp)
    assert len(data) < bare + 1000  # (the module set may cache a few values of its own)
    back = pickle.loads(data)
    assert not any(k.startswith("_memo") for k in vars(back))
    rng_a, rng_b = np.random.default_rng(5), np.random.default_rng(5)
    assert [back.random_order(rng_a) for _ in range(20)] == [sp.random_order(rng_b) for _ in range(20)]
    assert back.count_orders() == sp.count_orders()


@pytest.mark.parametrize("set_name", sorted(SETS))
def test_completion_counts_of_any_prefix_match_enumeration(set_name):
    sp = _space(set_name, "short")
    orders, stack = [], [()]
    while stack:  # every valid order, enumerated with the reference rule
        p = stack.pop()
        succ = ref_successors(sp, p)
        if not succ:
            if ref_validate(sp, p) is None:
                orders.append(p)
            continue
        stack += [p + (s,) for s in succ]
    assert sp.count_orders() == len(orders) > 0
    mass = lambda o: sum(sp.module_info(m).mass for m in o)
    probes = {o[:i] for o in _probe_orders(sp, np.random.default_rng(5), 100) for i in range(len(o) + 1)}
    probes = {p for p in probes if all(m in sp.module_set for m in p)}
    for p in sorted(probes):
        done = [o for o in orders if o[:len(p)] == p]
        assert sp.count_completions(p) == len(done), p
        assert sp.lightest_completion(p) == pytest.approx(min((mass(o) - mass(p) for o in done), default=math.inf)), p
