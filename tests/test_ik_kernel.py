"""The compiled IK loop (robodesign.solvers.ik_kernel) against independent references: pinocchio's forward
kinematics, frame Jacobian, log3 and Jlog3, the Python residual rows of ik.py, and the Python solver itself
(same seed → same solutions)."""
from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from robodesign.formats.module_io import load_module_set
from robodesign.model.robot import Robot
from robodesign.solvers import ik_kernel
from robodesign.solvers.ik import goal_model, solve_ik
from robodesign.core.spatial import homogeneous, rpy_to_matrix
from robodesign.formats.task_io import load_task
from robodesign.formats.tolerance import ToleratedPose

from conftest import IMPROV, PRIMITIVES, ROOT, TASKS

pytestmark = pytest.mark.skipif(not ik_kernel.available(), reason="ROBODESIGN_JIT=0")


@pytest.fixture(scope="module", autouse=True)
def compiled_kernels():
    """Compile (or load) the kernels in this process first: with a cold cache the solver would otherwise run
    the Python loop until the background compilation ends, and the comparisons below would compare the Python
    loop with itself."""
    assert ik_kernel.warm_up() and ik_kernel.ready()

BASE = homogeneous(rpy_to_matrix(0.3, -0.2, 1.0), [1.0, 2.0, 0.5])


@pytest.fixture(scope="module")
def robots(tmp_path_factory):
    from test_urdf import reversed_robot
    imp = load_module_set(IMPROV)
    prim = load_module_set(PRIMITIVES)
    rs = [Robot.from_order(imp, ["1", "21", "4", "21", "23", "12"]),
          Robot.from_order(imp, ["1", "22", "5", "23", "15", "29", "101"], base_pose=BASE),
          Robot.from_order(prim, ["base", "J2", "i_30", "J1", "l_15", "J2", "eef"]),   # prismatic joints
          reversed_robot(tmp_path_factory.mktemp("rev"))]                              # joints about −z
    kinds = [set(ik_kernel.chain_kernel(r).kind.tolist()) for r in rs]
    assert kinds[2] == {0, 1} and min(ik_kernel.chain_kernel(rs[3]).sign) == -1.0
    return rs


def kernel_fk(robot, q):
    ck = ik_kernel.chain_kernel(robot)
    T = np.zeros((4, 4))
    Jv = np.zeros((3, robot.dof))
    Jw = np.zeros((3, robot.dof))
    ik_kernel.fk_jacobian(np.asarray(q, float), ck.chain, ck.kind, ck.sign, ck.iq, ck.tcp, T, Jv, Jw)
    return T, Jv, Jw


def test_fk_and_jacobian_match_pinocchio(robots):
    rng = np.random.default_rng(0)
    for robot in robots:
        for base in (None, homogeneous(rpy_to_matrix(-0.4, 0.1, 2.0), [0.3, -0.2, 0.1])):
            if base is not None:
                robot.set_base_pose(base)      # the chain cache follows the base pose
            for _ in range(20):
                q = robot.random_configuration(rng)
                T, Jv, Jw = kernel_fk(robot, q)
                assert np.abs(T - robot.fk(q)).max() < 1e-12
                pin.computeJointJacobians(robot.model, robot.data, q)
                pin.updateFramePlacements(robot.model, robot.data)
                J = pin.getFrameJacobian(robot.model, robot.data, robot.tcp_frame, pin.LOCAL_WORLD_ALIGNED)
                assert np.abs(Jv - J[:3]).max() < 1e-12 and np.abs(Jw - J[3:]).max() < 1e-12


def _log3(R):
    K = ik_kernel._kernels()
    w = np.zeros(3)
    th = K["log3"](np.ascontiguousarray(R), w)
    return th, w


def test_log3_and_jlog3_match_pinocchio():
    rng = np.random.default_rng(1)
    K = ik_kernel._kernels()
    axes = [v / np.linalg.norm(v) for v in rng.normal(size=(30, 3))] + list(np.eye(3))
    angles = [1e-9, 1e-6, 1e-4, 9.9e-4, 1e-3, 0.01, 0.3, 1.0, 2.0, 3.0, math.pi - 1e-2, math.pi - 1e-3,
              math.pi - 1e-4, math.pi - 1e-7]
    for a in axes:
        for ang in angles:
            R = pin.exp3(a * ang)
            th, w = _log3(R)
            assert abs(th - ang) < 1e-9
            assert np.abs(w - pin.log3(R)).max() < 1e-7 * max(1.0, 1.0 / max(math.pi - ang, 1e-12) * 1e-6)
            if ang < math.pi - 1e-3:
                JL = np.zeros((3, 3))
                K["jlog3"](th, w, JL)
                assert np.abs(JL - pin.Jlog3(R)).max() < 1e-9
        # exactly π: the axis up to its sign
        th, w = _log3(pin.exp3(a * math.pi))
        assert abs(th - math.pi) < 1e-12
        assert min(np.abs(w - a * math.pi).max(), np.abs(w + a * math.pi).max()) < 1e-7


def _goals(T_ref):
    ptp3 = load_task(TASKS / "simple" / "PTP_3.json")
    pick = load_task(ROOT / "assets" / "tasks" / "robodesign" / "pick_and_place.json")
    gs = [g.pose for g in ptp3.goals] + [g.pose for g in pick.goals if getattr(g, "pose", None) is not None]
    gs += [
        ToleratedPose(T_ref, ("x", "y", "z", "N_x", "N_y", "N_z"),
                      ((-0.01, 0.02), (-0.02, 0.01), (-0.01, 0.01), (-0.03, 0.03), (-0.03, 0.03), (0.0, 0.05))),
        ToleratedPose(T_ref, ("x", "y", "z", "Theta_R"), ((-0.003, 0.003), (-0.003, 0.003), (-0.003, 0.003),
                                                          (0.0, 0.02)), ("world", "world", "world", "nominal")),
        ToleratedPose(T_ref, ("r_cyl", "z", "N_z", "Theta_R"), ((0.01, 0.03), (-0.01, 0.01), (-0.1, 0.1), (0.0, 0.2)),
                      ("world", "world", "world", "nominal")),
        ToleratedPose(T_ref, ("r_sph", "N_x", "N_y"), ((0.0, 0.02), (-0.05, 0.05), (-0.05, 0.05))),
        ToleratedPose(T_ref, ("z", "r_sph"), ((0.0, math.inf), (0.0, 0.5))),
    ]
    return gs


def test_goal_rows_match_the_python_rows(robots):
    robot = robots[1]
    rng = np.random.default_rng(2)
    T_ref = robot.fk(robot.random_configuration(rng)).copy()
    goals = _goals(T_ref)
    assert len(goals) >= 9
    K = ik_kernel._kernels()
    for gi, goal in enumerate(goals):
        gm = goal_model(goal)
        prog = gm.program()
        assert prog is not None, goal.projections
        tkind, tvec = prog
        m = ik_kernel.rows_of(tkind)
        assert m == gm.n_rows
        f, E_py, JJ_py = gm.evaluator(robot.dof)
        hits = 0
        for k in range(60):
            # half near a solution of the goal (rows partly zero, the exact check true for some), half anywhere
            q = robot.random_configuration(rng)
            if k % 2 == 0:
                res = solve_ik(robot, goal, rng=k, max_restarts=3, check_collision=False)
                if res.success:
                    q = res.q + rng.normal(0, 1e-3, robot.dof)
            T, Jv, Jw = kernel_fk(robot, q)
            pin.computeJointJacobians(robot.model, robot.data, q)
            pin.updateFramePlacements(robot.model, robot.data)
            J = pin.getFrameJacobian(robot.model, robot.data, robot.tcp_frame, pin.LOCAL)
            ok_py = f(robot.fk(q).copy(), J)
            E = np.zeros(m)
            JJ = np.zeros((m, robot.dof))
            ok_k = K["goal_rows"](T, Jv, Jw, gm.N_inv, tkind, tvec, E, JJ, np.zeros((2, 3)))
            assert ok_k == ok_py
            hits += ok_k
            assert np.abs(E - E_py).max() < 1e-10
            assert np.abs(JJ - JJ_py).max() < 1e-9
        if gi >= len(goals) - 5:
            assert 1 <= hits < 60   # the exact check was exercised both ways


@pytest.mark.parametrize("order", [["1", "22", "7", "29", "4", "21", "16"], ["1", "21", "4", "22", "5", "23", "12"],
                                   ["1", "4", "23", "7", "21", "5", "12"]])
def test_solver_gives_the_python_solutions(order, monkeypatch):
    """Same seed, same restarts → the compiled loop finds the same solutions as the Python loop."""
    ms = load_module_set(IMPROV)
    task = load_task(TASKS / "simple" / "PTP_3.json")
    T_ref = None
    results = {}
    for jit in ("1", "0"):
        monkeypatch.setenv("ROBODESIGN_JIT", jit)
        robot = Robot.from_order(ms, order)
        if T_ref is None:
            T_ref = robot.fk(robot.random_configuration(np.random.default_rng(5))).copy()
        goals = [g.pose for g in task.goals] + _goals(T_ref)[-5:]
        out = []
        for i, goal in enumerate(goals):
            res = solve_ik(robot, goal, rng=i, max_restarts=60, n_solutions=3)
            out.append((res.stats["attempts"], res.stats["converged"], res.stats["iterations"], res.solutions))
        results[jit] = out
    solved = 0
    for (a1, c1, i1, s1), (a0, c0, i0, s0) in zip(results["1"], results["0"]):
        assert (a1, c1, i1) == (a0, c0, i0)
        assert len(s1) == len(s0)
        for x, y in zip(s1, s0):
            assert np.abs(x - y).max() < 1e-8
        solved += bool(s1)
    assert solved >= 3
