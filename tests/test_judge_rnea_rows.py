"""The judge's RNEA rows in one pinocchio call (model.rnea_batch.rnea_rows, link side) against pinocchio's RNEA per
row (``Robot.link_torques``, the path the judge took before): the same numbers bit for bit, on PTP_3's judged motion
and on random rows."""
import numpy as np
import pinocchio as pin
import pytest

from robodesign.judge.quantities import TrajectoryQuantities
from robodesign.model.cell import solution_robot
from robodesign.model.rnea_batch import _pool, rnea_rows


@pytest.fixture(params=["batched", "per row"])
def rows_path(request, monkeypatch):
    """Both ways: pinocchio's rneaInParallel (when built with OpenMP) and the loop of pin.rnea without it."""
    if request.param == "per row":
        monkeypatch.delattr(pin, "rneaInParallel", raising=False)
    elif not hasattr(pin, "rneaInParallel"):
        pytest.skip("pinocchio built without OpenMP")
    return request.param


def _per_row(robot, Q, V, A):
    """Robot.link_torques: pin.rnea per row on the robot's own armature-free model copy."""
    return np.array([robot.rnea(q, v, a) for q, v, a in zip(Q, V, A)]).reshape(len(Q), robot.dof)


def test_rows_equal_pinocchio_per_row_on_ptp3(ptp3_solved, rows_path):
    task, ms, sol = ptp3_solved
    robot = solution_robot(task, sol, ms)
    tq = TrajectoryQuantities.from_solution(robot, sol, task)
    before, after = tq.one_sided_accelerations
    for V, A in ((tq.dq, tq.ddq), (tq.velocities, after), (tq.velocities, before)):
        got = tq._rnea(tq.q, V, A, None)
        assert got.shape == (tq.n, robot.dof) and got.flags.c_contiguous
        assert np.array_equal(got, _per_row(robot, tq.q, V, A))
    # the judge's torques at the samples, as Robot.drivetrain_torques computes them row by row
    lb, la = tq.motion_torques
    assert np.array_equal(la, robot.drivetrain_torques(tq.q, tq.velocities, after))
    assert np.array_equal(lb, robot.drivetrain_torques(tq.q, tq.velocities, before))
    assert np.array_equal(tq.torques, robot.drivetrain_torques(tq.q, tq.dq, tq.ddq))


def test_rows_equal_pinocchio_per_row_on_random_rows(ptp3_solved, rows_path):
    task, ms, sol = ptp3_solved
    robot = solution_robot(task, sol, ms)
    rng = np.random.default_rng(7)
    n = 500
    Q = rng.uniform(-4, 4, (n, robot.dof))
    V = rng.uniform(-6, 6, (n, robot.dof)) * (rng.random((n, 1)) < 0.8)  # some rows at rest
    A = rng.uniform(-80, 80, (n, robot.dof))
    m = robot.model
    assert np.array_equal(rnea_rows(m, Q, V, A, link_side=True), _per_row(robot, Q, V, A))
    # one row, no row, and rows that overflow (the same inf / nan as pin.rnea)
    assert np.array_equal(rnea_rows(m, Q[:1], V[:1], A[:1], link_side=True), _per_row(robot, Q[:1], V[:1], A[:1]))
    assert rnea_rows(m, Q[:0], V[:0], A[:0], link_side=True).shape == (0, robot.dof)
    big = A[:3] * 1e306
    with np.errstate(over="ignore", invalid="ignore"):
        assert np.array_equal(rnea_rows(m, Q[:3], V[:3], big, link_side=True), _per_row(robot, Q[:3], V[:3], big),
                              equal_nan=True)


def test_the_pool_model_has_no_armature_and_the_robot_keeps_its_own(ptp3_solved):
    task, ms, sol = ptp3_solved
    robot = solution_robot(task, sol, ms)
    TrajectoryQuantities.from_solution(robot, sol, task).motion_torques
    armature = robot.model.armature.copy()
    assert np.any(armature != 0)
    pool = _pool(robot.model, True)   # the link side's
    assert np.all(pool.getModel(0).armature == 0)
    assert np.array_equal(robot.model.armature, armature)
