"""The shared evaluator and the checker on the real PTP_3 task (IMPROV arms, CNC-machine mesh)."""
import json

import numpy as np
import pytest

from robodesign import load_module_set
from robodesign.judge.checker import check
from robodesign.design.evaluator import INFEASIBLE, STAGE_PENALTY, Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import BaseBounds, Candidate
from robodesign.formats.solution import SolutionTrajectory, parse_solution
from robodesign.design.solve import STAGES
from robodesign.formats.task_io import load_task, parse_task

from conftest import IMPROV, TASKS

PTP3 = TASKS / "simple" / "PTP_3.json"
GOOD = ("1", "21", "4", "22", "5", "23", "12")


@pytest.fixture(scope="module")
def problem():
    return Problem.build(PTP3, IMPROV, "cyc")


@pytest.fixture(scope="module")
def evaluator(problem):
    return Evaluator(EvaluatorSpec(problem, seed=0))


@pytest.fixture(scope="module")
def good(evaluator):
    return evaluator(Candidate(GOOD))


def test_known_good_candidate_is_feasible_and_scored_by_the_checker(evaluator, good):
    assert good.feasible and good.stage == "done" and good.stage_index == len(STAGES)
    sol = parse_solution(good.solution, "good")
    v = check(evaluator.task, sol, evaluator.module_set)  # one judge: the score is the checker's cost
    assert v.valid and good.score == good.cost == pytest.approx(v.cost) == pytest.approx(sol.trajectory.t[-1])
    assert [s["name"] for s in good.stages] == [s for s in STAGES if s != "trajopt"]
    assert all(s["passed"] and s["seconds"] >= 0 for s in good.stages)


def test_known_infeasible_candidates_stop_at_the_right_stage(evaluator):
    # three 2-DoF modules without links: goal 1 lies beyond the sum of the joint distances
    short = evaluator(Candidate(("1", "23", "22", "23", "16")))
    assert not short.feasible and short.stage == "reach" and "reaches at most" in short.message
    assert [s["name"] for s in short.stages] == ["assembly", "base", "reach"]
    # an order whose modules do not connect fails at the assembly stage
    bad = evaluator(Candidate(("1", "12", "21")))
    assert bad.stage == "assembly" and "do not connect" in bad.message
    # ordered scores: infeasible > any feasible; getting further ranks better
    assert bad.score > short.score > INFEASIBLE > 0
    assert short.score > INFEASIBLE + 1


def test_cache_and_determinism(evaluator, good):
    assert evaluator(Candidate(GOOD)) is good  # cached by candidate key
    fresh = Evaluator(EvaluatorSpec(Problem.build(str(PTP3), str(IMPROV), "cyc"), seed=0))
    assert fresh.cache_key(Candidate(GOOD)) == evaluator.cache_key(Candidate(GOOD))  # equal problems, equal keys
    again = fresh(Candidate(GOOD))
    assert again.cost == good.cost and again.seed == good.seed
    assert again.solution["trajectory"]["q"] == good.solution["trajectory"]["q"]


def _translation(p):
    T = np.eye(4)
    T[:3, 3] = p
    return T


def test_cache_key_covers_the_base_bounds(problem):
    """Regression: the cache was keyed by the candidate alone, so the same base parameters decoded under other
    base bounds (another free dimension, here y instead of x) returned the first problem's evaluation."""
    c = Candidate(GOOD, (0.03,))
    along_x = problem.with_(base_bounds=BaseBounds(lower=(-0.05, 0, 0, 0), upper=(0.05, 0, 0, 0)))
    along_y = problem.with_(base_bounds=BaseBounds(lower=(0, -0.05, 0, 0), upper=(0, 0.05, 0, 0)))
    assert along_x.fingerprint() != along_y.fingerprint()
    shared: dict = {}
    ex = Evaluator(EvaluatorSpec(along_x, seed=0), cache=shared)
    ey = Evaluator(EvaluatorSpec(along_y, seed=0), cache=shared)
    assert ex.cache_key(c) != ey.cache_key(c)
    a, b = ex(c), ey(c)
    assert a.feasible and b.feasible and len(shared) == 2
    nominal = problem.task.nominal_base_pose
    for ev, offset in ((a, [0.03, 0, 0]), (b, [0, 0.03, 0])):
        assert np.allclose(np.array(ev.solution["basePose"][0]), nominal @ _translation(offset))
    assert ey(c) is b and ex(c) is a
    # the seed and the solve settings are part of the key too
    assert Evaluator(EvaluatorSpec(along_x, seed=1)).cache_key(c) != ex.cache_key(c)


def test_ptp3_solution_valid_then_invalid_after_each_single_perturbation(evaluator, good, tmp_path):
    task, ms = evaluator.task, evaluator.module_set
    sol = parse_solution(good.solution, "good")
    assert check(task, sol, ms).valid
    tr = sol.trajectory

    def variant(q=None, dq=None, ddq=None, g2t=None, base=None):
        t2 = SolutionTrajectory(tr.t, tr.q if q is None else q, tr.dq if dq is None else dq,
                        tr.ddq if ddq is None else ddq, tr.goal2time if g2t is None else g2t)
        return sol.with_(trajectory=t2, base_pose=sol.base_pose if base is None else base)

    def kinds(v):
        return {x.constraint for x in v.violations}

    q = tr.q.copy()
    q[60, 1] = 3.0  # joint limit ±2.9671 crossed at one sample
    v = check(task, variant(q=q), ms)
    assert not v.valid and [(x.sample, x.joint) for x in v.violations if x.constraint == "joint.q"] == [(60, 1)]
    g2t = dict(tr.goal2time)
    g2t["2"] -= 0.3  # goal time moved: still on the way
    v = check(task, variant(g2t=g2t), ms)
    assert not v.valid and v.goals["2"] is False and "goal" in kinds(v)
    dq = tr.dq.copy()
    dq[80, 0] = 5.0  # velocity spike: PTP_3 limits q and τ only; the friction torque 15.68·5 + 7.14 > 75.5 Nm
    v = check(task, variant(dq=dq), ms)
    assert not v.valid and any(x.constraint == "joint.tau" and x.sample == 80 for x in v.violations)
    base = np.eye(4)
    base[:3, 3] = [0.2, 0, 0]  # PTP_3's basePlacement has no tolerance (any pose), but the goals move away
    v = check(task, variant(base=base), ms)
    assert not v.valid and "basePlacement" not in kinds(v) and "goal" in kinds(v)
    # with a real base tolerance (±5 cm) the same base pose is a basePlacement violation
    d = json.loads(PTP3.read_text())
    d["constraints"][-1]["pose"].update(toleranceProjection=["x", "y", "z"], tolerance=[[-0.05, 0.05]] * 3)
    (tmp_path / "simple").mkdir()
    (tmp_path / "simple" / "PTP_3.json").write_text(json.dumps(d))
    (tmp_path / "assets").symlink_to(TASKS / "assets")
    strict = load_task(tmp_path / "simple" / "PTP_3.json")
    assert check(strict, sol, ms).valid
    v = check(strict, variant(base=base), ms)
    assert "basePlacement" in kinds(v)


def test_missing_visual_mesh_is_a_warning_missing_collision_mesh_an_error(tmp_path):
    t2 = load_task(TASKS / "simple" / "PTP_2.json")  # its visual DMU_125P.stl is missing on purpose
    assert any("DMU_125P.stl" in w for w in t2.warnings) and len(t2.obstacles[0].collision) == 1
    d = json.loads((TASKS / "simple" / "PTP_2.json").read_text())
    d["obstacles"][0]["collision"][0]["parameters"]["file"] = "assets/nothere.stl"
    (tmp_path / "simple").mkdir()
    f = tmp_path / "simple" / "PTP_2.json"
    f.write_text(json.dumps(d))
    from robodesign import InputError
    with pytest.raises(InputError, match=r"PTP_2.json: obstacles\[0\].collision\[0\].parameters.file: mesh file not found"):
        load_task(f)


class _NoPath:
    path = None
    stats = {"reason": "no_solution"}

    def __bool__(self):
        return False


@pytest.mark.parametrize("planned", [0, 1])
def test_a_plan_failure_counts_the_goals_whose_moves_were_planned(problem, monkeypatch, planned):
    """The search ranks plan failures by how far the plan got: goals_reached counts the first goal (the start)
    and every goal whose move was planned before the failing one."""
    from robodesign.design import goal_planner
    real, calls = goal_planner.GoalPlanner._plan, []

    def plan(self, q, target, time_limit, other_goals=()):
        calls.append(1)
        return real(self, q, target, time_limit, other_goals) if len(calls) <= planned else _NoPath()
    monkeypatch.setattr(goal_planner.GoalPlanner, "_plan", plan)
    ev = Evaluator(EvaluatorSpec(problem, seed=0)).evaluate(Candidate(GOOD))
    assert ev.stage == "plan" and "no collision-free path to goal" in ev.message
    assert ev.goals_reached == 1 + planned
    # one goal further is one point better (lower) within the plan stage's band of scores
    assert ev.score == INFEASIBLE + (len(STAGES) - STAGES.index("plan")) * STAGE_PENALTY - (1 + planned)
