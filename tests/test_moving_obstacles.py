"""Planning among moving obstacles: waiting for a moving part, certified with the checker's semantics."""
import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from robodesign import load_module_set
from robodesign.model.cell import build_robot
from robodesign.judge.checker import check
from robodesign.design.solve import solve
from robodesign.solvers.schedule import ScheduleError, check_hold, find_wait
from robodesign.formats.task_io import load_task

import make_tasks as mt  # assets/tasks, on the path by conftest

ORDER = list(mt.DEFAULT_ORDER)


@pytest.fixture(scope="module")
def ms():
    return load_module_set("robodesign_arm")


# ---------------------------------------------------------------------------------------------------------
# find_wait on a hand-made collider
# ---------------------------------------------------------------------------------------------------------
class Window:
    """Blocks every sample with q[0] > 0.5 whose time lies in [t0, t1); optionally hits q == rest at t_hit."""

    def __init__(self, t0, t1, t_hit=None):
        self.t0, self.t1, self.t_hit = t0, t1, t_hit
        self.settles_at = t1

    def first_collision(self, t, Q):
        for k, (tk, q) in enumerate(zip(t, Q)):
            if q[0] > 0.5 and self.t0 <= tk + 1e-12 < self.t1:
                return k, "window"
            if self.t_hit is not None and abs(tk - self.t_hit) < 1e-9:
                return k, "hit"
        return None


def test_find_wait_smallest_wait_by_hand():
    dt = 0.1
    seg_t = np.arange(6) * dt  # q[0] goes 0 → 1 in 0.5 s: above 0.5 at rel 0.3, 0.4, 0.5
    seg_q = np.linspace(0, 1, 6)[:, None]
    # start at 0.8 s: without waiting q > 0.5 at 1.1 s (blocked until 2.0 s); the first free start has
    # 0.8 + n·0.1 + 0.3 ≥ 2.0 → n = 9 (the coarse scan overshoots to 10 and refines back)
    assert find_wait([Window(1.0, 2.0)], 0.8, seg_q[0], seg_t, seg_q, dt) == 9
    # a window that ends before the move needs no wait
    assert find_wait([Window(0.0, 0.5)], 0.8, seg_q[0], seg_t, seg_q, dt) == 0
    assert find_wait([], 0.8, seg_q[0], seg_t, seg_q, dt) == 0


def test_find_wait_fails_when_hit_while_waiting_or_never_free():
    dt = 0.1
    seg_t = np.arange(6) * dt
    seg_q = np.linspace(0, 1, 6)[:, None]
    with pytest.raises(ScheduleError, match="waiting"):
        find_wait([Window(1.0, 2.0, t_hit=1.5)], 0.8, seg_q[0], seg_t, seg_q, dt)

    class Forever(Window):
        def first_collision(self, t, Q):
            return (0, "wall") if np.any(Q[:, 0] > 0.5) else None
    with pytest.raises(ScheduleError, match="settled"):
        find_wait([Forever(0, 3.0)], 0.8, seg_q[0], seg_t, seg_q, dt)
    assert check_hold([Window(1.0, 2.0, t_hit=1.5)], 1.0, seg_q[0], 1.0, dt).startswith("at t = 1.500 s")
    assert check_hold([Window(1.0, 2.0, t_hit=1.5)], 1.0, seg_q[0], 0.3, dt) is None


# ---------------------------------------------------------------------------------------------------------
# a box that sits on the path until a known time
# ---------------------------------------------------------------------------------------------------------
T_CLEAR = 1.2  # the box leaves the path at this time


def crossing_task(tmp_path) -> Path:
    A, B = (0.5, 0.35, 0.30), (0.5, -0.35, 0.30)
    tol = dict(r_sph=(0.0, 0.005), N_x=(-0.05, 0.05), N_y=(-0.05, 0.05))
    k_clear = int(round(T_CLEAR / mt.DT))
    poses = [mt.T((0, 0, 0))] * k_clear + [mt.T((3.0, 0, 0))]  # one pose per step; then gone (x + 3 m)
    task = {
        "header": {"ID": "moving/crossing", "version": "2023", "timeStepSize": mt.DT},
        "obstacles": [mt.obstacle("box", "box on the path", [mt.box((0.58, 0.0, 0.30), (0.2, 0.2, 0.2))],
                                  trajectory={"t": mt.DT, "pose": poses})],
        "constraints": [{"type": "joint", "parts": ["q", "dq", "tau"]}, {"type": "collisionFree"},
                        {"type": "allGoalsFulfilled"}, {"type": "allGoalsFulfilledInOrder", "order": ["a", "b"]}],
        "goals": [{"ID": "a", "type": "reach", "goalPose": mt.tolerated(mt.T(A, mt.TOOL_DOWN), **tol)},
                  {"ID": "b", "type": "reach", "goalPose": mt.tolerated(mt.T(B, mt.TOOL_DOWN), **tol)}],
    }
    p = tmp_path / "moving" / "crossing.json"
    p.parent.mkdir(parents=True)
    p.write_text(json.dumps(mt._clean(task)))
    return p


def test_waits_for_a_box_that_blocks_the_path_and_no_wait_is_rejected_at_the_exact_sample(ms, tmp_path):
    task = load_task(crossing_task(tmp_path))
    box = task.obstacles[0]
    res = solve(task, ms, ORDER)
    assert res.feasible, res.message
    g2t = res.solution.trajectory.goal2time
    # the same robot in the cell without the box: the time-optimal move a → b
    static = replace(task, obstacles=())
    free = solve(static, ms, ORDER)
    assert free.feasible, free.message
    move = free.solution.trajectory.goal2time["b"] - free.solution.trajectory.goal2time["a"]
    # the solver waited: b is reached at least `move` after... the box is gone only at T_CLEAR, and the
    # TCP passes the box's place mid-move, so b is reached later than without the box
    assert g2t["b"] > free.solution.trajectory.goal2time["b"] + 0.2
    assert g2t["b"] - g2t["a"] >= move - 1e-9
    # the no-wait timing in the cell with the box: rejected, first at the sample where the arm meets the box
    v = check(task, free.solution.with_(task_id=task.id), ms)
    hits = sorted((x for x in v.violations if x.constraint == "collisionFree"), key=lambda x: x.time)
    assert not v.valid and hits, [str(x) for x in v.violations]
    # independent: the first sample at which the robot (at q_k) overlaps the box in its pose at t_k
    tr = free.solution.trajectory
    robot = build_robot(task, ms, free.solution.assembly(ms), free.solution.base_pose)
    k_hit = next(k for k in range(tr.n) if tr.t[k] < T_CLEAR - 1e-9 and robot.collides_with_obstacles(tr.q[k]))
    assert hits[0].sample in (k_hit - 1, k_hit)  # between samples k_hit-1 and k_hit, or at k_hit
    assert tr.t[k_hit - 1] - 1e-9 <= hits[0].time <= tr.t[k_hit] + 1e-9
    assert box.moving and box.transform_at(T_CLEAR)[0, 3] == 3.0


# ---------------------------------------------------------------------------------------------------------
# the built-in task: the shuttle covers the place station until 2 s
# ---------------------------------------------------------------------------------------------------------
def test_builtin_wait_for_shuttle_is_solved_only_by_waiting(ms):
    task = load_task("robodesign/wait_for_shuttle")
    res = solve(task, ms, ORDER, base_pose=mt.base_pose("wait_for_shuttle"))
    assert res.feasible, res.message
    assert res.verdict.valid
    # the shuttle covers the station until WS_PARKED_UNTIL and needs WS_SHUTTLE / (1.5 m / WS_LEAVE s) to
    # clear its own width: the place goal cannot be reached before
    g2t = res.solution.trajectory.goal2time
    assert g2t["place"] >= mt.SH_PARKED_UNTIL
    # a planner that sees the shuttle frozen at its t = 0 pose (the old solver) cannot solve the task
    shuttle = task.obstacles[1]
    frozen = replace(task, obstacles=(task.obstacles[0], replace(shuttle, motion_t=None, motion_poses=None)))
    old = solve(frozen, ms, ORDER)
    assert not old.feasible and old.stage in ("ik", "plan"), (old.stage, old.message)


# ---------------------------------------------------------------------------------------------------------
# the judge sweeps moving obstacles over the judged motion, not over the chord between samples
# ---------------------------------------------------------------------------------------------------------
def test_moving_obstacles_are_swept_over_the_judged_motion_not_the_chord(ms, tmp_path):
    """Two equal samples: the chord is a point clear of the box, but the motion between them (``at``: the base
    joint swings out by δ and back; ``path``: its speed bound πδ per unit of s) passes through it. The moving-obstacle sweep
    finds the contact only when it is given that motion, at a fraction s whose configuration is checked
    independently (the box is in its t = 0 place until T_CLEAR)."""
    from robodesign.formats.assembly import Assembly
    from robodesign.model.cell import moving_obstacle_events, moving_obstacle_indices

    task = load_task(crossing_task(tmp_path))
    robot = build_robot(task, ms, Assembly.from_order(ms, ORDER), task.nominal_base_pose)
    moving = moving_obstacle_indices(robot, task)
    assert len(moving) == 1
    rng = np.random.default_rng(5)
    for _ in range(5000):  # a configuration clear of the box whose base-joint swing by δ meets the box
        q = robot.random_configuration(rng)
        if robot.in_collision(q):
            continue
        hits = [d for d in np.linspace(0.05, 1.0, 20)
                if robot.collides_with_obstacles(q + d * np.eye(robot.dof)[0]) and not robot.in_self_collision(
                    q + d * np.eye(robot.dof)[0])]
        if hits:
            delta = hits[0]
            break
    else:
        pytest.fail("no test configuration found")
    e0 = np.eye(robot.dof)[0]

    def at(k, s):
        return q + delta * math.sin(math.pi * s) * e0   # out to δ at s = 1/2 and back

    path = (math.pi * delta * e0)[None, :]  # the joint's speed bound per unit s, as the judge's path_bound
    t = np.array([0.0, 0.4])  # both before T_CLEAR: the box stays in place
    Q = np.array([q, q])
    assert moving_obstacle_events(robot, task, moving, t, Q) == []  # the chord (a point) is clear
    evs = moving_obstacle_events(robot, task, moving, t, Q, path=path, at=at)
    assert evs and all(e.sample == 0 and 0.0 < e.s < 1.0 and e.second.startswith("obstacle:box") for e in evs)
    # independent: the configuration at the reported fraction touches the box (within the certification's
    # resolution: the first contact lies at or just before it), the start does not
    assert robot.collides_with_obstacles(at(0, 0.5))
    assert not robot.collides_with_obstacles(q)
    s_first = next(s for s in np.linspace(0, 0.5, 501) if robot.collides_with_obstacles(at(0, s)))
    assert min(e.s for e in evs) <= s_first + 1e-3
