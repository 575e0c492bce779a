"""CasADi/ipopt trajectory optimization on a 6-DoF IMPROV arm."""

import numpy as np
import pytest
from conftest import COBRA, IMPROV
from conftest import assert_within_limits as check_all_samples

from robodesign import Robot, load_module_set
from robodesign.solvers.timing import time_optimal_bound, time_parameterize
from robodesign.solvers.trajopt import TrajoptError, mechanical_energy, optimize_trajectory, trajopt_weights

DT = 0.01
QA = np.array([0.0, -0.5, 1.0, 0.0, 0.5, 0.0])
QB = np.array([1.2, 0.6, -0.4, 0.8, -0.6, 1.0])


@pytest.fixture(scope="module")
def arm():
    """IMPROV 1-21-4-22-5-23-12 with halved torque limits, so that torques limit the motion."""
    r = Robot.from_order(load_module_set(IMPROV), ["1", "21", "4", "22", "5", "23", "12"])
    r.tau_max = r.tau_max * 0.5
    return r


@pytest.fixture(scope="module")
def straight(arm):
    return time_parameterize(arm, np.array([QA, QB]), dt=DT)


@pytest.fixture(scope="module")
def min_time(arm, straight):
    return optimize_trajectory(arm, straight, cost="cyc", n_nodes=30, dt_out=DT)


@pytest.fixture(scope="module")
def min_energy(arm, straight):
    return optimize_trajectory(arm, straight, cost="mechEnergy", n_nodes=30, dt_out=DT)


def check_rest_to_rest(tr, qa, qb):
    np.testing.assert_array_equal(tr.q[0], qa)
    np.testing.assert_array_equal(tr.q[-1], qb)
    for k in (0, -1):
        assert np.all(tr.dq[k] == 0.0) and np.all(tr.ddq[k] == 0.0)
    np.testing.assert_allclose(np.diff(tr.t), DT, atol=1e-12)
    rq, rv = tr.consistency_residual()
    assert rq < 1e-10 and rv < 1e-10


def energy_independent(robot, tr):
    e = 0.0
    for k in range(len(tr) - 1):
        tau = robot.drivetrain_torques(tr.q[k], tr.dq[k], tr.ddq[k])[0]
        e += abs(float(tau @ tr.dq[k])) * (tr.t[k + 1] - tr.t[k])
    return e


def test_min_time_beats_toppra_and_keeps_limits(arm, straight, min_time):
    assert min_time.info["status"] == "Solve_Succeeded"
    check_rest_to_rest(min_time, QA, QB)
    worst = check_all_samples(arm, min_time)
    assert worst > 0.97  # torque-limited
    assert min_time.duration <= straight.duration + 1e-9
    assert min_time.duration >= time_optimal_bound(arm, QA, QB)
    # stays in the 0.05 rad tube around the (collision-checked) warm-start path: every output sample is
    # close to some warm-start sample (slack: half a warm-start step + quadratic sagging between nodes)
    gap = max(float(np.min(np.max(np.abs(straight.q - q), axis=1))) for q in min_time.q)
    assert gap <= 0.05 + 0.01


def test_min_energy_uses_less_energy(arm, straight, min_time, min_energy):
    check_rest_to_rest(min_energy, QA, QB)
    check_all_samples(arm, min_energy)
    e_time, e_energy = mechanical_energy(arm, min_time), mechanical_energy(arm, min_energy)
    assert e_time == pytest.approx(energy_independent(arm, min_time), rel=1e-9)
    assert e_energy == pytest.approx(energy_independent(arm, min_energy), rel=1e-9)
    assert e_energy < e_time
    assert e_energy < mechanical_energy(arm, straight)
    # without a cycle-time term the duration is the warm start's (rounded to the grid)
    assert abs(min_energy.duration - straight.duration) <= 2 * DT + 1e-9


def test_trajopt_weights():
    assert trajopt_weights("cyc") == {"cyc": 1.0}
    assert trajopt_weights("cyc_0.2,mechEnergy_0.5") == {"cyc": 0.2, "mechEnergy": 0.5}
    assert trajopt_weights({"effort": 2}) == {"effort": 2.0}
    with pytest.raises(ValueError):
        trajopt_weights("mass")
    with pytest.raises(ValueError):
        trajopt_weights("")


def test_start_at_a_joint_limit_keeps_the_limits():
    """Panda on a PTP_3 move whose start configuration (an IK solution) sits exactly at joint 1's upper
    limit: the energy-optimal motion hugs that limit. Interior nodes keep a 1 mm rad margin, so every
    output sample stays inside; without the margin ipopt's constraint tolerance lets a sample end 4e-5 rad
    beyond the limit, which the output check turns into a TrajoptError (solve then keeps TOPP-RA)."""
    from robodesign.formats.urdf import import_urdf
    ms = import_urdf(COBRA / "urdf" / "panda" / "urdf" / "panda.urdf")
    r = Robot.from_order(ms, [m.id for m in ms][:1])
    qa = np.array([1.46126, r.q_upper[1], 1.66363, -2.59881, -1.63492, 1.29217, 0.89685])
    qb = np.array([0.15835, 1.77879, 1.70154, -2.29422, -1.64564, 1.33638, -0.71902])
    warm = time_parameterize(r, np.array([qa, qb]), dt=DT)
    out = optimize_trajectory(r, warm, cost="mechEnergy,cyc_0.01", n_nodes=30, dt_out=DT)
    assert np.all(out.q >= r.q_lower) and np.all(out.q <= r.q_upper)
    assert out.q[0, 1] == r.q_upper[1] and np.allclose(out.q[-1], qb)
    assert mechanical_energy(r, out) < 0.2 * mechanical_energy(r, warm)      # 1.0 J vs 10.7 J
    with pytest.raises(TrajoptError, match="leaves the position limits"):
        optimize_trajectory(r, warm, cost="mechEnergy,cyc_0.01", n_nodes=30, dt_out=DT, limit_margin=0.0)
