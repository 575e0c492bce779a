"""The graded penalty (issue 21, point 4): an infeasible candidate's score says how far it missed — metres
beyond the reach bound, Nm over the torque limit — so that every optimizer can rank infeasible candidates."""
import json
import math

import numpy as np
import pytest

from robodesign.design.evaluator import (
    INFEASIBLE,
    STAGE_PENALTY,
    Evaluator,
    EvaluatorSpec,
    graded_shortfall,
    score_of,
)
from robodesign.design.problem import Problem
from robodesign.design.search_space import BaseBounds, Candidate
from robodesign.design.solve import STAGES

REACH, TORQUE = STAGES.index("reach"), STAGES.index("static_torque")


def test_score_grades_within_a_stage_and_never_across():
    base = INFEASIBLE + (len(STAGES) - REACH) * STAGE_PENALTY
    assert score_of(False, None, REACH, 0) == base  # no shortfall: the score of earlier releases
    assert score_of(False, None, REACH, 0, 0.1) == pytest.approx(base + 0.5)  # 0.1 m: half-way (scale 0.1 m)
    assert score_of(False, None, REACH, 0, 0.3) == pytest.approx(base + 0.75)
    assert score_of(False, None, TORQUE, 2, 10.0) == pytest.approx(
        INFEASIBLE + (len(STAGES) - TORQUE) * STAGE_PENALTY - 2 + 0.5)
    # monotone in the shortfall, below one goal and below one stage
    s = [score_of(False, None, TORQUE, 1, x) for x in (0.0, 1.0, 10.0, 1e3)]
    assert all(a < b for a, b in zip(s, s[1:]))
    # capped below 1 (resolved at the scores' magnitude, 1e9): never worse than one goal fewer
    assert s[-1] <= score_of(False, None, TORQUE, 1, 1e12) <= score_of(False, None, TORQUE, 1, math.inf) \
        < score_of(False, None, TORQUE, 0)
    assert score_of(False, None, REACH, 0, math.inf) < score_of(False, None, REACH - 1, 0)
    assert graded_shortfall("ik", 5.0) == 0.0 and graded_shortfall("reach", -1.0) == 0.0
    assert score_of(True, 3.5, len(STAGES), 0, 7.0) == 3.5


def _task(path, goal):
    task = {"header": {"ID": "test/one_goal", "version": "2022", "taskName": "one goal", "author": ["tests"],
                       "affiliation": ["robodesign"], "tags": ["test"], "date": "2024-01-01", "timeStepSize": 0.01,
                       "gravity": [0, 0, -9.81]},
            "obstacles": [], "constraints": [{"type": "joint", "parts": ["q", "tau"]}, {"type": "allGoalsFulfilled"}],
            "goals": [{"ID": "g", "type": "reach", "goalPose": {
                "nominal": [[1, 0, 0, goal[0]], [0, 1, 0, goal[1]], [0, 0, 1, goal[2]], [0, 0, 0, 1]],
                "toleranceProjection": ["r_sph"], "tolerance": [[0.0, 0.01]]}}]}
    path.write_text(json.dumps(task))
    return path


def test_reach_shortfall_is_the_metres_missed(tmp_path):
    """Moving the base 0.1 m farther from the goal, along the line from the goal to the first joint, adds
    exactly 0.1 m to the shortfall (and ranks the candidate worse); the search space's reach_shortfall is
    the pipeline's figure."""
    order = ("1", "21", "22", "22", "3", "23", "24", "23", "12")
    problem = Problem.build(_task(tmp_path / "t.json", (3.0, 0.0, 0.5)), "robodesign_arm", "cyc",
                            base_bounds=BaseBounds(lower=(-1.0, 0.0, 0.0, 0.0), upper=(1.0, 0.0, 0.0, 0.0)))
    o, R = problem.space.reach_bound(Candidate(order, (0.0,)))
    ev = Evaluator(EvaluatorSpec(problem))
    near, far = ev(Candidate(order, (0.0,))), ev(Candidate(order, (-0.1,)))
    d = float(np.linalg.norm(np.array([3.0, 0.0, 0.5]) - o))
    assert near.stage == far.stage == "reach"
    assert near.shortfall == pytest.approx(d - R - 0.01, abs=1e-9)
    # the first joint need not lie on the goal's x line: the 0.1 m move along -x adds d_far - d (≈ 0.1 m)
    d_far = float(np.linalg.norm(np.array([3.0, 0.0, 0.5]) - (o - [0.1, 0, 0])))
    assert far.shortfall - near.shortfall == pytest.approx(d_far - d, abs=1e-9) and d_far - d > 0.099
    assert near.score < far.score < near.score + 1
    assert problem.space.reach_shortfall(Candidate(order, (-0.1,))) == pytest.approx(far.shortfall, abs=1e-9)


def test_static_torque_shortfall_is_the_nm_over_the_limit(tmp_path):
    """Small 12 Nm joints at the base holding a long arm out sideways: the candidate stops at static_torque,
    its shortfall is the Nm over the limit (at most what the message reports for the first IK solution) and
    a stronger base joint (87 Nm) gets further."""
    problem = Problem.build(_task(tmp_path / "t.json", (0.9, 0.0, 0.35)), "robodesign_arm", "cyc")
    ev = Evaluator(EvaluatorSpec(problem))
    weak = ev(Candidate(("1", "3", "23", "24", "10", "24", "10", "23", "24", "23", "12")))
    assert weak.stage == "static_torque", weak.message
    needed, limit = (float(x) for x in
                     weak.message.split("needs ")[1].replace(" Nm at joint", "").replace("(limit", "").
                     replace(")", "").split()[::2][:2])
    assert limit == 12.0 and 0 < weak.shortfall <= needed - limit + 0.05
    assert INFEASIBLE + (len(STAGES) - TORQUE) * STAGE_PENALTY - weak.goals_reached < weak.score
    assert problem.space.torque_penalty(weak.candidate.order) == 0.0  # all 12 Nm: a flat profile
    assert problem.space.torque_penalty(("1", "23", "21", "12")) == pytest.approx((87 - 12) / 87)
