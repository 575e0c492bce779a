"""The checker: one valid and one invalid solution for every constraint and goal type, on a toy robot
whose kinematics is computed by hand (TCP = (0,0,0.15) + 0.25·u(q1) + 0.3·u(q1+q2), u(θ) = (−sin θ, 0, cos θ))."""
import copy
import json

import numpy as np
import pytest

from robodesign import load_module_set
from robodesign.judge.checker import check
from robodesign.formats.solution import Solution, SolutionTrajectory, load_solution
from robodesign.formats.task_io import load_task, parse_task

from conftest import toy_module_set

DT = 0.01


def tcp(q1, q2):
    u = lambda t: np.array([-np.sin(t), 0.0, np.cos(t)])
    p = np.array([0, 0, 0.15]) + 0.25 * u(q1) + 0.3 * u(q1 + q2)
    c, s = np.cos(-(q1 + q2)), np.sin(-(q1 + q2))
    T = np.eye(4)
    T[:3, :3] = [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    T[:3, 3] = p
    return T


def quintic(qa, qb, T):
    """Rest-to-rest quintic from qa to qb in T seconds, sampled every DT (analytic dq, ddq)."""
    n = int(round(T / DT))
    s = np.linspace(0, 1, n + 1)[:, None]
    d = np.asarray(qb) - np.asarray(qa)
    q = qa + d * (10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5)
    dq = d * (30 * s ** 2 - 60 * s ** 3 + 30 * s ** 4) / T
    ddq = d * (60 * s - 180 * s ** 2 + 120 * s ** 3) / T ** 2
    return q, dq, ddq


def hold(q, T):
    n = int(round(T / DT))
    return np.tile(q, (n + 1, 1)), np.zeros((n + 1, 2)), np.zeros((n + 1, 2))


QS = np.array([0.0, 0.0])
QA = np.array([0.5, 0.6])
QR = np.array([-0.4, 0.9])


def plan():
    """start → A (at, 1 s) → pause 0.5 s → R (reach, 1 s) → back to start (returnTo, 1 s)."""
    parts = [quintic(QS, QA, 1.0), hold(QA, 0.5), quintic(QA, QR, 1.0), quintic(QR, QS, 1.0)]
    q = [parts[0][0]]
    dq = [parts[0][1]]
    ddq = [parts[0][2]]
    for p in parts[1:]:  # share junction samples once
        q.append(p[0][1:])
        dq.append(p[1][1:])
        ddq.append(p[2][1:])
    q, dq, ddq = np.vstack(q), np.vstack(dq), np.vstack(ddq)
    t = np.arange(len(q)) * DT
    g2t = {"A": 1.0, "P": 1.5, "R": 2.5, "back": 3.5, "F": 1.0, "L": 3.2}
    return t, q, dq, ddq, g2t


def pose(T):
    return np.round(T, 12).tolist()


def task_json(extra_goals=True, constraints=None, obstacles=()):
    TA, TR = tcp(*QA), tcp(*QR)
    goals = [
        {"ID": "A", "type": "at", "goalPose": {"nominal": pose(TA), "toleranceProjection": ["x", "y", "z", "Theta_R"],
                                                "tolerance": [[-1e-3, 1e-3]] * 3 + [[0, 0.01]]}},
        {"ID": "P", "type": "pause", "duration": 0.5},
        {"ID": "R", "type": "reach", "goalPose": {"nominal": pose(TR), "toleranceProjection": ["r_sph", "Theta_R"],
                                                   "tolerance": [[0, 0.005], [0, 0.01]]}},
        {"ID": "back", "type": "returnTo"},
    ]
    if extra_goals:
        # follow the first motion (untimed: 3 poses along it), then leave the region around A
        q, _, _ = quintic(QS, QA, 1.0)
        poses = [{"nominal": pose(tcp(*q[k])), "toleranceProjection": ["r_sph"], "tolerance": [[0, 0.002]]}
                 for k in (30, 60, 100)]
        goals.append({"ID": "F", "type": "follow", "trajectory": {"pose": poses}})
        goals.append({"ID": "L", "type": "leave", "duration": 0.3,
                      "region": {"nominal": pose(TA), "toleranceProjection": ["r_sph"], "tolerance": [[0, 0.05]]}})
    if constraints is None:
        constraints = [
            {"type": "joint", "parts": ["q", "dq", "ddq", "tau"]},
            {"type": "selfCollisionFree"},
            {"type": "collisionFree", "safety_margin": 0.01},
            {"type": "allGoalsFulfilled"},
            {"type": "allGoalsFulfilledInOrder", "order": ["A", "R", "back"]},
            {"type": "endEffector", "v_max": 2.0},
            {"type": "basePlacement", "pose": {"nominal": pose(np.eye(4)), "toleranceProjection": ["x", "y", "z"],
                                               "tolerance": [[-0.1, 0.1], [-0.1, 0.1], [0, 0]]}},
        ]
    return {"header": {"ID": "toy/all", "timeStepSize": DT, "gravity": [0, 0, -9.81]},
            "obstacles": list(obstacles), "constraints": constraints, "goals": goals}


@pytest.fixture
def setup(tmp_path):
    ms = load_module_set(toy_module_set(tmp_path))
    (tmp_path / "toy").mkdir(exist_ok=True)
    f = tmp_path / "toy" / "all.json"
    f.write_text(json.dumps(task_json()))
    return ms, load_task(f), tmp_path


def solution(t, q, dq, ddq, g2t, base=np.eye(4), cost="cyc", order=("B", "J", "J", "E")):
    return Solution(task_id="toy/all", cost_function=cost, module_set="toy", module_order=order, base_pose=base,
                    trajectory=SolutionTrajectory(t, q, dq, ddq, dict(g2t)))


def kinds(verdict):
    return sorted({v.constraint for v in verdict.violations})


def test_valid_solution_and_its_costs(setup):
    ms, task, _ = setup
    t, q, dq, ddq, g2t = plan()
    v = check(task, solution(t, q, dq, ddq, g2t), ms)
    assert v.valid, [str(x) for x in v.violations]
    assert v.goals == {"A": True, "P": True, "R": True, "back": True, "F": True, "L": True}
    assert v.costs["cyc"] == pytest.approx(3.5)
    assert v.costs["numJ"] == 2 and v.costs["mass"] == pytest.approx(5.5)
    assert v.costs["Whit2"] == pytest.approx(0.025 * 2 + 0.1 * 5.5)
    # qDist: three quintic moves (monotone per joint) → Σ|Δq|
    assert v.costs["qDist"] == pytest.approx(np.abs(QA - QS).sum() + np.abs(QR - QA).sum() + np.abs(QS - QR).sum())
    assert v.cost == pytest.approx(3.5)


def _invalid(setup, mutate, expect, **kw):
    ms, task, _ = setup
    t, q, dq, ddq, g2t = plan()
    q, dq, ddq = q.copy(), dq.copy(), ddq.copy()
    base = kw.pop("base", np.eye(4))
    mutate(t, q, dq, ddq, g2t)
    v = check(task, solution(t, q, dq, ddq, g2t, base=base), ms)
    assert not v.valid
    assert expect in kinds(v), [str(x) for x in v.violations]
    return v


def test_joint_limit_crossed_at_one_sample(setup):
    def m(t, q, dq, ddq, g):
        q[40, 0] = 3.3
    v = _invalid(setup, m, "joint.q")
    jq = [x for x in v.violations if x.constraint == "joint.q"]
    assert len(jq) == 1 and jq[0].sample == 40 and jq[0].joint == 0 and jq[0].value == 3.3 and jq[0].bound == 3.2


def test_velocity_spike(setup):
    def m(t, q, dq, ddq, g):
        dq[77, 1] = 2.5  # limit 2 rad/s
    v = _invalid(setup, m, "joint.dq")
    x = [x for x in v.violations if x.constraint == "joint.dq"][0]
    assert (x.sample, x.joint, x.value, x.bound) == (77, 1, 2.5, 2.0)


def test_acceleration_limit_is_enforced(setup):
    def m(t, q, dq, ddq, g):
        ddq[120, 0] = -10.5  # limit 10 rad/s² (the reference never checks this)
    v = _invalid(setup, m, "joint.ddq")
    assert [x.sample for x in v.violations if x.constraint == "joint.ddq"] == [120]


def test_torque_limit(setup):
    # holding the arm out horizontally needs more than 50 Nm? No: 2·9.81·0.45 ≈ 8.8 Nm. A huge ddq does it.
    def m(t, q, dq, ddq, g):
        ddq[200, 0] = 4.9
    ms, task, _ = setup
    t, q, dq, ddq, g2t = plan()
    v = check(task, solution(t, q, dq, ddq, g2t), ms)
    from robodesign.model.robot import Robot
    r = Robot.from_order(ms, ["B", "J", "J", "E"])
    tau = r.drivetrain_torques(q, dq, ddq)
    assert np.abs(tau).max() < 50  # the valid plan is well inside the limit
    # scale the limit down through a module-set edit: 5 Nm < the gravity torque at QA
    d = json.loads((setup[2] / "toy" / "modules.json").read_text())
    d["modules"][1]["joints"][0]["limits"]["peakTorque"] = 5.0
    (setup[2] / "weak").mkdir()
    (setup[2] / "weak" / "modules.json").write_text(json.dumps(d))
    weak = load_module_set(setup[2] / "weak")
    v = check(task, solution(t, q, dq, ddq, g2t), weak)
    assert not v.valid and "joint.tau" in kinds(v)
    first = [x for x in v.violations if x.constraint == "joint.tau"][0]
    assert abs(first.value) == pytest.approx(abs(tau[first.sample, first.joint]), rel=1e-9) and abs(first.value) > 5


def test_goal_time_moved(setup):
    def m(t, q, dq, ddq, g):
        g["A"] = 0.8  # still moving, not yet at A
    v = _invalid(setup, m, "goal")
    assert v.goals["A"] is False and v.goals["R"] is True


def test_reach_requires_rest(setup):
    def m(t, q, dq, ddq, g):
        g["R"] = 2.49  # the pose is within 5 mm but the TCP still moves
    v = _invalid(setup, m, "goal")
    assert any("still moving" in x.message for x in v.violations)


def test_goals_out_of_order(setup):
    def m(t, q, dq, ddq, g):
        g["A"], g["R"] = 2.5, 1.0
    _invalid(setup, m, "allGoalsFulfilledInOrder")


def test_pause_broken(setup):
    def m(t, q, dq, ddq, g):
        q[130, 1] += 1e-6
    v = _invalid(setup, m, "goal")
    assert v.goals["P"] is False


def test_return_to_start_missed(setup):
    def m(t, q, dq, ddq, g):
        q[-1] += 1e-3
    v = _invalid(setup, m, "goal")
    assert v.goals["back"] is False


def test_base_pose_outside_tolerance(setup):
    base = np.eye(4)
    base[:3, 3] = [0.05, 0.0, 0.0]
    ms, task, _ = setup
    t, q, dq, ddq, g2t = plan()
    # inside the base tolerance, but then the goals move: check only the base placement verdict
    v_in = check(task, solution(t, q, dq, ddq, g2t, base=base), ms)
    assert "basePlacement" not in kinds(v_in)
    base[:3, 3] = [0.15, 0.0, 0.0]
    v_out = check(task, solution(t, q, dq, ddq, g2t, base=base), ms)
    assert "basePlacement" in kinds(v_out)


def test_end_effector_speed(setup, tmp_path):
    ms, _, _ = setup
    d = task_json()
    d["constraints"][5]["v_max"] = 0.5  # the quintic from A to R peaks at ~0.9 m/s
    f = tmp_path / "toy" / "all.json"
    f.write_text(json.dumps(d))
    t, q, dq, ddq, g2t = plan()
    v = check(load_task(f), solution(t, q, dq, ddq, g2t), ms)
    assert "endEffector.v" in kinds(v)
    x = [x for x in v.violations if x.constraint == "endEffector.v"][0]
    # independent value: |J(q) dq| linear part
    from robodesign.model.robot import Robot
    r = Robot.from_order(ms, ["B", "J", "J", "E"])
    speed = np.linalg.norm(r.jacobian(q[x.sample])[:3] @ dq[x.sample])
    assert x.value == pytest.approx(speed, rel=1e-9) and speed > 0.5


def test_obstacle_collision_at_samples_and_between_samples(setup, tmp_path):
    ms, _, _ = setup
    t, q, dq, ddq, g2t = plan()
    # a box around the TCP position at t = 0.5 s
    Tm = tcp(*q[50])
    box = {"ID": "box", "collision": {"type": "box", "parameters": {"x": 0.05, "y": 0.05, "z": 0.05},
                                      "pose": pose(np.block([[np.eye(3), Tm[:3, 3:]], [np.zeros((1, 3)), np.ones((1, 1))]]))}}
    f = tmp_path / "toy" / "all.json"
    f.write_text(json.dumps(task_json(obstacles=[box])))
    v = check(load_task(f), solution(t, q, dq, ddq, g2t), ms)
    assert "collisionFree" in kinds(v)
    # a thin plate (1 mm) that the TCP crosses *between* two samples of a coarse trajectory
    # the eef cylinder (r 2 cm) ending at the TCP jumps 0.55 m × 0.15 rad ≈ 8 cm sideways in one step
    qa, qb = np.array([0.2, 0.3]), np.array([0.35, 0.3])
    mid = tcp(*(0.5 * (qa + qb)))
    plate_pose = mid.copy()  # the plate's thin x axis is along the motion direction of the tip
    plate_pose[:3, 3] = mid[:3, 3] - 0.03 * mid[:3, 2]
    plate = {"ID": "plate", "collision": {"type": "box", "parameters": {"x": 0.001, "y": 0.02, "z": 0.02},
                                          "pose": pose(plate_pose)}}
    d = task_json(extra_goals=False, constraints=[{"type": "collisionFree"}], obstacles=[plate])
    d["goals"] = []
    f.write_text(json.dumps(d))
    task = load_task(f)
    T2 = np.array([0.0, 0.01])
    Q2 = np.vstack([qa, qb])
    DQ2 = np.tile((qb - qa) / 0.01, (2, 1))  # one motion: constant velocity from qa to qb
    sol = solution(T2, Q2, DQ2, np.zeros((2, 2)), {})
    from robodesign.model.cell import build_robot
    r = build_robot(task, ms, sol.assembly(ms), np.eye(4))
    assert not r.in_collision(qa) and not r.in_collision(qb)  # both samples are free ...
    v = check(task, sol, ms)
    assert not v.valid and "between samples 0 and 1" in v.violations[0].message  # ... the motion is not
    from robodesign.judge.checker import CheckSettings
    v_samples_only = check(task, sol, ms, CheckSettings(between_samples=False))
    assert v_samples_only.valid  # what a sample-only checker (the reference) would say


def test_self_collision(setup):
    ms, task, tmp = setup
    d = json.loads((tmp / "toy" / "all.json").read_text())
    d["goals"] = []
    d["constraints"] = [{"type": "selfCollisionFree"}]
    (tmp / "toy" / "all.json").write_text(json.dumps(d))
    task = load_task(tmp / "toy" / "all.json")
    q, dq, ddq = quintic([0, 0, 0], [0, np.pi, 0], 1.0)
    t = np.arange(len(q)) * DT
    sol = solution(t, q, dq, ddq, {}, order=("B", "J", "J", "J", "E"))
    v = check(task, sol, ms)
    assert "selfCollisionFree" in kinds(v)
    q2, dq2, ddq2 = quintic([0, 0, 0], [0, 1.0, 0], 1.0)
    assert check(task, solution(t, q2, dq2, ddq2, {}, order=("B", "J", "J", "J", "E")), ms).valid


def test_follow_and_leave(setup):
    def m(t, q, dq, ddq, g):
        g["L"] = 1.2  # the TCP is still within 5 cm of A right after the pause starts
    v = _invalid(setup, m, "goal")
    assert v.goals["L"] is False and v.goals["F"] is True

    def m2(t, q, dq, ddq, g):
        g["F"] = 0.2  # the follow poses lie later on the path
    v = _invalid(setup, m2, "goal")
    assert v.goals["F"] is False


def test_invalid_assembly_and_wrong_dof(setup):
    ms, task, _ = setup
    t, q, dq, ddq, g2t = plan()
    v = check(task, solution(t, q, dq, ddq, g2t, order=("B", "E", "J")), ms)
    assert not v.valid and kinds(v) == ["validAssembly"] and "do not connect" in v.violations[0].message
    v = check(task, solution(t, q, dq, ddq, g2t, order=("B", "J", "J", "J", "E")), ms)
    assert kinds(v) == ["trajectory"]


def test_solution_file_round_trip(setup, tmp_path):
    ms, task, _ = setup
    t, q, dq, ddq, g2t = plan()
    sol = solution(t, q, dq, ddq, g2t)
    f = sol.write(tmp_path / "sol.json")
    back = load_solution(f)
    np.testing.assert_array_equal(back.trajectory.q, q)
    assert back.trajectory.goal2time == g2t and back.module_order == ("B", "J", "J", "E")
    assert check(task, back, ms).valid
