"""The IK stage's small shortcuts for a candidate that fails early (issue 25, seventh round): each equals, bit for
bit, what it replaced, written out here as it was.

* ``robot._svd_values``: numpy's SVD gufunc called directly; the same singular values as
  ``np.linalg.svd(J, compute_uv=False)`` on random Jacobian-shaped matrices and stacks (full rank, rank-deficient,
  tiny and huge scales), and the same error for an input numpy rejects;
* ``GoalModel.position_lower_bound``: the boxes' corners made once per goal; the same bound as the former loop
  over the boxes on random goals (x/y/z boxes in the nominal, world and task frames, with and without a sphere)
  and random points.
"""
import math
import warnings

import numpy as np
import pinocchio as pin
import pytest

from robodesign.formats.tolerance import ToleratedPose
from robodesign.model.robot import _svd_values
from robodesign.solvers.ik import GoalModel


def _matrices(rng, n):
    """``n`` random float64 matrices or stacks shaped like TCP Jacobians (6×k, k = 1…8), some rank-deficient (a
    column repeated or zeroed), some scaled to 1e-150 or 1e150."""
    for _ in range(n):
        k = int(rng.integers(1, 9))
        stack = int(rng.integers(0, 5))
        A = rng.normal(size=(stack, 6, k) if stack else (6, k))
        if k > 1 and rng.random() < 0.3:
            A[..., 1] = A[..., 0]
        if rng.random() < 0.2:
            A[..., -1] = 0.0
        if rng.random() < 0.2:
            A *= 10.0 ** float(rng.choice([-150, -8, 8, 150]))
        yield np.ascontiguousarray(A)


def test_svd_values_equal_numpy_bit_for_bit():
    rng = np.random.default_rng(7)
    for A in _matrices(rng, 3000):
        assert _svd_values(A).tobytes() == np.linalg.svd(A, compute_uv=False).tobytes()
    assert _svd_values(np.zeros((6, 7))).tobytes() == np.linalg.svd(np.zeros((6, 7)), compute_uv=False).tobytes()


def test_svd_values_reject_a_vector_as_numpy():
    """A one-joint arm's Jacobian comes from pinocchio as a vector: numpy's error, not the gufunc's."""
    with pytest.raises(np.linalg.LinAlgError) as ours:
        _svd_values(np.ones(6))
    with pytest.raises(np.linalg.LinAlgError) as numpy_error:
        np.linalg.svd(np.ones(6), compute_uv=False)
    assert str(ours.value) == str(numpy_error.value)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_svd_values_answer_a_non_finite_input_as_numpy(bad):
    """numpy raises for a NaN and answers for an infinity: the same error, or the same values, without a warning
    of its own."""
    A = np.random.default_rng(1).normal(size=(6, 7))
    A[2, 3] = bad

    def outcome(f):
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                return f(A).tobytes(), [str(w.message) for w in caught]
        except np.linalg.LinAlgError as e:
            return "LinAlgError: " + str(e), []
    assert outcome(_svd_values) == outcome(lambda J: np.linalg.svd(J, compute_uv=False))


def _old_position_lower_bound(gm, point):
    """The former loop: the boxes' corners made at every call."""
    pd = gm.N_inv[:3, :3].dot(np.asarray(point, float)) + gm.N_inv[:3, 3]
    best = 0.0
    if math.isfinite(gm.sphere_hi):
        best = float(np.linalg.norm(pd)) - gm.sphere_hi
    for frame, d in gm.boxes.items():
        if all(n in d for n in "xyz"):
            Q = gm._Qs.get(frame)
            v = pd if Q is None else Q @ pd
            lo = np.array([d[n][0] for n in "xyz"])
            hi = np.array([d[n][1] for n in "xyz"])
            best = max(best, float(np.linalg.norm(v - np.clip(v, lo, hi))))
    return best


def _random_pose(rng):
    T = np.eye(4)
    T[:3, :3] = pin.rpy.rpyToMatrix(*rng.uniform(-math.pi, math.pi, 3))
    T[:3, 3] = rng.uniform(-1.0, 1.0, 3)
    return T


def _random_goal(rng):
    """A goal with x/y/z bounds in one to three frames (some incomplete), sometimes an r_sph and a Theta_R."""
    task_frame = _random_pose(rng)
    projections, intervals, frames = [], [], []
    for frame in rng.permutation(["nominal", "world", "task"])[:int(rng.integers(1, 4))]:
        for name in "xyz":
            if rng.random() < 0.85:
                lo = float(rng.uniform(-0.2, 0.05))
                projections.append(name)
                intervals.append((lo, lo + float(rng.uniform(0.0, 0.3))))
                frames.append(str(frame))
    for name, hi in (("r_sph", 0.3), ("Theta_R", 0.5)):
        if rng.random() < 0.4:
            projections.append(name)
            intervals.append((0.0, float(rng.uniform(0.0, hi))))
            frames.append("nominal")
    return ToleratedPose(_random_pose(rng), tuple(projections), tuple(intervals), tuple(frames),
                         frame_resolver=lambda name: task_frame)


def test_position_lower_bound_equals_the_former_loop():
    rng = np.random.default_rng(11)
    boxes = 0
    for _ in range(300):
        gm = GoalModel(_random_goal(rng))
        boxes += len(gm._position_boxes)
        for _ in range(20):
            p = rng.uniform(-1.5, 1.5, 3)
            got, want = gm.position_lower_bound(p), _old_position_lower_bound(gm, p)
            assert np.float64(got).tobytes() == np.float64(want).tobytes()
    assert boxes > 300   # most goals have at least one complete box
