"""Batched RNEA for the time scaling (robodesign.model.rnea_batch) against one pinocchio call per sample, and the
time scaling's users of it (the path terms of the TOPP-RA constraint, the per-sample torque check) against the
per-sample computations they replace: the same numbers, bit for bit."""
import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV, ROOT

from robodesign import Robot, load_module_set
from robodesign.core.defaults import DEFAULT_ORDER
from robodesign.core.trajectory import Trajectory
from robodesign.solvers import timing
from robodesign.model.rnea_batch import rnea_rows

PATH = np.array([[0.0, -0.5, 1.0, 0.0, 0.5, 0.0],
                 [0.6, -0.2, 0.8, 0.4, 0.2, 0.3],
                 [1.0, 0.3, 0.2, 0.6, -0.3, 0.8],
                 [0.7, 0.6, -0.4, 0.8, -0.6, 1.0]])


@pytest.fixture(scope="module")
def robots():
    imp = load_module_set(IMPROV)
    builtin = load_module_set(ROOT / "assets" / "modules" / "robodesign_arm")
    from robodesign.core.spatial import homogeneous, rpy_to_matrix
    return [Robot.from_order(imp, ["1", "21", "4", "22", "5", "23", "12"]),
            Robot.from_order(imp, ["1", "22", "5", "23", "15", "29", "101"],
                             base_pose=homogeneous(rpy_to_matrix(0.3, -0.2, 1.0), [1.0, 2.0, 0.5])),
            Robot.from_order(builtin, list(DEFAULT_ORDER))]


def test_rnea_rows_are_pinocchios_calls(robots):
    rng = np.random.default_rng(3)
    for r in robots:
        n = 97
        Q, V, A = (rng.uniform(-3, 3, (n, r.dof)) for _ in range(3))
        V[::3] = 0.0
        A[::4] = 0.0
        A[5] = -0.0
        data = r.model.createData()
        ref = np.array([pin.rnea(r.model, data, Q[k], V[k], A[k]) for k in range(n)])
        assert rnea_rows(r.model, Q, V, A).tobytes() == ref.tobytes()
        assert rnea_rows(r.model, Q[:0], V[:0], A[:0]).shape == (0, r.dof)


def _link_per_row(r, Q, V, A):
    """pinocchio's rnea per sample on an armature-free copy of the robot's model (what Robot.rnea calls)."""
    return np.array([r.rnea(Q[k], V[k], A[k]) for k in range(len(Q))]).reshape(len(Q), r.dof)


def test_link_side_is_robots_link_torques(robots):
    """rnea_rows(link_side=True), and Robot.link_torques through it, against one pinocchio call per sample on the
    robot's own armature-free copy (Robot.rnea)."""
    rng = np.random.default_rng(4)
    for r in robots:
        Q, V, A = (rng.uniform(-2, 2, (40, r.dof)) for _ in range(3))
        ref = _link_per_row(r, Q, V, A).tobytes()
        assert rnea_rows(r.model, Q, V, A, link_side=True).tobytes() == ref
        assert r.link_torques(Q, V, A).tobytes() == ref


def test_kept_pools_follow_the_models_changes(robots):
    """The pools are kept per model and made again when the model changed (base pose, gravity): the torques are
    always those of one pinocchio call per sample on the model as it is."""
    from robodesign.core.spatial import homogeneous, rpy_to_matrix
    r = robots[0]
    rng = np.random.default_rng(6)
    Q, V, A = (rng.uniform(-2, 2, (25, r.dof)) for _ in range(3))
    base = r.base_pose.copy()
    try:
        for pose, g in ((base, (0.0, 0.0, -9.81)), (homogeneous(rpy_to_matrix(0.2, 0.1, 0.3), [0.5, 0.0, 0.2]),
                                                    (0.0, 0.0, -9.81)), (base, (0.0, 1.0, -9.0)), (base, (0.0, 0.0, -9.81))):
            r.set_base_pose(pose)
            r.set_gravity(g)
            data = r.model.createData()
            ref = np.array([pin.rnea(r.model, data, Q[k], V[k], A[k]) for k in range(len(Q))])
            assert rnea_rows(r.model, Q, V, A).tobytes() == ref.tobytes()
            assert rnea_rows(r.model, Q, V, A, link_side=True).tobytes() == _link_per_row(r, Q, V, A).tobytes()
    finally:
        r.set_base_pose(base)
        r.set_gravity((0.0, 0.0, -9.81))


def _sample_torques_per_call(robot, traj):
    """sample_torques as it was: Robot.drivetrain_torques (one pinocchio call per sample) after and before."""
    after = robot.drivetrain_torques(traj.q, traj.dq, traj.ddq)
    if len(traj.t) < 2:
        return np.abs(after)
    before = robot.drivetrain_torques(traj.q, traj.dq, np.vstack([traj.ddq[:1], traj.ddq[:-1]]))
    return np.maximum(np.abs(after), np.abs(before))


def test_sample_torques_are_the_per_sample_ones(robots):
    r = robots[0]
    tr = timing.time_parameterize(r, PATH, dt=0.01)
    assert timing.sample_torques(r, tr).tobytes() == _sample_torques_per_call(r, tr).tobytes()
    one = Trajectory.at_rest(PATH[0])
    assert timing.sample_torques(r, one).tobytes() == _sample_torques_per_call(r, one).tobytes()


def test_path_terms_are_the_per_point_ones(robots):
    """The TOPP-RA constraint's RNEA terms along a blended path (with blends: left and right limits of q'' differ
    at their boundaries), against one pinocchio call per grid point and term as before."""
    for r in robots:
        path = timing.BlendedPolyline(PATH[:, :r.dof] if r.dof <= 6 else np.hstack([PATH, PATH])[:, :r.dof], 0.05)
        grid = path.gridpoints(0.02)
        tm = timing._PathTerms(r, path, grid, True)
        q, qs, qr, ql = path(grid, 0), path(grid, 1), path(grid, 2), path.eval_left(grid, 2)
        assert np.any(ql != qr)
        data, zero = r.model.createData(), np.zeros(r.dof)
        for i in range(len(grid)):
            g = pin.rnea(r.model, data, q[i], zero, zero).copy()
            assert tm.g[i].tobytes() == g.tobytes()
            assert tm.a[i].tobytes() == (pin.rnea(r.model, data, q[i], zero, qs[i]) - g).tobytes()
            br = pin.rnea(r.model, data, q[i], qs[i], qr[i]) - g
            assert tm.bR[i].tobytes() == br.tobytes()
            bl = br if np.all(ql[i] == qr[i]) else pin.rnea(r.model, data, q[i], qs[i], ql[i]) - g
            assert tm.bL[i].tobytes() == bl.tobytes()


def test_each_pool_is_made_at_its_first_ask_from_the_kept_copy(robots):
    """The two pools of a model are made one at a time, in either order, from the copy kept when the model was first
    seen: whichever side is asked first, later, or again after the model changed, the torques are pinocchio's calls
    per sample on the model as it is (with and without armature), bit for bit; a side never asked has no pool."""
    from robodesign.core.spatial import homogeneous, rpy_to_matrix
    from robodesign.model import rnea_batch
    rng = np.random.default_rng(11)
    for first in (True, False):
        for r0 in robots:
            r = Robot(r0.module_set, r0.assembly, base_pose=r0.base_pose)   # (a model not seen before)
            Q, V, A = (rng.uniform(-2.5, 2.5, (30, r.dof)) for _ in range(3))
            rnea_batch._POOLS.pop(id(r.model), None)   # (an earlier model's entry at the same id)
            data = r.model.createData()
            ref = {False: np.array([pin.rnea(r.model, data, Q[k], V[k], A[k]) for k in range(len(Q))]).tobytes(),
                   True: _link_per_row(r, Q, V, A).tobytes()}
            assert rnea_rows(r.model, Q, V, A, link_side=first).tobytes() == ref[first]
            assert rnea_batch._POOLS[id(r.model)][1 if first else 2] is None   # the other side: not made
            for side in (not first, first, not first):
                assert rnea_rows(r.model, Q, V, A, link_side=side).tobytes() == ref[side]
            base = r.base_pose.copy()
            try:   # a changed model: a new copy, no pool until asked
                r.set_base_pose(homogeneous(rpy_to_matrix(0.1, 0.2, -0.4), [0.3, -0.2, 0.1]))
                data = r.model.createData()
                moved = np.array([pin.rnea(r.model, data, Q[k], V[k], A[k]) for k in range(len(Q))]).tobytes()
                assert rnea_rows(r.model, Q, V, A, link_side=True).tobytes() == _link_per_row(r, Q, V, A).tobytes()
                assert rnea_batch._POOLS[id(r.model)][1] is None
                assert rnea_rows(r.model, Q, V, A).tobytes() == moved
            finally:
                r.set_base_pose(base)
