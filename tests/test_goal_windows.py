"""Goal-level constraints hold over exactly the goal's window (issue 13): a spike at the window's first,
middle and last sample is reported at that sample, one just outside the window is not — for every
constraint type a goal may carry. Toy robot and plan of test_checker: the leave goal L (t_g = 3.2 s,
duration 0.3 s) spans samples 320..350 of the return move R → start."""
import json

import numpy as np
import pytest

from robodesign import load_module_set
from robodesign.judge.checker import check
from robodesign.judge.quantities import TrajectoryQuantities
from robodesign.model.cell import solution_robot
from robodesign.formats.task_io import load_task

from conftest import toy_module_set
from test_checker import plan, pose, solution, task_json, tcp

K0, K1 = 320, 350
SPIKES = (K0, (K0 + K1) // 2, K1)
OUTSIDE = (K0 - 1, K1 + 1)


def padded_plan():
    """test_checker's plan followed by 0.5 s at rest, so that the window [320, 350] has samples after it."""
    t, q, dq, ddq, g2t = plan()
    n = 50
    t = np.concatenate([t, t[-1] + 0.01 * np.arange(1, n + 1)])
    q = np.vstack([q, np.repeat(q[-1:], n, axis=0)])
    dq, ddq = (np.vstack([a, np.zeros((n, a.shape[1]))]) for a in (dq, ddq))
    return t, q, dq, ddq, g2t


def goal_task(tmp_path, goal_constraint, obstacles=()):
    d = task_json(constraints=[{"type": "allGoalsFulfilled"}], obstacles=obstacles)
    for g in d["goals"]:
        if g["ID"] == "L":
            g["constraints"] = [goal_constraint]
    f = tmp_path / "toy" / "all.json"
    f.parent.mkdir(exist_ok=True)
    f.write_text(json.dumps(d))
    return load_task(f)


@pytest.fixture
def ms(tmp_path):
    return load_module_set(toy_module_set(tmp_path))


def goal_violations(task, ms, q=None, dq=None, ddq=None, kind=None):
    t, q0, dq0, ddq0, g2t = padded_plan()
    sol = solution(t, q0 if q is None else q, dq0 if dq is None else dq, ddq0 if ddq is None else ddq, g2t)
    v = check(task, sol, ms)
    return v, [x for x in v.violations if x.goal == "L" and (kind is None or x.constraint == kind)]


def test_the_window_is_samples_320_to_350(tmp_path, ms):
    task = goal_task(tmp_path, {"type": "joint", "parts": ["dq"]})
    t, q, dq, ddq, g2t = padded_plan()
    sol = solution(t, q, dq, ddq, g2t)
    tq = TrajectoryQuantities.from_solution(solution_robot(task, sol, ms), sol, task)
    assert tq.goal_windows["L"] == (K0, K1) and t[K0] == pytest.approx(3.2) and t[K1] == pytest.approx(3.5)
    v, vs = goal_violations(task, ms)
    assert v.valid and not vs


# (constraint, which array to spike, spike value for joint 0 (added), expected violation kind)
CASES = [
    ({"type": "joint", "parts": ["q"]}, "q", 4.0, "joint.q"),            # beyond the ±3.2 rad limit
    ({"type": "joint", "parts": ["dq"]}, "dq", 5.0, "joint.dq"),         # limit 2 rad/s
    ({"type": "joint", "parts": ["ddq"]}, "ddq", 50.0, "joint.ddq"),     # limit 10 rad/s²
    ({"type": "joint", "parts": ["tau"]}, "ddq", 500.0, "joint.tau"),    # > 50 Nm through the arm's inertia
    ({"type": "endEffector", "v_max": 1.0}, "dq", 5.0, "endEffector.v"),
    ({"type": "endEffector", "o_max": 1.5}, "dq", 5.0, "endEffector.o"),
    ({"type": "endEffector", "pose": {"nominal": pose(np.eye(4)), "toleranceProjection": ["Theta_R"],
                                      "tolerance": [[0, 0.3]]}}, "q", 1.0, "endEffector.pose"),
]


@pytest.mark.parametrize("constraint, array, value, kind", CASES, ids=[c[3] for c in CASES])
def test_goal_level_constraint_reads_exactly_its_window(tmp_path, ms, constraint, array, value, kind):
    task = goal_task(tmp_path, constraint)
    _, q, dq, ddq, _ = padded_plan()
    for k in SPIKES + OUTSIDE:
        arrays = {"q": q.copy(), "dq": dq.copy(), "ddq": ddq.copy()}
        arrays[array][k, 0] += value
        v, vs = goal_violations(task, ms, kind=kind, **arrays)
        if k in OUTSIDE:
            assert not vs, (k, [str(x) for x in vs])
            assert v.goals["L"] is True
        else:
            assert vs and {x.sample for x in vs} == {k}, (k, [str(x) for x in vs])
            assert v.goals["L"] is False and not v.valid
            if kind.startswith("joint."):
                assert vs[0].joint == 0 and abs(vs[0].value) > vs[0].bound


def test_goal_level_collision_free_reads_exactly_its_window(tmp_path, ms):
    """An obstacle where the arm is only at the spike configuration (q = (1.4, 0), arm almost horizontal)."""
    spike = np.array([1.4, 0.0])
    T = tcp(*spike)
    box = np.eye(4)
    box[:3, 3] = T[:3, 3] + np.array([0.0, 0.0, 0.0])
    obstacle = {"ID": "box", "collision": {"type": "box", "parameters": {"x": 0.05, "y": 0.05, "z": 0.05},
                                           "pose": pose(box)}}
    for kind, constraint in (("collisionFree", {"type": "collisionFree"}),):
        task = goal_task(tmp_path, constraint, obstacles=[obstacle])
        v, vs = goal_violations(task, ms, kind=kind)
        assert not vs and v.valid  # the plan itself never comes near the box
        for k in SPIKES + OUTSIDE:
            _, q, _, _, _ = padded_plan()
            q[k] = spike
            v, vs = goal_violations(task, ms, q=q, kind=kind)
            if k in OUTSIDE:
                assert not vs, (k, [str(x) for x in vs])
            else:
                # the window's own motion into the spike (or the spike sample itself) collides
                assert vs and {x.sample for x in vs} <= {k - 1, k} and all(K0 <= x.sample <= K1 for x in vs), \
                    (k, [str(x) for x in vs])


def test_goal_level_self_collision_free_reads_exactly_its_window(tmp_path, ms):
    """Folded back (q2 = 3.1 rad) the last link reaches down onto the base."""
    spike = np.array([0.0, 3.1])
    from robodesign.model.robot import Robot
    assert Robot.from_order(ms, ["B", "J", "J", "E"]).in_self_collision(spike)
    task = goal_task(tmp_path, {"type": "selfCollisionFree"})
    for k in SPIKES + OUTSIDE:
        _, q, _, _, _ = padded_plan()
        q[k] = spike
        v, vs = goal_violations(task, ms, q=q, kind="selfCollisionFree")
        if k in OUTSIDE:
            assert not vs, (k, [str(x) for x in vs])
        else:
            assert vs and {x.sample for x in vs} <= {k - 1, k} and all(K0 <= x.sample <= K1 for x in vs), \
                (k, [str(x) for x in vs])
