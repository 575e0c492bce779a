"""The planner's test whether a move goes nowhere (``goal_planner._same_configuration``) is ``np.allclose(a, b,
atol=1e-12)`` (issue 25, round 9): the same verdict on random pairs near and far from its tolerance, with
infinities, NaN and zeros of both signs."""
import numpy as np

from robodesign.design.goal_planner import _same_configuration


def test_the_verdicts_are_allcloses():
    rng = np.random.default_rng(4)
    seen = {True: 0, False: 0}
    for _ in range(8000):
        dof = int(rng.integers(1, 9))
        b = rng.normal(0.0, 10.0 ** rng.uniform(-14, 3), dof)
        tol = 1e-12 + 1e-05 * np.abs(b)
        a = b + tol * rng.choice([0.0, 0.5, 1.0, 1.0 - 1e-15, 1.0 + 1e-15, 2.0, -1.0, -2.0], dof)
        for x in (a, b):
            u = rng.uniform(size=dof)
            x[u < 0.02] = np.inf
            x[(u >= 0.02) & (u < 0.04)] = -np.inf
            x[(u >= 0.04) & (u < 0.06)] = np.nan
            x[(u >= 0.06) & (u < 0.08)] = rng.choice([0.0, -0.0])
        with np.errstate(invalid="ignore"):
            want = bool(np.allclose(a, b, atol=1e-12))
        assert _same_configuration(a, b) is want
        seen[want] += 1
    assert seen[True] > 500 and seen[False] > 3000


def test_other_shapes_take_numpys_answer():
    """Arrays that are not two vectors of one length get np.allclose's own answer (broadcast)."""
    a, b = np.zeros((2, 3)), np.zeros(3)
    assert _same_configuration(a, b) is True
    assert _same_configuration(np.zeros(3), np.array([0.0])) is True
    assert _same_configuration(np.ones(3), np.array([0.0])) is False
