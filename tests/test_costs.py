import math

import numpy as np
import pytest

from robodesign.core.errors import InputError
from robodesign.formats.costs import (
    CostContext,
    CostFunction,
    MissingQuantityError,
    known_costs,
    parse_cost,
    register_compound,
    register_cost,
)

# A tiny 3-sample, 2-joint trajectory with non-uniform time steps.
T = [0.0, 0.5, 1.5]
Q = [[0.0, 0.0], [0.1, -0.2], [0.3, -0.1]]
DQ = [[0.2, -0.4], [0.3, 0.1], [0.0, 0.0]]
TAU = [[1.0, 2.0], [3.0, -4.0], [5.0, 6.0]]
TAU_LINK = [[0.5, 1.0], [1.0, -1.0], [0.0, 0.0]]


def ctx(**kw):
    base = dict(t=T, q=Q, dq=DQ, tau=TAU, tau_link=TAU_LINK, mass=12.5, goals_achieved=2, num_goals=3)
    base.update(kw)
    return CostContext(**base)


# Hand computation:
#   power_0 = 1·0.2 + 2·(−0.4) = −0.6 → |.|·(0.5 − 0)   = 0.3
#   power_1 = 3·0.3 + (−4)·0.1 =  0.5 → |.|·(1.5 − 0.5) = 0.5      (last sample has weight 0)
MECH = 0.8
#   link: |0.5·0.2 − 1·0.4|·0.5 + |1·0.3 − 1·0.1|·1 = 0.15 + 0.2
LINK = 0.35
QDIST = 0.1 + 0.2 + 0.2 + 0.1
EFFORT = (1 + 2 + 3 + 4 + 5 + 6) * 0.5          # Σ|τ| · (t1 − t0)
CYC = 1.5


@pytest.mark.parametrize("name, value", [
    ("cyc", CYC), ("mechEnergy", MECH), ("linkMechEnergy", LINK), ("qDist", QDIST), ("effort", EFFORT),
    ("mass", 12.5), ("numJ", 2), ("fulfillN", 2), ("fulfillP", 2 / 3),
])
def test_single_terms_by_hand(name, value):
    assert parse_cost(name).evaluate(ctx()) == pytest.approx(value)


def test_compounds_by_hand():
    assert parse_cost("Liu2").evaluate(ctx()) == pytest.approx(MECH + 0.2 * CYC)       # 1.1
    assert parse_cost("Whit2").evaluate(ctx()) == pytest.approx(0.025 * 2 + 0.1 * 12.5)  # 1.3
    assert parse_cost("Liu2").name == "Liu2"
    assert parse_cost("Liu2").descriptor() == "cyc_0.2,mechEnergy"
    assert parse_cost("Whit2").descriptor() == "mass_0.1,numJ_0.025"
    assert parse_cost("Liu2_2").evaluate(ctx()) == pytest.approx(2 * (MECH + 0.2 * CYC))


def test_breakdown_sums_to_total():
    c = parse_cost("cyc_0.2,mechEnergy,qDist_2")
    b = c.breakdown(ctx())
    assert b == pytest.approx({"cyc": 0.3, "mechEnergy": MECH, "qDist": 2 * QDIST})
    assert c.evaluate(ctx()) == pytest.approx(sum(b.values()))
    assert c.raw_values(ctx()) == pytest.approx({"cyc": CYC, "mechEnergy": MECH, "qDist": QDIST})


def test_both_notations_parse_to_the_same_terms():
    a = parse_cost("cyc_0.2,mechEnergy_1")
    b = parse_cost("[(cyc|0.2),(mechEnergy|1)]")
    c = parse_cost(" [ (mechEnergy | 1) , (cyc|0.2) ] ")
    d = parse_cost("Liu2")
    assert a.terms == b.terms == c.terms == d.terms == (("cyc", 0.2), ("mechEnergy", 1.0))
    assert a == b == c == d
    assert parse_cost("[(mechEnergy)]").terms == (("mechEnergy", 1.0),)


@pytest.mark.parametrize("text", [
    "cyc", "cyc_0.2,mechEnergy", "fulfillN_-1.0", "mass_0.1,numJ_0.025", "effort_2.5,linkMechEnergy,qDist_0.001",
    "cyc_1e-07",
])
def test_descriptor_round_trip(text):
    c = parse_cost(text)
    assert parse_cost(c.descriptor()) == c
    assert parse_cost(c.paper_notation()) == c


def test_descriptor_writer_rule():
    assert parse_cost("mechEnergy_1,cyc_0.2").descriptor() == "cyc_0.2,mechEnergy"      # sorted, weight 1 dropped
    assert parse_cost("fulfillN_-1").descriptor() == "fulfillN_-1.0"                    # reference float format
    assert parse_cost("cyc_1.00001").descriptor() == "cyc_1.00001"                      # exact (issue 22, case 4)
    assert parse_cost("cyc_0.123456789").descriptor() == "cyc_0.123456789"              # full precision kept
    assert parse_cost("[(cyc|0.2),(mechEnergy|1)]").paper_notation() == "[(cyc|0.2),(mechEnergy|1)]"


def test_duplicates_are_merged_and_empty_cost():
    assert parse_cost("cyc_0.2,cyc_0.3").terms == (("cyc", 0.5),)
    for empty in ("", "  ", "[]"):
        c = parse_cost(empty)
        assert c.is_empty and c.evaluate(ctx()) == 0 and c.descriptor() == ""


def test_torques_are_lazy():
    calls = {"tau": 0, "tau_link": 0}

    def tau():
        calls["tau"] += 1
        return TAU

    def tau_link():
        calls["tau_link"] += 1
        return TAU_LINK

    c = ctx(tau=tau, tau_link=tau_link)
    assert parse_cost("cyc,qDist,mass,numJ").evaluate(c) == pytest.approx(CYC + QDIST + 12.5 + 2)
    assert calls == {"tau": 0, "tau_link": 0}
    assert parse_cost("mechEnergy_0,cyc").evaluate(c) == pytest.approx(CYC)   # weight 0: not evaluated
    assert calls["tau"] == 0
    assert parse_cost("mechEnergy,effort").evaluate(c) == pytest.approx(MECH + EFFORT)
    assert parse_cost("Liu2").evaluate(c) == pytest.approx(MECH + 0.3)
    assert calls == {"tau": 1, "tau_link": 0}                                  # computed once, cached
    assert c.is_evaluated("tau") and not c.is_evaluated("tau_link")


def test_missing_torque_is_a_clear_error():
    c = CostContext(t=T, q=Q)
    with pytest.raises(MissingQuantityError, match="drivetrain joint torques"):
        parse_cost("mechEnergy").evaluate(c)
    with pytest.raises(MissingQuantityError, match="robot mass"):
        parse_cost("mass").evaluate(c)


def test_dq_defaults_to_gradient_of_q():
    c = CostContext(t=[0, 1, 2], q=[[0.0], [1.0], [4.0]], tau=[[1.0], [1.0], [1.0]])
    assert c.get("dq")[:, 0] == pytest.approx([1.0, 2.0, 3.0])                 # numpy.gradient
    assert parse_cost("mechEnergy").evaluate(c) == pytest.approx(1.0 * 1 + 2.0 * 1)
    assert c.get("num_joints") == 1


def test_fulfill_p_without_goals_is_zero():
    assert parse_cost("fulfillP").evaluate(ctx(goals_achieved=0, num_goals=0)) == 0


@pytest.mark.parametrize("text, message", [
    ("cyc_0.2,mechEnrgy", r"unknown cost 'mechEnrgy' \(did you mean 'mechEnergy'\?\); known costs: cyc, "
                          r"mechEnergy, linkMechEnergy, qDist, effort, mass, numJ, fulfillN, fulfillP, .*Liu2, Whit2"),
    ("cyc_abc", r"weight 'abc' of cost 'cyc' is not a number"),
    ("cyc_", r"weight '' of cost 'cyc' is not a number"),
    ("cyc_nan", r"weight 'nan' of cost 'cyc' is not a number"),
    ("cyc_inf", r"weight 'inf' of cost 'cyc' is not a number"),
    ("cyc_0.2_3", r"weight '0.2_3' of cost 'cyc' is not a number"),
    ("cyc_1e400", r"weight '1e400' of cost 'cyc' must be finite"),
    ("cyc_-1", r"weight -1 of cost 'cyc' is negative: costs are minimised, so only rewards \(fulfillN, fulfillP\)"),
    ("mass,qDist_-0.5", r"weight -0.5 of cost 'qDist' is negative"),
    ("Liu2_-1", r"weight -1 of cost 'mechEnergy' is negative"),       # a compound scales its terms
    ("[(cyc|0.2),(effort|-3)]", r"weight -3 of cost 'effort' is negative"),
    ("cyc,,mass", r"empty term in cost"),
    ("[(cyc|0.2),(mass|x)]", r"weight 'x' of cost 'mass' is not a number"),
    ("[(cyc|0.2)", r"does not end with '\]'"),
    ("[cyc|0.2]", r"cannot read term 'cyc\|0.2'"),
])
def test_bad_costs_name_the_field(text, message):
    with pytest.raises(InputError, match=r"sol\.json: costFunction: .*" + message):
        parse_cost(text, file="sol.json", path="costFunction")


def test_negative_weights_only_on_rewards():
    # a reward (what the reference writes as fulfillN_-1) keeps its negative weight ...
    assert parse_cost("cyc,fulfillN_-1").evaluate(ctx(goals_achieved=3, num_goals=4)) == pytest.approx(CYC - 3)
    assert parse_cost("fulfillP_-2").evaluate(ctx(goals_achieved=3, num_goals=4)) == pytest.approx(-1.5)
    # ... every other term is minimised with a weight >= 0, also when built in Python
    with pytest.raises(InputError, match="weight -1 of cost 'cyc' is negative"):
        CostFunction((("cyc", -1.0),))
    with pytest.raises(InputError, match="negative"):
        parse_cost("mass") * -1
    with pytest.raises(ValueError, match="weight -1 of cost 'numJ' is negative"):
        register_compound("Bad", {"numJ": -1.0}, "a compound rewarding more joints")


def test_term_properties_match_what_the_terms_do():
    """needs_torques ⇔ the term fails without torques; non_negative terms are ≥ 0 on random contexts;
    trajopt ⇔ trajectory optimization accepts the term."""
    from robodesign.formats.costs import cost_terms
    from robodesign.solvers.trajopt import trajopt_weights
    rng = np.random.default_rng(0)
    builtin = ("cyc", "mechEnergy", "linkMechEnergy", "qDist", "effort", "mass", "numJ", "fulfillN", "fulfillP")
    terms = cost_terms()
    for name in builtin:
        term = terms[name]
        no_tau = ctx(tau=None, tau_link=None)
        try:
            term.fn(no_tau)
            needs = False
        except MissingQuantityError:
            needs = True
        assert term.needs_torques == needs, name
        assert parse_cost(name).needs_torques == needs
        if term.non_negative:
            for _ in range(20):
                t = np.cumsum(rng.uniform(0.01, 1, 5))
                q = rng.normal(size=(5, 3))
                c = CostContext(t=t, q=q, dq=rng.normal(size=(5, 3)), tau=rng.normal(size=(5, 3)),
                                tau_link=rng.normal(size=(5, 3)), mass=3.0, goals_achieved=1, num_goals=2)
                assert term.fn(c) >= 0, name
        try:
            trajopt_weights(name)
            ok = True
        except ValueError:
            ok = False
        assert term.trajopt == ok, name
    assert {n for n in builtin if terms[n].trajopt} == {"cyc", "mechEnergy", "effort"}
    assert {n for n in builtin if terms[n].reward} == {"fulfillN", "fulfillP"}


def test_non_string_cost():
    with pytest.raises(InputError, match=r"costFunction: expected a cost function string, got 3"):
        parse_cost(3, path=["costFunction"])


def test_register_user_cost():
    register_cost("pathLen", lambda c: float(np.sum(np.linalg.norm(np.diff(c.q, axis=0), axis=1))),
                  "joint-space path length", overwrite=True)
    c = parse_cost("pathLen_2,cyc")
    assert c.evaluate(ctx()) == pytest.approx(2 * (math.hypot(0.1, 0.2) + math.hypot(0.2, 0.1)) + CYC)
    assert "pathLen" in known_costs()
    with pytest.raises(ValueError, match="already registered"):
        register_cost("cyc", lambda c: 0.0, "dup")
    with pytest.raises(ValueError, match="invalid cost name"):
        register_cost("my_cost", lambda c: 0.0, "underscore is the weight separator")
    register_compound("Fast", {"cyc": 1.0, "pathLen": 0.5}, "cycle time plus path", overwrite=True)
    assert parse_cost("Fast").descriptor() == "cyc,pathLen_0.5"


def test_cost_function_arithmetic():
    c = parse_cost("cyc") + 0.2 * parse_cost("mechEnergy")
    assert c.descriptor() == "cyc,mechEnergy_0.2"
    with pytest.raises(InputError, match="unknown cost 'nope'"):
        CostFunction((("nope", 1.0),))


def test_copycat_weight_does_not_land_on_the_cyc_board():
    """Issue 22, case 4: cyc_0.99995 used to be written 'cyc' (4-decimal rounding) and was ranked on the cyc
    board with 0.99995·t. The descriptor now keeps the exact weight, and parses back to the same cost."""
    c = parse_cost("cyc_0.99995")
    assert c.descriptor() == "cyc_0.99995" and c.descriptor() != parse_cost("cyc").descriptor()
    assert parse_cost(c.descriptor()).weight("cyc") == 0.99995
    for w in (0.99995, 1 + 2 ** -52, 0.1 + 0.2, 1e-7, 123456.789):
        assert parse_cost(parse_cost(f"cyc_{w!r}").descriptor()).weight("cyc") == w


@pytest.mark.parametrize("text", ["cyc_1e308", "cyc,fulfillN_-1e308", "mechEnergy_2e6", "[(cyc|1e7)]"])
def test_overflowing_weights_are_refused(text):
    """Issue 22, case 5: weights that overflow a cost to ±inf are bad input, naming the term."""
    with pytest.raises(InputError, match="larger than 1e\\+06"):
        parse_cost(text, file="s.json", path=["costFunction"])
    assert parse_cost("cyc_1e6").weight("cyc") == 1e6  # the bound itself is accepted
