"""The cheap paths of a candidate that fails early (issue 25): each equals, bit for bit, the formula it replaced,
written out here as it was, on many random robots of three module sets at random base poses.

* ``Robot.generic_rank``: configurations from cached standard uniforms, the Jacobians after the first in one SVD
  call; the same rank for every ``samples`` and ``rtol`` tried, and the scratch space (``data``) left as the
  one-by-one loop left it;
* ``Robot.reach_bound`` and ``Robot.tcp_chain``: the chain from the walk, norms as ``t.dot(t)``; the same point
  and radius bit for bit, the same chain as pinocchio's parents give. The bound no longer runs forward kinematics
  on the scratch space (tests/test_fast_fail9.py), so what is checked after it is that the scratch space's next
  answers (forward kinematics, the Jacobian) are the same.
"""
import math

import numpy as np
import pinocchio as pin
import pytest

from robodesign import Assembly, Robot, load_module_set
from robodesign.core.errors import AssemblyError
from robodesign.formats.assembly import random_serial_order
from robodesign.model import robot as robot_module

from conftest import IMPROV, PRIMITIVES


def _old_tcp_chain(robot):
    m, chain = robot.model, []
    j = m.frames[robot.tcp_frame].parentJoint
    while j > 0:
        chain.append(j)
        j = m.parents[j]
    return chain[::-1]


def _old_reach_bound(robot):
    m, d = robot.model, robot.data
    chain = _old_tcp_chain(robot)
    pin.forwardKinematics(m, d, pin.neutral(m))
    if not chain:
        return pin.updateFramePlacement(m, d, robot.tcp_frame).translation.copy(), 0.0
    o = d.oMi[chain[0]].translation.copy()
    R = sum(float(np.linalg.norm(m.jointPlacements[b].translation)) for b in chain[1:])
    R += float(np.linalg.norm(m.frames[robot.tcp_frame].placement.translation))
    for j in chain:
        if m.joints[j].shortname().startswith("JointModelP"):
            idx = m.joints[j].idx_q
            lo, hi = m.lowerPositionLimit[idx], m.upperPositionLimit[idx]
            R += max(abs(lo), abs(hi)) if np.isfinite(lo) and np.isfinite(hi) else math.inf
    return o, R


def _old_generic_rank(robot, samples=4, rtol=1e-8):
    rng = np.random.default_rng(0)
    lo = np.maximum(np.asarray(robot.q_lower, float), -math.pi)
    hi = np.minimum(np.asarray(robot.q_upper, float), math.pi)
    scale = max(_old_reach_bound(robot)[1], 1e-3)
    best = 0
    for _ in range(max(1, samples)):
        J = np.array(robot.jacobian(rng.uniform(lo, hi)), dtype=float)
        J[3:] *= scale
        s = np.linalg.svd(J, compute_uv=False) if J.size else np.zeros(0)
        best = max(best, int(np.sum(s > rtol * s[0])) if s.size and s[0] > 0 else 0)
        if best >= min(J.shape):
            break
    return best


def _random_pose(rng):
    T = np.eye(4)
    T[:3, :3] = pin.rpy.rpyToMatrix(*rng.uniform(-math.pi, math.pi, 3))
    T[:3, 3] = rng.uniform(-1.0, 1.0, 3)
    return T


def _twins(modules, seed, n):
    """``n`` pairs of robots built alike (random orders with 1–7 joints where the set has them, random base
    poses)."""
    ms = load_module_set(modules)
    rng = np.random.default_rng(seed)
    made = 0
    while made < n:
        try:
            asm = Assembly.from_order(ms, random_serial_order(ms, rng, dof=int(rng.integers(1, 8))))
        except AssemblyError:
            continue
        made += 1
        T = _random_pose(rng)
        yield Robot(ms, asm, base_pose=T), Robot(ms, asm, base_pose=T)


def _scratch(robot):
    """The scratch space's joint and TCP poses, as bytes."""
    d = robot.data
    return [M.homogeneous.tobytes() for M in d.oMi] + [d.oMf[robot.tcp_frame].homogeneous.tobytes()]


SETS = [("robodesign_arm", 1), (IMPROV, 2), (PRIMITIVES, 3)]


@pytest.mark.parametrize("modules,seed", SETS)
def test_reach_bound_and_chain_equal_the_former_formula(modules, seed):
    """Point and radius bit for bit, the same chain, the same answers of the scratch space after, then at another base
    pose."""
    rng = np.random.default_rng(seed + 100)
    for new, old in _twins(modules, seed, 60):
        for _ in range(2):
            assert new.tcp_chain() == _old_tcp_chain(old)
            o, R = new.reach_bound()
            o_old, R_old = _old_reach_bound(old)
            assert o.tobytes() == o_old.tobytes() and np.float64(R).tobytes() == np.float64(R_old).tobytes()
            q = rng.uniform(-math.pi, math.pi, new.dof)
            assert new.fk(q).tobytes() == old.fk(q).tobytes()
            assert new.jacobian(q).tobytes() == old.jacobian(q).tobytes()
            assert _scratch(new) == _scratch(old)
            T = _random_pose(rng)
            new.set_base_pose(T)
            old.set_base_pose(T)


@pytest.mark.parametrize("modules,seed", SETS)
def test_generic_rank_equals_the_one_by_one_loop(modules, seed):
    """The same rank and scratch space for several sample counts and tolerances (large tolerances make ranks that
    differ between samples, so the loop stops at the second or third sample or never)."""
    ranks = set()
    for new, old in _twins(modules, seed, 40):
        for samples in (1, 2, 4, 6):
            for rtol in (1e-8, 1e-2, 0.1, 0.3, 0.6):
                new._generic_rank = None
                got = _outcome(lambda: new.generic_rank(samples, rtol))
                assert got == _outcome(lambda: _old_generic_rank(old, samples, rtol))
                assert _scratch(new) == _scratch(old)
                ranks.add(got)
    assert len(ranks) >= 5   # (with the error of a one-joint arm: pinocchio gives its Jacobian as a vector)


def _outcome(f):
    """f's value, or the type and message of what it raised."""
    try:
        return f()
    except Exception as e:   # noqa: BLE001 - compared, not handled
        return (type(e), str(e))


def test_rank_samples_are_the_generators_draws():
    """``_rank_samples`` rows equal ``default_rng(0).uniform(lo, hi)`` called once per row, bit for bit."""
    rng = np.random.default_rng(7)
    for _ in range(2000):
        n = int(rng.integers(0, 9))
        lo = rng.uniform(-4.0, 1.0, n)
        hi = lo + rng.uniform(0.0, 7.0, n)
        g = np.random.default_rng(0)
        samples = int(rng.integers(1, 7))
        want = np.array([g.uniform(lo, hi) for _ in range(samples)]).reshape(samples, n)
        assert robot_module._rank_samples(lo, hi, samples).tobytes() == want.tobytes()


def test_norm_is_numpys():
    """``vector_norm`` equals ``float(np.linalg.norm(t))`` bit for bit (contiguous and strided vectors, zeros, large)."""
    rng = np.random.default_rng(3)
    for k in range(3000):
        T = rng.normal(size=(4, 4)) * 10.0 ** rng.integers(-8, 8)
        t = T[:3, 3] if k % 2 else T[:3, 3].copy()
        if k % 7 == 0:
            t = np.zeros(3)
        assert np.float64(robot_module.vector_norm(t)).tobytes() == np.float64(float(np.linalg.norm(t))).tobytes()


def test_rank_counts_as_numpy():
    """``_rank`` equals ``int(np.sum(s > rtol * s[0]))`` (0 without values or a largest one not above 0), on
    random, tied, zero, negative and NaN values."""
    rng = np.random.default_rng(5)
    for k in range(5000):
        s = np.sort(rng.uniform(0.0, 1.0, int(rng.integers(0, 8))) * 10.0 ** rng.integers(-6, 6))[::-1]
        if k % 5 == 0 and s.size:
            s[rng.integers(s.size)] = [0.0, np.nan, -1.0, s[0] * 1e-8][k % 4]
        rtol = [1e-8, 0.5, 1.0, 0.0][k % 4]
        want = int(np.sum(s > rtol * s[0])) if s.size and s[0] > 0 else 0
        assert robot_module._rank(s, rtol) == want


def _old_chain_bounds(robot):
    """(c_tcp, circle, R1, R2) as ChainBounds computed them before (None where it stopped early)."""
    from robodesign.solvers.ik import _REVOLUTE_AXES
    m, chain = robot.model, _old_tcp_chain(robot)
    fr = m.frames[robot.tcp_frame]
    c_tcp = np.asarray(fr.placement.rotation, float).T @ np.asarray(fr.placement.translation, float)
    R = _old_reach_bound(robot)[1]
    if len(chain) < 2 or not math.isfinite(R):
        return c_tcp, None, None, None
    j1, j2 = chain[0], chain[1]
    jm = m.joints[j1]
    name = jm.shortname()
    if name in _REVOLUTE_AXES:
        ax = np.array(_REVOLUTE_AXES[name])
    elif name == "JointModelRevoluteUnaligned":
        ax = np.asarray(jm.extract().axis if hasattr(jm, "extract") else jm.axis, float)
    else:
        return c_tcp, None, None, None
    F1 = m.jointPlacements[j1]
    if m.parents[j1] != 0 or m.parents[j2] != j1:
        return c_tcp, None, None, None
    R1, p1 = np.asarray(F1.rotation, float), np.asarray(F1.translation, float)
    t2 = np.asarray(m.jointPlacements[j2].translation, float)
    along = float(ax @ t2)
    circle = (p1 + R1 @ (ax * along), R1 @ ax / np.linalg.norm(ax), float(np.linalg.norm(t2 - ax * along)))
    r1 = R - float(np.linalg.norm(t2))
    return c_tcp, circle, r1, r1 - float(np.linalg.norm(fr.placement.translation))


def _bits(x):
    """Everything in ``x`` (arrays, floats, tuples, None) as bytes."""
    if x is None:
        return b"none"
    if isinstance(x, tuple):
        return b"|".join(_bits(v) for v in x)
    return np.asarray(x, dtype=float).tobytes()


@pytest.mark.parametrize("modules,seed", SETS)
def test_chain_bounds_equal_the_former_formula(modules, seed):
    """ChainBounds' TCP offset, circle and radii bit for bit, at two base poses per robot (some robots have a
    revolute first joint, some a prismatic one, some one joint only)."""
    from robodesign.solvers.ik import ChainBounds
    rng = np.random.default_rng(seed + 200)
    circles = 0
    for robot, _ in _twins(modules, seed, 60):
        for _ in range(2):
            cb = ChainBounds(robot)
            got = (cb.c_tcp, cb.circle, getattr(cb, "R1", None), getattr(cb, "R2", None))
            want = _old_chain_bounds(robot)
            assert _bits(got) == _bits(want)
            circles += cb.circle is not None
            robot.set_base_pose(_random_pose(rng))
    assert circles >= 20


def test_lazy_generator_draws_as_the_generator_made_at_once():
    """The IK stage's LazyGenerator and ``np.random.default_rng(seed)``: the same draws through every way the
    pipeline uses it (its own methods, ``solve_ik``'s generator, ``Robot.random_configuration``), interleaved,
    for the evaluator's seeds; ``solve_ik`` on a robot gives the same solutions and statistics with either."""
    from robodesign.design.evaluator import candidate_seed
    from robodesign.solvers.ik import _as_rng, solve_ik
    from robodesign.solvers.lazy_rng import LazyGenerator
    for k in range(200):
        seed = candidate_seed(k % 3, f"c{k}")
        lazy, eager = LazyGenerator(seed), np.random.default_rng(seed)
        assert _as_rng(lazy) is _as_rng(lazy)
        for step in range(6):
            a = [lazy.integers(2 ** 31), lazy.uniform(-1.0, 1.0, 3), _as_rng(lazy).random(4), lazy.normal(size=2)]
            b = [eager.integers(2 ** 31), eager.uniform(-1.0, 1.0, 3), eager.random(4), eager.normal(size=2)]
            assert _bits(tuple(np.asarray(x, dtype=float) for x in a)) == _bits(tuple(np.asarray(x, dtype=float) for x in b))
        assert lazy.bit_generator.state == eager.bit_generator.state
    ms = load_module_set(IMPROV)
    robot = Robot.from_order(ms, ["1", "21", "4", "22", "5", "23", "12"])
    from robodesign.formats.tolerance import ToleratedPose
    goal = ToleratedPose(robot.fk(robot.random_configuration(np.random.default_rng(1))))
    for seed in (3, 4):
        lazy, eager = LazyGenerator(seed), np.random.default_rng(seed)
        q_lazy, q_eager = robot.random_configuration(lazy), robot.random_configuration(eager)
        assert q_lazy.tobytes() == q_eager.tobytes()
        r1, r2 = solve_ik(robot, goal, lazy, max_restarts=20, n_solutions=3), solve_ik(robot, goal, eager, max_restarts=20,
                                                                                       n_solutions=3)
        assert [q.tobytes() for q in r1.solutions] == [q.tobytes() for q in r2.solutions] and r1.solutions
        assert lazy.bit_generator.state == eager.bit_generator.state


def test_lazy_generator_copies_and_pickles():
    """A copy, a deep copy and a pickled LazyGenerator, made before and after its first draw, go on drawing what
    the original would (a deep copy or a pickle has its own generator; a copy made after a draw shares it)."""
    import copy
    import pickle
    from robodesign.solvers.lazy_rng import LazyGenerator
    for drawn in (False, True):
        lazy = LazyGenerator(11)
        if drawn:
            lazy.random(3)
        for twin in (copy.deepcopy(lazy), pickle.loads(pickle.dumps(lazy))):
            assert isinstance(twin, LazyGenerator)
            assert twin.random(5).tobytes() == copy.deepcopy(lazy).random(5).tobytes()
        shallow = copy.copy(lazy)
        assert isinstance(shallow, LazyGenerator) and shallow.integers(1000) >= 0
    with pytest.raises(AttributeError):
        LazyGenerator(1)._missing
