"""The structural shortcut of ``Robot.generic_rank`` (model/rank_bound.py, issue 25): the structural bound is never
below the rank numpy's SVD counts at random configurations of random robots of three module sets; the certificate
``certainly_rank_at_least`` never claims more singular values above the tolerance than numpy's SVD counts, on many
random matrices made to be rank deficient, nearly so, badly scaled or generic; and ``generic_rank`` with the shortcut
equals the former one-by-one SVD loop and leaves the same scratch space (the shortcut deciding many of the arms)."""
import math

import numpy as np
import pytest

from robodesign.model import rank_bound
from robodesign.model.rank_bound import certainly_rank_at_least, structural_rank, structural_rank_bound

from test_fast_fail import SETS, _old_generic_rank, _outcome, _scratch, _twins
from test_fast_fail7 import _matrices, _svd_rank


def _scaled_jacobian(robot, q):
    """The TCP Jacobian straight from pinocchio, its angular rows times the reach radius (generic_rank's scaling)."""
    J = np.array(robot.jacobian(q), dtype=float).reshape(6, -1)   # (a one-joint arm's: a vector)
    J[3:] *= max(robot.reach_bound()[1], 1e-3)
    return J


@pytest.mark.parametrize("modules,seed", SETS)
def test_the_structural_bound_is_never_below_the_svd_rank(modules, seed):
    rng = np.random.default_rng(seed + 300)
    below = 0
    for robot, _ in _twins(modules, seed + 300, 60):
        bound = structural_rank_bound(robot, max(robot.reach_bound()[1], 1e-3))
        if bound is None:
            continue
        below += bound < min(6, robot.dof)
        lo = np.maximum(robot.q_lower, -math.pi)
        hi = np.minimum(robot.q_upper, math.pi)
        for _ in range(12):
            assert _svd_rank(_scaled_jacobian(robot, rng.uniform(lo, hi)), 1e-8) <= bound
    if modules == "robodesign_arm":
        assert below >= 5   # (arms whose structure alone shows a rank below six: met)


def test_certainly_rank_at_least_never_claims_more_than_the_svd_counts():
    rng = np.random.default_rng(31)
    certified = refused = 0
    for J in _matrices(rng, 3000):
        for rtol in (1e-8, 1e-10, 1e-6):
            rank = _svd_rank(J, rtol)
            for r in range(1, min(J.shape) + 1):
                if certainly_rank_at_least(J, r, rtol):
                    certified += 1
                    assert rank >= r, (J, r, rtol)
                else:
                    refused += rank < r
    assert certified > 10000 and refused > 1000
    J = rng.normal(size=(6, 4)) @ rng.normal(size=(4, 7))   # rank 4 exactly: 4 shown, 5 never
    assert certainly_rank_at_least(J, 4, 1e-8) and not certainly_rank_at_least(J, 5, 1e-8)
    for bad in (np.zeros((6, 7)), np.full((6, 7), np.nan), np.full((6, 7), np.inf), np.ones(6)):
        assert not certainly_rank_at_least(bad, 1, 1e-8)
    assert not certainly_rank_at_least(np.eye(6), 6, 1e-5) and not certainly_rank_at_least(np.eye(6), 7, 1e-8)


@pytest.mark.parametrize("modules,seed", SETS)
def test_generic_rank_with_the_structure_equals_the_former_loop(modules, seed, monkeypatch):
    """The rank and the scratch space after, with and without the shortcut, and as the former loop."""
    got, ref, decided = [], [], 0
    for new, old in _twins(modules, seed + 500, 60):
        for rtol in (1e-8, 1e-10):
            new._generic_rank = None
            got.append((_outcome(lambda: new.generic_rank(4, rtol)), _scratch(new)))
            with monkeypatch.context() as m:
                m.setattr(rank_bound, "structural_rank", lambda *a: None)
                new._generic_rank = None
                ref.append((_outcome(lambda: new.generic_rank(4, rtol)), _scratch(new)))
            assert got[-1][0] == _outcome(lambda: _old_generic_rank(old, 4, rtol)) and got[-1][1] == _scratch(old)
        lo = np.maximum(new.q_lower, -math.pi)
        J = _scaled_jacobian(new, lo + (np.minimum(new.q_upper, math.pi) - lo) * 0.5)
        decided += structural_rank(new, J, max(new.reach_bound()[1], 1e-3), 1e-8) is not None
    assert got == ref
    if modules == "robodesign_arm":
        assert decided >= 5
