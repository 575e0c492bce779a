"""solvers/certificate_kernel.py: the compiled loops that apply the planner's pair certificates give the numpy path's
pending pairs, kept certificates and verdicts (random certificates and blocks; random IMPROV arms' segments in the
PTP_3 cell and among boxes, against coal asked about every pair; seeded)."""
from types import SimpleNamespace

import numpy as np
import pytest
from test_pair_certificates import coal_verdict, robots  # noqa: F401  (robots: the module's fixture)

from robodesign.solvers import certificate_kernel, planning
from robodesign.solvers.pair_certificates import ANCHORS, SLACK, PairCertificates

pytestmark = pytest.mark.skipif(not certificate_kernel.available(), reason="numba unavailable or ROBODESIGN_JIT=0")


@pytest.fixture(scope="module", autouse=True)
def compiled():
    assert certificate_kernel.warm_up()


def random_certificates(rng, kernel):
    """Certificates of 1–9 joints and 1–60 pairs with 0–40 made (NaN where a pair was not computed; clearances
    near and far from the slack), and a block of 0–150 rows near their anchors with a survivor mask."""
    dof, k, n = int(rng.integers(1, 10)), int(rng.integers(1, 61)), int(rng.integers(0, 151))
    certs = PairCertificates(SimpleNamespace(dof=dof), rng.random(k) < 0.7, rng.random((dof, k)) * 0.5,
                             rng.random(k) * 0.01)
    certs.kernel = kernel
    certs.count = int(rng.integers(0, 41))
    certs.anchors[:] = rng.uniform(-3, 3, certs.anchors.shape)
    certs.free[:] = np.where(rng.random(certs.free.shape) < 0.3, np.nan,
                             rng.choice([0.05, 1.0, SLACK], size=certs.free.shape) * rng.random(certs.free.shape))
    R = certs.anchors[rng.integers(0, ANCHORS, n)] + rng.normal(size=(n, dof)) * rng.choice([1e-3, 0.1, 1])
    S = rng.random((n, k)) < rng.choice([0.01, 0.1, 0.5])
    return certs, R, S


def test_pending_is_the_numpy_paths():
    """``pending`` with the kernel equals the numpy path's (and the formula over every row), S left as it was."""
    cleared = kept = 0
    for case in range(400):
        fast, R, S = random_certificates(np.random.default_rng([31, case]), certificate_kernel)
        slow, R2, S2 = random_certificates(np.random.default_rng([31, case]), None)
        S0 = S.copy()
        got, want = fast.pending(R, S), slow.pending(R2, S2)
        assert got.dtype == bool and np.array_equal(got, want)
        assert np.array_equal(S, S0)
        m = min(fast.count, ANCHORS)
        if m and len(R):
            bound = np.abs(R[:, None, :] - fast.anchors[None, :m]) @ fast.W
            formula = S & ~(fast.free[:m] - bound > SLACK).any(axis=1) | (S & ~fast.certified)
            assert np.array_equal(got, formula)
        cleared, kept = cleared + int((S & ~got).sum()), kept + int(got.sum())
    assert cleared > 1000 and kept > 1000


def test_ask_keeps_and_clears_as_the_numpy_path():
    """A block's rows asked in order (each row's pairs given random clearances, the same on both paths): the pairs
    left at each row, the block's pending mask after each ask and the kept certificates are the numpy path's."""
    made = cleared = 0
    for case in range(300):
        paths = []
        for kernel in (certificate_kernel, None):
            rng = np.random.default_rng([47, case])
            certs, R, S = random_certificates(rng, kernel)
            P = certs.pending(R, S)
            clearances = rng.choice([-0.01, SLACK / 2, 0.02, 0.3], size=P.shape) * rng.random(P.shape)
            certs._distances = lambda q, own, C=clearances, R=R: C[int(np.flatnonzero((R == q).all(axis=1))[0]), own]
            trail = []
            for j in range(len(R)):
                trail.append((certs.ask(P, R, j), P.copy()))
            paths.append((trail, certs.anchors.copy(), certs.free.copy(), certs.count, S))
        (a, anchors_a, free_a, count_a, S), (b, anchors_b, free_b, count_b, _) = paths
        assert count_a == count_b
        assert np.array_equal(anchors_a, anchors_b) and np.array_equal(free_a, free_b, equal_nan=True)
        for (left_a, P_a), (left_b, P_b) in zip(a, b):
            assert left_a == left_b and np.array_equal(P_a, P_b)
        made += count_a
        cleared += int(S.sum() - sum(len(left) for left, _ in a))
    assert made > 1000 and cleared > 1000


def test_segment_verdicts_and_certificates_with_and_without_the_kernel(robots):  # noqa: F811
    """first_invalid on random segments of random IMPROV arms (in the PTP_3 cell, among boxes): with the kernel and
    with the numpy path the same first invalid state, the same remembered verdicts (coal's, asked about every pair)
    and the same certificates made."""
    rng = np.random.default_rng(13)
    states = 0
    for robot in robots:
        memos, counts = [], []
        segments = []
        for _ in range(10):
            a = robot.random_configuration(rng)
            b = a + rng.normal(0.0, 0.6, robot.dof)
            n = int(np.ceil(np.max(np.abs(b - a)) / 0.01))
            segments.append((a + (b - a) * (np.arange(1, n + 1) / n)[:, None])[rng.permutation(n)])
        for kernel in (certificate_kernel, None):
            valid = planning._Memoized(planning._config_validator(robot), robot)
            valid.culler()
            valid.certificates.kernel = kernel
            firsts = [valid.first_invalid(Q) for Q in segments]
            memos.append((firsts, valid.memo))
            counts.append(valid.certificates.count)
        assert memos[0] == memos[1] and counts[0] == counts[1]
        for Q, first in zip(segments, memos[0][0]):
            ref = [bool(np.all(q >= robot.q_lower - 1e-9) and np.all(q <= robot.q_upper + 1e-9))
                   and not coal_verdict(robot, q) for q in Q]
            assert first == (ref.index(False) if False in ref else -1)
            states += len(Q)
    assert states > 5000


def test_a_feasible_evaluation_compiles_nothing_the_warm_up_did_not():
    """The warm-up (what ``python -m robodesign.solvers.certificate_kernel`` puts in numba's cache) covers the
    argument types a PTP_3 evaluation passes (as tests/test_kernel_warm_up.py for the other kernel modules)."""
    from test_kernel_warm_up import GOOD, SHARED

    from robodesign.design.evaluator import Evaluator, EvaluatorSpec
    from robodesign.design.problem import Problem
    from robodesign.design.search_space import Candidate
    kernels = certificate_kernel.KERNELS.cache.kernels
    warmed = {k: set(getattr(certificate_kernel, k).signatures) for k in kernels}
    problem = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
    rng = np.random.default_rng(0)
    evaluator = Evaluator(EvaluatorSpec(problem, seed=0))
    evs = [evaluator.evaluate(c) for c in [Candidate(GOOD)] + [problem.space.random_candidate(rng) for _ in range(60)]]
    assert sum(ev.stage in ("done", "timing", "check") or ev.feasible for ev in evs) >= 2   # planning ran
    assert {k: set(getattr(certificate_kernel, k).signatures) for k in kernels} == warmed
    assert all(warmed.values())


def test_a_clearance_within_the_slack_proves_nothing_since_the_lever_arms_are_never_negative(robots):  # noqa: F811
    """The kernels sum no bound for a clearance of at most SLACK, as ``f − bound ≤ f`` when W ≥ 0: W (sweep.pair_arms)
    of the random IMPROV arms and the built-in arm has no negative entry; and with such clearances only (touching
    faces at every anchor, a few far ones) ``pending`` and ``ask`` keep what the formula over every row and anchor
    keeps, on real W and states near the anchors."""
    from robodesign.model.sweep import pair_arms
    rng = np.random.default_rng(59)
    for robot in robots:
        W = pair_arms(robot)
        assert W.shape == (robot.dof, len(robot.geom_model.collisionPairs)) and (W >= 0).all()
        certs = PairCertificates(robot, np.ones(W.shape[1], bool), np.ascontiguousarray(W), np.zeros(W.shape[1]))
        certs.kernel = certificate_kernel
        certs.count = ANCHORS
        certs.anchors[:] = np.array([robot.random_configuration(rng) for _ in range(ANCHORS)])
        certs.free[:] = np.where(rng.random(certs.free.shape) < 0.9, rng.uniform(-SLACK, SLACK, certs.free.shape),
                                 rng.uniform(0.0, 0.2, certs.free.shape))
        R = certs.anchors[rng.integers(0, ANCHORS, 200)] + rng.normal(0.0, 0.01, (200, robot.dof))
        S = rng.random((200, W.shape[1])) < 0.5
        bound = np.abs(R[:, None, :] - certs.anchors[None, :]) @ W
        want = S & ~(certs.free - bound > SLACK).any(axis=1)
        assert np.array_equal(certs.pending(R, S), want) and (S & ~want).any() and want.any()
        P, j = want.copy(), 7
        own = np.flatnonzero(P[j])
        free = np.where(rng.random(len(own)) < 0.7, rng.uniform(-SLACK, SLACK, len(own)), 0.05)
        certs._distances = lambda q, own, free=free: free
        left = certs.ask(P, R, j)
        later = free - np.abs(R[j + 1:] - R[j]) @ W[:, own] > SLACK
        assert left == own[free <= SLACK].tolist()
        assert np.array_equal(P[j + 1:, own], want[j + 1:, own] & ~later)
