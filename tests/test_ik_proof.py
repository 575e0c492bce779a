"""The compiled descent's proof of ``ToleratedPose.valid`` (``ik_kernel.proven_valid``): wherever it claims the
pose valid, ``valid`` itself says so, on random robots, poses and goals whose bounds lie within a few rounding
errors of the pose's values; it fires on most converged poses; it is off for goals outside its conditions; and
``solve_ik`` finds the same solutions, bit for bit, with the proof and with ``valid`` asked every time."""
from __future__ import annotations

import math

import numpy as np
import pytest

from robodesign.core.spatial import homogeneous, rpy_to_matrix
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.formats.tolerance import PROJECTIONS, ToleratedPose
from robodesign.model.robot import Robot
from robodesign.solvers import ik, ik_kernel, ik_proof
from robodesign.solvers.ik import goal_model, solve_ik

from conftest import IMPROV, PRIMITIVES, TASKS

pytestmark = pytest.mark.skipif(not ik_kernel.available(), reason="ROBODESIGN_JIT=0")

RADIAL = ("x", "y", "z", "r_cyl", "r_sph", "Theta_R")


@pytest.fixture(scope="module", autouse=True)
def compiled_kernels():
    assert ik_kernel.warm_up() and ik_kernel.ready()


def _robots():
    imp, prim = load_module_set(IMPROV), load_module_set(PRIMITIVES)
    rng = np.random.default_rng(11)
    out = []
    for order, ms in ((["1", "21", "4", "22", "5", "23", "12"], imp), (["1", "22", "5", "23", "15", "29", "101"], imp),
                      (["base", "J2", "i_30", "J1", "l_15", "J2", "eef"], prim)):
        base = homogeneous(rpy_to_matrix(*rng.uniform(-math.pi, math.pi, 3)), rng.uniform(-2.0, 2.0, 3))
        out.append(Robot.from_order(ms, order, base_pose=base))
    return out


def _values(goal: ToleratedPose, T: np.ndarray) -> dict:
    """The reference values of every radial projection of T in the goal's nominal frame (``values``' own)."""
    probe = ToleratedPose(goal.nominal, RADIAL, tuple((PROJECTIONS[n].lo, PROJECTIONS[n].hi) for n in RADIAL))
    return {name: v for (name, _), v in probe.values(T).items()}


def _kernel_status(robot, goal, q) -> tuple:
    """(status of one kernel iteration at q: 2 proven, 1 analytic check only, 0 neither; the kernel's T)."""
    gm = goal_model(goal)
    tkind, tvec = gm.program()
    ck = ik_kernel.chain_kernel(robot)
    n = robot.dof
    E, JJ, T = np.zeros(ik_kernel.rows_of(tkind)), np.zeros((ik_kernel.rows_of(tkind), n)), np.zeros((4, 4))
    params = np.array([0.02, 1e-6, 1.0, 0.9, 3.0])
    lo, hi = np.full(n, -10.0), np.full(n, 10.0)
    status, _ = ik_kernel.lm_descend(np.array(q, float), 1, lo, hi, ck.chain, ck.kind, ck.sign, ck.iq, ck.tcp,
                                     gm.N_inv, tkind, tvec, E, JJ, T, params)
    return status, T


def test_the_proof_never_claims_an_invalid_pose():
    """Goals whose bounds sit k·1e-13 (|k| ≤ 12) from the pose's own values: the proof's verdicts against
    ``valid``'s, and both outcomes of ``valid`` exercised."""
    rng = np.random.default_rng(3)
    proven = valid_only = invalid = 0
    for robot in _robots():
        for _ in range(40):
            q = robot.random_configuration(rng)
            T0 = robot.fk(q).copy()
            nominal = homogeneous(rpy_to_matrix(*rng.normal(0.0, 0.3, 3)), rng.normal(0.0, 0.2, 3)) @ T0
            vals = _values(ToleratedPose(nominal), T0)
            names = [str(x) for x in rng.choice(RADIAL, size=int(rng.integers(1, 4)), replace=False)]
            k = int(rng.integers(-12, 13))
            side = rng.integers(0, 2, len(names))
            intervals = []
            for name, s in zip(names, side):
                edge = vals[name] + k * 1e-13 * (1 if s else -1)
                lo_free = 0.0 if name in ("r_cyl", "r_sph", "Theta_R") else vals[name] - 1.0
                intervals.append((edge, vals[name] + 1.0) if s else (lo_free, edge))
            goal = ToleratedPose(nominal, tuple(names), tuple(intervals))
            if goal_model(goal).program() is None:
                continue
            status, T = _kernel_status(robot, goal, q)
            if status == 2:
                proven += 1
                assert goal.valid(T), (names, intervals, k)
            elif goal.valid(T):
                valid_only += 1
            else:
                invalid += 1
    assert proven > 20 and invalid > 5 and valid_only > 0


def test_the_proof_fires_on_converged_poses_and_follows_its_conditions():
    """PTP_3's goals are provable and the proof holds at their solutions; a world frame, an orientation axis, a
    constraint covering its whole range or a bound beyond ±64 turn it off (its interval empty)."""
    ms = load_module_set(IMPROV)
    robot = Robot.from_order(ms, ["1", "21", "4", "22", "5", "23", "12"])
    task = load_task(TASKS / "simple" / "PTP_3.json")
    for g in task.goals:
        assert ik_proof.valid_provable(g.pose, goal_model(g.pose).N_inv)
        res = solve_ik(robot, g.pose, rng=0, max_restarts=40, n_solutions=3, check_collision=False)
        for q in res.solutions:
            assert _kernel_status(robot, g.pose, q)[0] == 2
    N = robot.fk(robot.random_configuration(np.random.default_rng(1))).copy()
    off = [ToleratedPose(N, ("x", "r_sph"), ((-0.1, 0.1), (0.0, 0.1)), ("world", "nominal")),
           ToleratedPose(N, ("r_sph", "N_x"), ((0.0, 0.1), (-0.1, 0.1))),
           ToleratedPose(N, ("r_sph", "Theta_R"), ((0.0, 0.1), (0.0, math.pi))),
           ToleratedPose(N, ("z", "r_sph"), ((-100.0, 100.0), (0.0, 0.1)))]
    for goal in off:
        assert not ik_proof.valid_provable(goal, goal_model(goal).N_inv)
        prog = goal_model(goal).program()
        assert prog is None or (prog[1][:, 10] > prog[1][:, 11]).all()
    far = homogeneous(np.eye(3), [20.0, 0.0, 0.0])
    assert not ik_proof.valid_provable(ToleratedPose(far, ("r_sph",), ((0.0, 0.1),)), np.linalg.inv(far))


@pytest.mark.parametrize("order", [["1", "21", "4", "22", "5", "23", "12"], ["1", "22", "7", "29", "4", "21", "16"]])
def test_solve_ik_gives_the_same_solutions_with_and_without_the_proof(order, monkeypatch):
    """Bit for bit: solutions, stats and the generator's state after the call; ``valid`` asked far less."""
    ms = load_module_set(IMPROV)
    task = load_task(TASKS / "simple" / "PTP_3.json")
    out, asked = {}, {}
    for proof in (True, False):
        if not proof:
            monkeypatch.setattr(ik, "valid_provable", lambda goal, N_inv: False)
        robot = Robot.from_order(ms, order)
        T_ref = robot.fk(robot.random_configuration(np.random.default_rng(5))).copy()
        goals = [g.pose for g in task.goals] + [
            ToleratedPose(T_ref, ("x", "y", "z", "Theta_R"), ((-0.003, 0.003),) * 3 + ((0.0, 0.02),)),
            ToleratedPose(T_ref, ("r_cyl", "z", "Theta_R"), ((0.0, 0.01), (-0.01, 0.01), (0.0, 0.05)))]
        goals = [ToleratedPose(g.nominal, g.projections, g.intervals, g.frames) for g in goals]   # fresh caches
        calls = [0]
        for g in goals:
            real = g.valid

            def counted(T, *a, _real=real):
                calls[0] += 1
                return _real(T, *a)
            object.__setattr__(g, "valid", counted)
        res = []
        for i, goal in enumerate(goals):
            rng = np.random.default_rng(1000 + i)
            r = solve_ik(robot, goal, rng=rng, max_restarts=150, n_solutions=48)
            res.append(([q.tobytes() for q in r.solutions], {k: v for k, v in r.stats.items() if k != "time"},
                        rng.bit_generator.state["state"]["state"]))
        out[proof], asked[proof] = res, calls[0]
    assert out[True] == out[False]
    assert sum(len(s) for s, _, _ in out[True]) >= 5
    assert asked[True] < 0.2 * asked[False] and asked[False] > 50
