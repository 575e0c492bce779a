"""robodesign's built-in tasks (assets/tasks/robodesign/*.json, written by assets/tasks/make_tasks.py).

For every task: the file is what the generator writes; the default arm solves it (fixed seed, base pose
from ``SOLVE_SETUP``); the checker accepts the solution, also after a write/read round trip with
identical costs; and a targeted perturbation is flagged with the expected violation. Across all tasks
every goal and constraint type appears (computed from the loaded tasks).
"""
import importlib.util
import math
import sys

import numpy as np
import pinocchio as pin
import pytest

from robodesign.model.cell import build_robot
from robodesign.judge.checker import check
from robodesign.judge.quantities import TrajectoryQuantities, step_residuals
from robodesign.formats.module_io import load_module_set
from robodesign.core.trajectory import Trajectory
from robodesign.formats.solution import Solution, load_solution
from robodesign.solvers.ik import solve_ik
from robodesign.formats.task_io import load_task
from robodesign.formats.task_spec import (BasePlacement, CollisionFree, EndEffectorConstraint, Follow, JointLimitsConstraint,
                                  Leave, Pause)
from robodesign.formats.tolerance import ToleratedPose

from conftest import ROOT

TASK_DIR = ROOT / "assets" / "tasks"
_spec = importlib.util.spec_from_file_location("robodesign_make_tasks", TASK_DIR / "make_tasks.py")
mt = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = mt
_spec.loader.exec_module(mt)

NAMES = sorted(mt.TASKS)
ALL_GOAL_TYPES = {"at", "reach", "returnTo", "pause", "follow", "leave"}
ALL_CONSTRAINT_TYPES = {"joint", "selfCollisionFree", "collisionFree", "basePlacement", "endEffector",
                        "allGoalsFulfilled", "allGoalsFulfilledInOrder", "validAssembly"}


@pytest.fixture(scope="module")
def ms():
    return load_module_set(mt.MODULE_SET)


@pytest.fixture(scope="module")
def solved():
    """name → (task, SolveResult), solved once per test session."""
    cache = {}

    def get(name):
        if name not in cache:
            task, res, _ = mt.solve_builtin(name)
            assert res.feasible, f"{name}: failed at {res.stage}: {res.message}"
            cache[name] = (task, res)
        return cache[name]
    return get


def kinds(verdict):
    return sorted({v.constraint for v in verdict.violations})


def with_trajectory(sol: Solution, q=None, g2t=None, base=None) -> Solution:
    tr = sol.trajectory
    return sol.with_(trajectory=Trajectory(tr.t, tr.q if q is None else q, tr.dq, tr.ddq,
                                           dict(tr.goal2time if g2t is None else g2t)),
                     base_pose=sol.base_pose if base is None else base)


# ---------------------------------------------------------------------------------------------------------
# files and coverage
# ---------------------------------------------------------------------------------------------------------
def test_files_match_the_generator():
    on_disk = sorted(p.stem for p in (TASK_DIR / mt.PACKAGE).glob("*.json"))
    assert on_disk == NAMES
    for name in NAMES:
        text = mt.dumps(mt._clean(mt.TASKS[name]())) + "\n"
        assert mt.task_path(name).read_text() == text, f"{name}.json is stale: run make_tasks.py"
        assert text == mt.dumps(mt._clean(mt.TASKS[name]())) + "\n"  # deterministic


def test_tasks_load_by_id():
    for name in NAMES:
        task = load_task(f"{mt.PACKAGE}/{name}")
        assert task.id == f"{mt.PACKAGE}/{name}" and task.root == TASK_DIR.resolve()
        assert task.dt == 0.01 and not task.warnings


def test_coverage_matrix():
    """Every goal type and constraint type appears in some built-in task (from the loaded tasks)."""
    tasks = [load_task(mt.task_path(n)) for n in NAMES]
    goal_types, cons_types, joint_parts = set(), set(), set()
    features = set()
    for task in tasks:
        for g in task.goals:
            goal_types.add(g.type)
            if isinstance(g, Follow):
                features.add("follow.timed" if g.t is not None else "follow.untimed")
                if np.any(g.external_force != 0) or np.any(g.external_torque != 0):
                    features.add("follow.externalWrench")
            if isinstance(g, Pause) and g.duration > 0:
                features.add("pause.duration")
            if isinstance(g, Leave) and g.duration > 0 and not g.region.is_unconstrained:
                features.add("leave.region+duration")
        for c, level in [(c, "task") for c in task.constraints] + \
                        [(c, "goal") for g in task.goals for c in g.constraints]:
            cons_types.add(c.type)
            if isinstance(c, JointLimitsConstraint):
                joint_parts |= set(c.parts)
            if isinstance(c, CollisionFree) and c.safety_margin > 0:
                features.add("collisionFree.margin")
            if isinstance(c, BasePlacement):
                # a real tolerance: bounded, and wider than the nominal pose alone
                p = c.pose
                if not p.is_unconstrained and p.valid(p.nominal):
                    shifted = p.nominal.copy()
                    shifted[:3, 3] += [0.2, -0.2, 0.0]
                    if p.valid(shifted):
                        far = p.nominal.copy()
                        far[:3, 3] += [5.0, 0.0, 0.0]
                        if not p.valid(far):
                            features.add("basePlacement.tolerance")
            if isinstance(c, EndEffectorConstraint) and math.isfinite(c.v_max) and c.pose is not None \
                    and not c.pose.is_unconstrained:
                features.add(f"endEffector.v_max+pose.{level}")
        if any(o.moving for o in task.obstacles):
            features.add("movingObstacle")
    assert goal_types == ALL_GOAL_TYPES
    assert ALL_CONSTRAINT_TYPES <= cons_types, ALL_CONSTRAINT_TYPES - cons_types
    assert joint_parts == {"q", "dq", "ddq", "tau"}
    assert features >= {"follow.timed", "follow.untimed", "follow.externalWrench", "pause.duration",
                        "leave.region+duration", "collisionFree.margin", "basePlacement.tolerance",
                        "endEffector.v_max+pose.goal", "movingObstacle"}, features


# ---------------------------------------------------------------------------------------------------------
# solve → check → write → read → check
# ---------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", NAMES)
def test_solve_check_round_trip(name, ms, solved, tmp_path):
    task, res = solved(name)
    sol = res.solution
    setup = mt.SOLVE_SETUP[name]
    assert sol.module_order == tuple(setup["order"]) and sol.module_set == mt.MODULE_SET
    np.testing.assert_allclose(sol.base_pose, mt.base_pose(name))
    v = check(task, sol, ms)
    assert v.valid, [str(x) for x in v.violations]
    assert all(v.goals.values()) and set(v.goals) == {g.id for g in task.goals}
    f = sol.write(tmp_path / f"{name}.json")
    back = load_solution(f)
    assert back.task_id == task.id
    v2 = check(task, back, ms)
    assert v2.valid, [str(x) for x in v2.violations]
    assert v2.costs == v.costs and v2.cost == v.cost
    np.testing.assert_array_equal(back.trajectory.q, sol.trajectory.q)
    # one motion (docs/checker.md): robodesign's samples meet both rules to rounding; only the quintic moves of
    # timed follow goals (sampled from the polynomial) use a few percent of the slack
    tr = sol.trajectory
    q_share, dq_share = step_residuals(tr.t, tr.q, tr.dq, tr.ddq).worst_ratio
    assert q_share < (0.05 if name == "timed_follow" else 1e-8) and dq_share < (0.01 if name == "timed_follow" else 1e-8)


# ---------------------------------------------------------------------------------------------------------
# perturbations
# ---------------------------------------------------------------------------------------------------------
def test_pick_and_place_perturbed(ms, solved):
    task, res = solved("pick_and_place")
    sol = res.solution
    g2t = dict(sol.trajectory.goal2time)
    # goals in the wrong order
    swapped = dict(g2t, pick=g2t["place"], place=g2t["pick"])
    v = check(task, with_trajectory(sol, g2t=swapped), ms)
    assert "allGoalsFulfilledInOrder" in kinds(v)
    # the base is bolted down: ±1 mm. 5 mm off is a basePlacement violation
    base = sol.base_pose.copy()
    base[0, 3] += 0.005
    v = check(task, with_trajectory(sol, base=base), ms)
    assert "basePlacement" in kinds(v)
    assert any("x = 0.005" in x.message for x in v.violations if x.constraint == "basePlacement")


def test_machine_tending_pause_broken_and_leave_region_reentered(ms, solved):
    task, res = solved("machine_tending")
    sol = res.solution
    tr = sol.trajectory
    g2t = tr.goal2time
    # pause: nudge one joint by 1 µrad in the middle of the 1 s hold
    k = int(np.argmin(np.abs(tr.t - (g2t["hold"] - 0.5))))
    q = tr.q.copy()
    q[k, 2] += 1e-6
    v = check(task, with_trajectory(sol, q=q), ms)
    assert v.goals["hold"] is False and "goal" in kinds(v)
    assert all(ok for gid, ok in v.goals.items() if gid != "hold")
    # leave: put the TCP back inside the machine (at the load configuration) during the leave window
    k_load = int(np.argmin(np.abs(tr.t - g2t["load"])))
    k0 = int(np.argmin(np.abs(tr.t - g2t["clear"])))
    k_in = k0 + 20  # 0.2 s into the 0.5 s window
    q = tr.q.copy()
    q[k_in] = tr.q[k_load]
    v = check(task, with_trajectory(sol, q=q), ms)
    assert v.goals["clear"] is False
    msg = [x for x in v.violations if x.goal == "clear"]
    assert msg and "inside the region" in msg[0].message and msg[0].sample == k_in


def test_welding_seam_follow_pose_skipped(ms, solved):
    task, res = solved("welding_seam")
    sol = res.solution
    tr = sol.trajectory
    weld = task.goal("weld")
    robot = build_robot(task, ms, sol.assembly(ms), sol.base_pose)
    k_end = int(np.argmin(np.abs(tr.t - tr.goal2time["weld"])))
    k_start = int(np.argmin(np.abs(tr.t - tr.goal2time["seam_start"])))
    # lift the torch (shoulder pitch) wherever seam pose 3 would be met: the pose is skipped
    q = tr.q.copy()
    hits = [k for k in range(k_start, k_end + 1) if weld.poses[3].valid(robot.fk(q[k]))]
    assert hits
    q[hits, 1] -= 0.03
    v = check(task, with_trajectory(sol, q=q), ms)
    assert v.goals["weld"] is False
    assert any("pose 3" in x.message and "never met" in x.message for x in v.violations if x.goal == "weld")
    # ... and the torch left the seam line: the goal-level endEffector pose tolerance reports it
    assert "endEffector.pose" in kinds(v)


def _fext_independent(robot, q, force, torque):
    """Independent construction: the wrench (f, τ) acts at the TCP point, world axes."""
    m, d = robot.model, robot.model.createData()
    pin.framesForwardKinematics(m, d, q)
    p_tcp = d.oMf[robot.tcp_frame].translation
    jid = m.frames[robot.tcp_frame].parentJoint
    w_world = pin.SE3(np.eye(3), p_tcp).act(pin.Force(np.asarray(force, float), np.asarray(torque, float)))
    fext = pin.StdVec_Force()
    for _ in range(m.njoints):
        fext.append(pin.Force.Zero())
    fext[jid] = d.oMi[jid].actInv(w_world)
    return fext


def test_welding_seam_external_force_raises_torque(ms, solved):
    task, res = solved("welding_seam")
    sol = res.solution
    tr = sol.trajectory
    weld = task.goal("weld")
    np.testing.assert_array_equal(weld.external_force, mt.WS_FORCE)  # read from the file, not dropped
    robot = build_robot(task, ms, sol.assembly(ms), sol.base_pose)
    with_force = TrajectoryQuantities.from_solution(robot, sol, task)
    k0, k1 = with_force.goal_windows["weld"]
    assert k1 > k0 and tr.t[k1] == pytest.approx(tr.goal2time["weld"])
    np.testing.assert_array_equal(with_force.external_wrenches[k0:k1 + 1, :3],
                                  np.broadcast_to(mt.WS_FORCE, (k1 - k0 + 1, 3)))
    without = TrajectoryQuantities.from_solution(robot, sol, None)  # no task: no wrenches
    tau_f, tau_0 = with_force.torques, without.torques
    outside = [k for k in range(tr.n) if k < k0 or k > k1]
    np.testing.assert_array_equal(tau_f[outside], tau_0[outside])
    m = robot.model
    for k in (k0, (k0 + k1) // 2, k1):
        q, dq, ddq = tr.q[k], tr.dq[k], tr.ddq[k]
        d = m.createData()
        ref = pin.rnea(m, d, q, dq, ddq, _fext_independent(robot, q, weld.external_force, weld.external_torque)).copy()
        ref0 = pin.rnea(m, m.createData(), q, dq, ddq).copy()
        np.testing.assert_allclose(tau_f[k] - tau_0[k], ref - ref0, atol=1e-9)
        # and the closed form: the environment's push f on the TCP takes −Jᵀf off the joints
        J = robot.jacobian(q)  # TCP, world-aligned
        np.testing.assert_allclose(tau_f[k] - tau_0[k], -J[:3].T @ weld.external_force, atol=1e-9)
        assert np.abs(tau_f[k] - tau_0[k]).max() > 1.0  # 20 N at ~0.5 m: several Nm at the shoulder


def test_base_placement_base_outside_tolerance(ms, solved):
    task, res = solved("base_placement")
    sol = res.solution
    bp = task.base_placement
    assert bp.valid(sol.base_pose) and not bp.valid(mt.T((0.45, 0.0, 0.0)))
    base = sol.base_pose.copy()
    base[0, 3] = 0.45  # 5 cm outside x ∈ [-0.4, 0.4]
    v = check(task, with_trajectory(sol, base=base), ms)
    assert "basePlacement" in kinds(v)
    assert any("x = 0.45" in x.message for x in v.violations if x.constraint == "basePlacement")
    # yaw is free: the documented base turned by 3 rad is still inside the tolerance
    assert bp.valid(mt.T(mt.BP_BASE, mt.rz(3.0)))
    # from the nominal base the fixture is out of reach
    _, r0, _ = mt.solve_builtin("base_placement", base=np.eye(4))
    assert not r0.feasible and r0.stage == "reach" and "fixture" in r0.message


def test_base_placement_moving_part_is_checked_over_time(ms, solved):
    """Hold the arm where the part will be at t ≈ 5 s: free at t = 0, hit when the part arrives."""
    task, res = solved("base_placement")
    sol = res.solution
    part = next(o for o in task.obstacles if o.moving)
    robot = build_robot(task, ms, sol.assembly(ms), sol.base_pose)
    t_hit = 5.0
    center = part.transform_at(t_hit) @ part.collision[0].pose
    # the TCP (any orientation) 1 cm below the top face of the part at t_hit; collision-free at t = 0
    target = ToleratedPose.from_json({"nominal": mt.T(center[:3, 3] + [0.0, 0.0, mt.BP_PART / 2 - 0.01]).tolist(),
                                      "toleranceProjection": ["r_sph"], "tolerance": [[0, 0.01]]})
    ik = solve_ik(robot, target, np.random.default_rng(0), check_collision=True, max_restarts=500)
    assert ik, ik.stats
    q_hit = ik.q
    n = int(round(mt.BP_DURATION / mt.DT)) + 1
    t = np.arange(n) * mt.DT
    Q = np.tile(q_hit, (n, 1))
    hold = Solution(task_id=task.id, cost_function="cyc", module_set=mt.MODULE_SET, module_order=sol.module_order,
                    base_pose=sol.base_pose, trajectory=Trajectory(t, Q, np.zeros_like(Q), np.zeros_like(Q), {}))
    v = check(task, hold, ms)
    hits = [x for x in v.violations if x.constraint == "collisionFree" and "part" in x.message]
    assert hits, [str(x) for x in v.violations]
    # the part (12 cm, 0.12 m/s) touches the tool only around t_hit, never at the start
    assert all(1.5 < x.time < 8.5 for x in hits), [(x.time, x.message) for x in hits]
    assert not any(x.constraint == "collisionFree" and x.time is not None and x.time < 1.0 for x in v.violations)
    # a checker that ignored the motion (part frozen at its t = 0 pose) would see nothing
    assert not robot.collides_with_obstacles(q_hit)


def test_timed_follow_timing_shifted(ms, solved):
    task, res = solved("timed_follow")
    sol = res.solution
    g2t = dict(sol.trajectory.goal2time)
    assert task.goal("dispense").t is not None
    v = check(task, with_trajectory(sol, g2t=dict(g2t, dispense=g2t["dispense"] + 0.2)), ms)
    assert v.goals["dispense"] is False
    assert any("not met at t=" in x.message for x in v.violations if x.goal == "dispense")
    # return home missed by 1 mrad on one joint
    q = sol.trajectory.q.copy()
    q[-1, 0] += 1e-3
    v = check(task, with_trajectory(sol, q=q), ms)
    assert v.goals["home"] is False and v.goals["dispense"] is True
