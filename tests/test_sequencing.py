"""Choosing IK solutions along the goal sequence: dynamic programming against brute-force enumeration,
vectorised time bounds against the scalar ones, and the effect on real solves."""
import itertools

import numpy as np
import pytest

from conftest import COBRA

from robodesign.solvers.sequencing import Fixed, Free, Jump, Tied, choose
from robodesign.solvers.timing import time_optimal_bound, time_optimal_bounds, trapezoid_time


def _l1(A, B):
    return np.abs(B[None, :, :] - A[:, None, :]).sum(axis=-1)


def _brute(nodes, cost):
    """Enumerate every combination of Free choices and add up the chain's moves."""
    frees = [n for n in nodes if isinstance(n, Free)]
    best = (np.inf, None)
    for combo in itertools.product(*[range(len(n.configs)) for n in frees]):
        pick = {n.key: n.configs[i] for n, i in zip(frees, combo)}
        first = pick[nodes[0].key] if isinstance(nodes[0], Free) else nodes[0].q
        total, q = 0.0, None
        for n in nodes:
            target = (pick[n.key] if isinstance(n, Free) else first if isinstance(n, Tied) else n.q)
            if q is not None and not isinstance(n, Jump):
                total += float(cost(q[None], target[None])[0, 0])
            q = target
        if total < best[0]:
            best = (total, dict(zip([n.key for n in frees], combo)))
    return best


@pytest.mark.parametrize("seed", range(6))
def test_choose_matches_brute_force(seed):
    rng = np.random.default_rng(seed)
    dof = 3
    sizes = rng.integers(1, 5, size=4)
    nodes = [Free(f"g{i}", rng.normal(size=(k, dof))) for i, k in enumerate(sizes)]
    # a return to the start closes the cycle; a follow goal (fixed start, free jump to its end) in between
    chains = [nodes, nodes + [Tied()], nodes[:2] + [Fixed(rng.normal(size=dof)), Jump(rng.normal(size=dof))]
              + nodes[2:] + [Tied()], [Fixed(rng.normal(size=dof))] + nodes]
    for chain in chains:
        idx, total = choose(chain, _l1)
        b_total, b_idx = _brute(chain, _l1)
        assert total == pytest.approx(b_total, abs=1e-12)
        # the chosen indices realise the reported total
        assert _brute([n if not isinstance(n, Free) else Free(n.key, n.configs[[idx[n.key]]]) for n in chain],
                      _l1)[0] == pytest.approx(total, abs=1e-12)


def test_tied_cycle_changes_the_choice():
    """Hand-made chains on a line (cost = distance): the first choice is carried round the cycle; the one that
    makes the round trip cheaper wins with it (all totals hand-computed in the comments)."""
    g1 = Free("a", np.array([[0.0], [4.0]]))
    g2 = Free("b", np.array([[5.0]]))
    idx, total = choose([g1, g2], _l1)
    assert idx == {"a": 1, "b": 0} and total == 1.0          # 4 → 5
    idx, total = choose([g1, g2, Tied()], _l1)
    assert idx == {"a": 1, "b": 0} and total == 2.0          # 4 → 5 → 4
    g3 = Free("c", np.array([[-1.0]]))
    idx, total = choose([g1, g2, g3, Tied()], _l1)           # start 0: 5+6+1 = 12; start 4: 1+6+5 = 12
    assert total == 12.0
    g3 = Free("c", np.array([[-3.0]]))
    idx, total = choose([g1, g2, g3, Tied()], _l1)           # start 0: 5+8+3 = 16; start 4: 1+8+7 = 16
    assert total == 16.0
    g0 = Free("a", np.array([[0.0], [4.0], [-2.0]]))
    idx, total = choose([g0, g2, g3, Tied()], _l1)           # start -2: 7+8+1 = 16 ... all 16: a loop 5→-3
    assert total == 16.0
    g2b = Free("b", np.array([[5.0], [-2.5]]))
    idx, total = choose([g0, g2b, g3, Tied()], _l1)          # -2 → -2.5 → -3 → -2: 0.5+0.5+1
    assert idx == {"a": 2, "b": 1, "c": 0} and total == 2.0


def test_vectorised_bounds_match_scalar():
    from robodesign import Robot, load_module_set
    ms = load_module_set("../shared/cobra/modules/IMPROV")
    robot = Robot.from_order(ms, ["1", "21", "4", "22", "5", "23", "12"])
    rng = np.random.default_rng(0)
    A = np.array([robot.random_configuration(rng) for _ in range(5)])
    B = np.array([robot.random_configuration(rng) for _ in range(4)])
    B[0] = A[0]                                                   # a zero move
    B[1] = A[1] + 1e-4                                            # a tiny (bang-bang) move
    M = time_optimal_bounds(robot, np.abs(B[None] - A[:, None]))
    for i in range(5):
        for j in range(4):
            ref = max(trapezoid_time(d, v, a) for d, v, a in zip(B[j] - A[i], robot.dq_max, robot.ddq_max))
            assert M[i, j] == pytest.approx(ref, rel=1e-12, abs=1e-15)
            assert time_optimal_bound(robot, A[i], B[j]) == M[i, j]
    assert M[0, 0] == 0.0


def test_returning_move_is_in_the_objective():
    """PTP_3 with a return to the start appended (1 → 2 → 3 → back to 1): the chosen IK solutions minimise
    the bound of all three moves, the closing one included — brute force over the solver's IK sets."""
    import dataclasses
    from robodesign.formats.assembly import Assembly
    from robodesign.design.evaluator import evaluation_settings
    from robodesign.formats.module_io import load_module_set
    from robodesign.model.cell import build_robot
    from robodesign.design.solve import GoalPlanner, SolveResult
    from robodesign.formats.task_io import load_task
    from robodesign.formats.task_spec import ReturnTo
    task = load_task(str(COBRA / "tasks" / "simple" / "PTP_3.json"))
    task = dataclasses.replace(task, goals=task.goals + (ReturnTo(id="back"),))
    assert task.goal_order == ("1", "2", "3", "back")
    ms = load_module_set(str(COBRA / "modules" / "IMPROV"))
    order = ["1", "8", "22", "5", "21", "5", "29", "5", "13"]          # 7 DoF: many IK solutions per goal
    robot = build_robot(task, ms, Assembly.from_order(ms, order), task.nominal_base_pose)
    gp = GoalPlanner(task, robot, evaluation_settings(seed=0), np.random.default_rng(0), SolveResult())
    gp.solve_ik()
    gp.filter_static_torque()
    gp.choose_and_plan()

    def cost(A, B):
        return time_optimal_bounds(robot, np.abs(B[None] - A[:, None]))
    S = [np.asarray(gp.ik[g]) for g in ("1", "2", "3")]
    assert min(len(x) for x in S) > 4
    c12, c23, c31 = cost(S[0], S[1]), cost(S[1], S[2]), cost(S[2], S[0])
    cycle = c12[:, :, None] + c23[None, :, :] + c31.T[:, None, :]       # [i, j, k]: 1i → 2j → 3k → 1i
    q = [gp.choice[g] for g in ("1", "2", "3")]
    got = sum(time_optimal_bound(robot, a, b) for a, b in zip(q, q[1:] + q[:1]))
    assert got == pytest.approx(float(cycle.min()), rel=1e-12)
    # ignoring the return (the open chain's optimum) costs more round trip here
    open_best = np.unravel_index(np.argmin(c12[:, :, None] + c23[None, :, :]), cycle.shape)
    assert cycle[open_best] > got + 1e-3
    # the robot starts at the chosen configuration of goal 1 and the return moves back there
    assert np.array_equal(gp.q0, q[0]) and np.array_equal(gp.actions[-1][1], q[0])
