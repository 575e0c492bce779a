"""Batched IK: its vectorised kinematics equals pinocchio; its solutions lie inside the tolerance."""
import numpy as np
import pytest

from robodesign import Assembly, Robot, load_module_set
from robodesign.checker import build_robot
from robodesign.solvers.batch_ik import ChainKinematics, batch_ik, rotation_weights
from robodesign.task_io import load_task

from conftest import IMPROV, PRIMITIVES, TASKS


@pytest.mark.parametrize("folder,order", [(IMPROV, ["1", "21", "4", "22", "5", "23", "12"]),
                                          (PRIMITIVES, ["base", "J2", "i_30", "J1", "l_15", "J2", "eef"])])
def test_chain_kinematics_equals_pinocchio(folder, order):
    ms = load_module_set(folder)
    r = Robot.from_order(ms, order)
    B = np.eye(4)
    B[:3, :3] = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])
    B[:3, 3] = [0.3, -0.2, 0.1]
    r.set_base_pose(B)
    ck = ChainKinematics(r)
    Q = np.random.default_rng(0).uniform(-1.5, 1.5, (7, r.dof))
    Q = np.clip(Q, r.q_lower, r.q_upper)
    T, J = ck.fk_jac(Q)
    for i in range(len(Q)):
        np.testing.assert_allclose(T[i], r.fk(Q[i]), atol=1e-12)
        np.testing.assert_allclose(J[i], r.jacobian(Q[i]), atol=1e-12)


def test_batch_ik_solutions_are_valid_and_deterministic():
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    r = build_robot(task, ms, Assembly.from_order(ms, ["1", "21", "4", "22", "5", "23", "12"]), np.eye(4))
    g = task.goals[1].pose
    res = batch_ik(r, g, np.random.default_rng(3), n_seeds=64, n_solutions=3)
    assert res.solutions
    for q in res.solutions:
        T = r.fk(q)
        # independent check of the PTP_3 tolerance: r_sph ≤ 1 cm, rotation angle ≤ 0.01 rad
        assert np.linalg.norm(T[:3, 3] - g.nominal[:3, 3]) <= 0.01
        c = (np.trace(g.nominal[:3, :3].T @ T[:3, :3]) - 1) / 2
        assert np.arccos(np.clip(c, -1, 1)) <= 0.01
        assert np.all(q >= r.q_lower) and np.all(q <= r.q_upper) and not r.in_collision(q)
    again = batch_ik(r, g, np.random.default_rng(3), n_seeds=64, n_solutions=3)
    assert all(np.array_equal(a, b) for a, b in zip(res.solutions, again.solutions))
    # a pose 5 m away: nothing converges, nothing is returned
    from robodesign.tolerance import ToleratedPose
    far = ToleratedPose(nominal=np.array([[1, 0, 0, 5.0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]),
                        projections=("r_sph",), intervals=((0.0, 0.01),))
    assert not batch_ik(r, far, np.random.default_rng(0), n_seeds=32)


def test_rotation_weights_follow_the_tolerance():
    from robodesign.tolerance import ToleratedPose
    E = np.eye(4)
    assert list(rotation_weights(ToleratedPose(E, ("x", "N_x", "N_y"), ((-1, 1), (-0.1, 0.1), (-0.1, 0.1))))) == [1, 1, 0]
    assert list(rotation_weights(ToleratedPose(E, ("r_sph", "Theta_R"), ((0, 0.1), (0, 0.1))))) == [1, 1, 1]
    assert list(rotation_weights(ToleratedPose(E, ("r_sph",), ((0, 0.1),)))) == [0, 0, 0]
