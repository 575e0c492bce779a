"""model/pair_clearance.py's proof (issue 25): its distances and verdicts equal the plain form's. Against a copy of the
plain form (a new ``coal.Transform3s`` per row; every cell of a round asked before the round is judged) on the self
pairs of random IMPROV and primitive-module arms at several limits."""
import coal
import numpy as np
import pytest
from conftest import IMPROV, PRIMITIVES

from robodesign.formats.assembly import random_serial_order
from robodesign.formats.module_io import load_module_set
from robodesign.model import pair_clearance
from robodesign.model.collision_cull import SLACK
from robodesign.model.robot import Robot


def plain_distances(shape_a, shape_b, Pb, links, angles):
    """coal's distance of a (at the identity) and b (at ``Pb`` in the last chain joint's frame) at every row of chain
    ``angles``: a new transform, request and result per row."""
    out = []
    for P in pair_clearance.chain_poses(links, angles) @ Pb:
        out.append(coal.distance(shape_a, coal.Transform3s(np.eye(3), np.zeros(3)), shape_b,
                                 coal.Transform3s(P[:3, :3].copy(), P[:3, 3].copy()),
                                 coal.DistanceRequest(), coal.DistanceResult()))
    return np.array(out)


def plain_clears(distance, arms, limit, budget=pair_clearance.BUDGET):
    """The proof's plain form: every cell of a round asked, then the round judged (``distance``: rows → all
    distances)."""
    k = len(arms)
    h = np.pi / pair_clearance.START
    axes = [-np.pi + h * (2 * np.arange(pair_clearance.START) + 1)] * k
    C = np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=1).reshape(-1, k)
    HW = np.full(C.shape, h)
    asked = 0
    while len(C):
        if asked + len(C) > budget:
            return False
        d = distance(C)
        asked += len(C)
        if (d <= limit).any():
            return False
        terms = HW * arms
        keep = d - terms.sum(axis=1) <= limit
        C, HW, terms = C[keep], HW[keep], terms[keep]
        m = np.argmax(terms, axis=1)
        rows = np.arange(len(C))
        HW = HW.copy()
        HW[rows, m] *= 0.5
        lo, hi = C.copy(), C.copy()
        lo[rows, m] -= HW[rows, m]
        hi[rows, m] += HW[rows, m]
        C, HW = np.vstack([lo, hi]), np.vstack([HW, HW])
    return True


def chained_pairs(seed, n):
    """(shape a, shape b, Pb, links) of every self pair with a chain of ``n`` random arms of each module set, seen
    from a (:func:`pair_clearance.in_a_frame`)."""
    rng = np.random.default_rng(seed)
    out = []
    for path, dofs in ((IMPROV, (6, 7)), (PRIMITIVES, (3, 8))):
        ms = load_module_set(path)
        for _ in range(n):
            robot = Robot.from_order(ms, random_serial_order(ms, rng, dof=int(rng.integers(*dofs))))
            objs = robot.geom_model.geometryObjects
            for cp in robot.geom_model.collisionPairs:
                if cp.second >= robot.n_collision_geometries:
                    continue
                a, b = objs[cp.first], objs[cp.second]
                links = pair_clearance.chain(robot.model, a.parentJoint, b.parentJoint)
                if links is None:
                    a, b = b, a
                    links = pair_clearance.chain(robot.model, a.parentJoint, b.parentJoint)
                if links is not None and type(b.geometry).__name__ != "BVHModelOBBRSS":
                    f_links, Pb = pair_clearance.in_a_frame(np.array(a.placement.homogeneous), links,
                                                            np.array(b.placement.homogeneous))
                    out.append((a.geometry, b.geometry, Pb, f_links))
    return out


def test_distances_are_the_plain_ones_up_to_the_first_below_the_stop():
    """The distances at random chain angles are the plain form's bit for bit; with a stop, the same ones up to and
    including the first not above it."""
    rng = np.random.default_rng(7)
    stopped = 0
    for a, b, Pb, links in chained_pairs(11, 2):
        angles = rng.uniform(-np.pi, np.pi, (20, len(links)))
        plain = plain_distances(a, b, Pb, links, angles)
        fast = pair_clearance._PairDistance(a, np.eye(4), b, Pb, links)
        assert np.array_equal(fast(angles), plain)
        stop = float(np.median(plain))
        first = int(np.argmax(plain <= stop))
        assert np.array_equal(fast(angles, stop), plain[:first + 1])
        stopped += first + 1 < len(plain)
    assert stopped > 20


@pytest.mark.parametrize("margin", [0.0, 0.01, 0.05])
def test_verdicts_are_the_plain_forms(margin):
    """The proof's verdict is the plain form's on every chained self pair of random arms, at every limit tried."""
    verdicts = []
    for a, b, Pb, links in chained_pairs(12, 2):
        arms = pair_clearance.chain_arms(links, (a, np.eye(4)), (b, Pb))
        limit = margin + SLACK + pair_clearance.ALLOWANCE
        fast = pair_clearance.chain_clears(pair_clearance._PairDistance(a, np.eye(4), b, Pb, links), arms, limit)
        plain = plain_clears(lambda C: plain_distances(a, b, Pb, links, C), arms, limit)
        assert fast == plain
        verdicts.append(fast)
    assert 10 < sum(verdicts) < len(verdicts) - 10


def plain_chain_poses(links, angles):
    """``chain_poses``'s plain form: each rotation on an identity stack made by broadcasting ``np.eye(4)``."""
    n = len(angles)
    T = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
    for (M, axis), a in zip(links, angles.T):
        x, y, z = axis
        K = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
        X = np.broadcast_to(np.eye(4), (n, 4, 4)).copy()
        X[:, :3, :3] += np.sin(a)[:, None, None] * K + (1.0 - np.cos(a))[:, None, None] * (K @ K)
        T = T @ M @ X
    return T


def test_chain_poses_are_the_plain_forms_bit_for_bit():
    """``chain_poses`` of random chains (1–3 joints, random axes and placements) at random angles equals the plain
    form's bit for bit."""
    rng = np.random.default_rng(8)
    for _ in range(200):
        links = []
        for _ in range(int(rng.integers(1, 4))):
            M = np.eye(4)
            M[:3, :3] = np.linalg.qr(rng.normal(size=(3, 3)))[0]
            M[:3, 3] = rng.normal(size=3)
            axis = rng.normal(size=3)
            links.append((M, axis / np.linalg.norm(axis)))
        angles = rng.uniform(-np.pi, np.pi, (int(rng.integers(1, 300)), len(links)))
        assert np.array_equal(pair_clearance.chain_poses(links, angles), plain_chain_poses(links, angles))
