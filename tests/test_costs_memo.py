"""The cost terms' values kept per context (CostContext.term_value) and named_costs kept per state of the registry
(issue 25): against the former computation (each term's function called anew at every ask, the named costs built
anew at every call), on random trajectories and weights, bit for bit."""
import numpy as np
import pytest

from robodesign.formats import costs
from robodesign.formats.costs import CostContext, CostFunction, MissingQuantityError, named_costs, register_cost


def _context(rng, n, dof, lazy=True):
    t = np.cumsum(np.r_[0.0, rng.uniform(0.001, 0.2, n - 1)])
    q, dq, ddq, tau, tau_link = (rng.normal(0, 2, (n, dof)) for _ in range(5))
    if rng.random() < 0.3:
        tau[rng.integers(n), rng.integers(dof)] = rng.choice([np.inf, -np.inf, np.nan, 1e308])
    kw = dict(t=t, q=q, dq=dq, ddq=ddq, mass=float(rng.uniform(1, 30)), num_joints=dof,
              goals_achieved=int(rng.integers(0, 4)), num_goals=int(rng.integers(0, 4)))
    if lazy:
        return lambda: CostContext(**kw, tau=lambda: tau, tau_link=lambda: tau_link)
    return lambda: CostContext(**kw, tau=tau, tau_link=tau_link)


def _former(cf: CostFunction, ctx: CostContext) -> float:
    """CostFunction.evaluate as it was: every term's function called anew."""
    return float(sum({n: (w * float(costs._REGISTRY[n].fn(ctx)) if w != 0 else 0.0) for n, w in cf.terms}.values()))


def _bits(x: float) -> bytes:
    return np.float64(x).tobytes()


def test_kept_term_values_are_the_former_evaluation():
    """Every named cost and 40 random weighted sums, all evaluated on one context (the judge's use: each term asked
    by several costs), equal the former evaluation on a fresh context, bit for bit; raw_values too."""
    rng = np.random.default_rng(25)
    names = sorted(costs._REGISTRY)
    for case in range(30):
        make = _context(rng, int(rng.integers(2, 60)), int(rng.integers(1, 8)), lazy=case % 2 == 0)
        shared = make()
        fns = list(named_costs().values())
        for _ in range(40):
            k = int(rng.integers(1, len(names) + 1))
            picked = rng.choice(names, size=k, replace=False)
            weights = [float(rng.choice([0.0, 1.0, rng.uniform(0, 5), 1e6])) for _ in picked]
            weights = [-w if costs._REGISTRY[n].reward and rng.random() < 0.5 else w for n, w in zip(picked, weights)]
            fns.append(CostFunction(tuple(zip(picked, weights))))
        for cf in fns:
            assert _bits(cf.evaluate(shared)) == _bits(_former(cf, make()))
            fresh = make()
            assert {n: _bits(v) for n, v in cf.raw_values(shared).items()} == \
                {n: _bits(float(costs._REGISTRY[n].fn(fresh))) for n, w in cf.terms if w != 0}


def test_a_term_is_computed_once_per_context_and_again_when_registered_anew():
    calls = []

    def counted(c):
        calls.append(1)
        return float(c.t[-1]) * 2
    register_cost("memoTwice", counted, "2 × cycle time", overwrite=True)
    try:
        ctx = CostContext(t=[0.0, 0.5, 2.0], q=[[0.0], [1.0], [3.0]])
        for cf in (CostFunction((("memoTwice", 1.0),)), CostFunction((("memoTwice", 0.5), ("cyc", 1.0)))):
            cf.evaluate(ctx)
        assert len(calls) == 1 and ctx.term_value("memoTwice") == 4.0
        register_cost("memoTwice", lambda c: float(c.t[-1]) * 3, "3 × cycle time", overwrite=True)
        assert ctx.term_value("memoTwice") == 6.0                           # the new term, not the kept value
        assert CostFunction((("memoTwice", 1.0),)).evaluate(ctx) == 6.0
    finally:
        del costs._REGISTRY["memoTwice"]


def test_a_term_that_raises_is_asked_again():
    ctx = CostContext(t=[0.0, 1.0], q=[[0.0], [1.0]])
    for _ in range(2):
        with pytest.raises(MissingQuantityError):
            ctx.term_value("effort")
    assert "effort" not in ctx._terms


def _named_former():
    out = {n: CostFunction(((n, 1.0),)) for n in costs._REGISTRY}
    out.update({n: CostFunction(terms, name=n) for n, terms in costs._COMPOUNDS.items()})
    return out


def _same(a, b):
    return list(a) == list(b) and all(a[k] == b[k] and a[k].name == b[k].name for k in a)


def test_named_costs_follow_the_registry():
    """named_costs equals the dict built anew, in order and names, after registering, overwriting and deleting terms
    and compounds (also by editing the registry directly, as tests do), and its dict is the caller's own."""
    assert _same(named_costs(), _named_former())
    got = named_costs()
    got.clear()
    assert _same(named_costs(), _named_former())
    register_cost("memoNamed", lambda c: 1.0, "one", overwrite=True)
    try:
        assert "memoNamed" in named_costs() and _same(named_costs(), _named_former())
        costs.register_compound("MemoComp", {"memoNamed": 2.0, "cyc": 1.0}, "two plus cyc", overwrite=True)
        assert _same(named_costs(), _named_former()) and named_costs()["MemoComp"].name == "MemoComp"
        costs.register_compound("MemoComp", {"memoNamed": 3.0}, "three", overwrite=True)
        assert named_costs()["MemoComp"] == CostFunction((("memoNamed", 3.0),))
    finally:
        del costs._REGISTRY["memoNamed"]
        costs._COMPOUNDS.pop("MemoComp", None)
        costs._COMPOUND_DESCRIPTIONS.pop("MemoComp", None)
    assert "memoNamed" not in named_costs() and "MemoComp" not in named_costs()
    assert _same(named_costs(), _named_former())
