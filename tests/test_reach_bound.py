"""The module set's reach bound (robodesign.design.reach) against brute force, and the out-of-reach proof.

* per module: the bound of one revolute joint's connector distance is the maximum over a fine sweep of q;
* per set: the dynamic programme's maximum equals the largest sum of module extents over every valid order
  enumerated by SearchSpace (toy set, geometric primitives, IMPROV with small module counts), and no TCP of
  any enumerated order, over random and locally maximised configurations, is farther from its base than it;
* the proof: hand-computed figures for a fixed base, a base box, a free base (spread of two goals).
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import IMPROV, PRIMITIVES, toy_module_set

from robodesign.design.diagnosis import diagnose, torque_shortfall
from robodesign.design.problem import Problem
from robodesign.design.reach import distance_to_region, reach_proof, set_reach
from robodesign.model.extent import connector_distance_bound, module_extent
from robodesign.design.search_space import SearchSpace
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.model.robot import Robot

SMALL = {  # (set, rules): every valid order is enumerated
    "toy3": ("toy", dict(min_dof=1, max_dof=3)),
    "primitives": (PRIMITIVES, dict(min_dof=1, max_dof=3, max_modules=6)),
    "improv": (IMPROV, dict(min_dof=1, max_dof=3, max_modules=6)),
    "improv_links": (IMPROV, dict(min_dof=2, max_dof=2, max_links_between=2, max_modules=6)),
}


def _set(ref, tmp_path):
    return load_module_set(toy_module_set(tmp_path) if ref == "toy" else ref)


def _rz(a):
    c, s = math.cos(a), math.sin(a)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    return T


def test_one_revolute_joint_is_exact_against_a_sweep():
    """Each one-joint module of IMPROV and the primitives: the bound equals the largest connector distance over
    q ∈ [−π, π] (3,601 samples), computed from the module's own poses."""
    for ref in (IMPROV, PRIMITIVES):
        ms = load_module_set(ref)
        for m in ms:
            if len(m.joints) != 1 or m.joints[0].type != "revolute":
                continue
            j = m.joints[0]
            for a in m.connectors:
                for b in m.connectors:
                    if a.id >= b.id:
                        continue
                    if {a.body_id, b.body_id} != {j.parent, j.child}:
                        continue
                    pa_body, pb_body = (a, b) if a.body_id == j.parent else (b, a)
                    p = pa_body.pose[:3, 3]
                    sweep = max(float(np.linalg.norm((j.pose_parent @ _rz(q) @ j.pose_child @ pb_body.pose)[:3, 3] - p))
                                for q in np.linspace(-math.pi, math.pi, 3601))
                    assert connector_distance_bound(m, a.id, b.id) == pytest.approx(sweep, abs=2e-6), (m.id, a.id, b.id)


def test_toy_bound_by_hand(tmp_path):
    # base 0.1 (base connector → flange), joint 0.05 + 0.2 on either side of a perpendicular axis, eef 0.1
    ms = _set("toy", tmp_path)
    assert module_extent(ms["B"]) == pytest.approx(0.1)
    assert module_extent(ms["J"]) == pytest.approx(0.25)
    assert module_extent(ms["E"]) == pytest.approx(0.1)
    for k in (1, 2, 3):
        r = set_reach(SearchSpace(ms, min_dof=1, max_dof=k))
        assert r.bound == pytest.approx(0.2 + 0.25 * k)
        assert r.order == ("B",) + ("J",) * k + ("E",)
        robot = Robot.from_order(ms, r.order)
        assert np.linalg.norm(robot.fk(np.zeros(k))[:3, 3]) == pytest.approx(r.bound)  # straight: the bound is met


@pytest.mark.parametrize("name", list(SMALL))
def test_dynamic_programme_equals_brute_force_over_all_orders(name, tmp_path):
    ref, rules = SMALL[name]
    ms = _set(ref, tmp_path)
    space = SearchSpace(ms, **rules)
    ext = {m.id: module_extent(m) for m in ms}
    orders = list(space.enumerate_orders())
    assert 3 <= len(orders) <= 20000
    sums = {o: sum(ext[m] for m in o) for o in orders}
    r = set_reach(space)
    assert r.bound == pytest.approx(max(sums.values()), abs=1e-12)
    assert space.validate_order(r.order) is None and sums[r.order] == pytest.approx(r.bound)


@pytest.mark.parametrize("name", list(SMALL))
def test_no_reachable_tcp_exceeds_the_bound(name, tmp_path):
    """Random configurations (and a local ascent from the best) of every enumerated order (at most 150, spread
    over the list): the TCP's distance from the base origin never exceeds the order's sum nor the set's bound."""
    ref, rules = SMALL[name]
    ms = _set(ref, tmp_path)
    space = SearchSpace(ms, **rules)
    r = set_reach(space)
    ext = {m.id: module_extent(m) for m in ms}
    orders = list(space.enumerate_orders())
    step = max(1, len(orders) // 150)
    picked = orders[::step] + [r.order]
    rng = np.random.default_rng(0)
    for order in picked:
        robot = Robot.from_order(ms, order)
        lo, hi = np.maximum(robot.q_lower, -math.pi), np.minimum(robot.q_upper, math.pi)
        dist = lambda q: float(np.linalg.norm(robot.fk(q)[:3, 3]))  # noqa: E731 - base pose = identity
        Q = rng.uniform(lo, hi, size=(60, len(lo)))
        best_q = max(Q, key=dist)
        best = dist(best_q)
        step_size = 0.3
        for _ in range(60):  # coordinate ascent
            improved = False
            for i in range(len(lo)):
                for s in (step_size, -step_size):
                    q = best_q.copy()
                    q[i] = np.clip(q[i] + s, lo[i], hi[i])
                    d = dist(q)
                    if d > best:
                        best, best_q, improved = d, q, True
            if not improved:
                step_size /= 2
        assert best <= sum(ext[m] for m in order) + 1e-9 <= r.bound + 1e-9, order


@pytest.mark.parametrize("name", ["robodesign_arm", "robodesign_heavy"])
def test_builtin_bound_is_met_by_the_straight_longest_arm(name):
    """The built-in sets' modules are straight at q = 0 (elbows aside), so the longest order's TCP at q = 0 is
    exactly the bound away from its base: the bound is tight, not just admissible."""
    ms = load_module_set(name)
    r = set_reach(SearchSpace(ms))
    robot = Robot.from_order(ms, r.order)
    assert robot.fk(np.zeros(6))[2, 3] == pytest.approx(r.bound, abs=1e-9)
    assert r.bound == pytest.approx({"robodesign_arm": 5.422, "robodesign_heavy": 6.645}[name], abs=1e-9)


# -- the proof -------------------------------------------------------------------------------------------------
def reach_task_json(goals, base_tolerance=None, name="t", constraints=()) -> dict:
    """A task with reach goals at ``goals`` (x, y, z; ±1 mm), joint q/τ limits plus ``constraints``, and a
    basePlacement at the origin with ``base_tolerance`` (projection → interval; None: no basePlacement)."""
    cons = [{"type": "joint", "parts": ["q", "tau"]}, *constraints]
    if base_tolerance is not None:
        cons.append({"type": "basePlacement", "pose": {"nominal": np.eye(4).tolist(),
                                                       "toleranceProjection": list(base_tolerance),
                                                       "tolerance": list(base_tolerance.values())}})
    gs = []
    for i, p in enumerate(goals):
        T = np.eye(4)
        T[:3, 3] = p
        gs.append({"ID": f"g{i}", "type": "reach", "goalPose": {
            "nominal": T.tolist(), "toleranceProjection": ["x", "y", "z"], "tolerance": [[-1e-3, 1e-3]] * 3}})
    return {"header": {"ID": f"test/{name}", "version": "2022", "taskName": name, "author": ["t"],
                       "affiliation": ["t"], "email": ["t@t"], "tags": [], "date": "2026-11-26",
                       "timeStepSize": 0.01, "gravity": [0, 0, -9.81]},
            "obstacles": [], "constraints": cons, "goals": gs}


def _task(tmp_path, goals, base_tolerance=None, name="t"):
    data = reach_task_json(goals, base_tolerance, name)
    f = tmp_path / f"{name}.json"
    f.write_text(json.dumps(data))
    return load_task(f)


FIXED = {"x": [-1e-3, 1e-3], "y": [-1e-3, 1e-3], "z": [-1e-3, 1e-3]}
BOX = {"x": [-1.0, 1.0], "y": [-1.0, 1.0], "z": [-1.0, 1.0], "Theta_R": [0, math.pi]}
TOL = math.sqrt(3) * 1e-3  # a goal's ±1 mm box: its farthest point from the nominal


def test_distance_to_a_base_box_by_hand(tmp_path):
    t = _task(tmp_path, [(4.0, 3.0, 0.5)], BOX)
    assert distance_to_region(t.base_placement, (4.0, 3.0, 0.5)) == pytest.approx(math.hypot(3.0, 2.0))
    assert distance_to_region(t.base_placement, (0.5, -0.5, 0.2)) == 0.0


def test_proof_fixed_base_goal_beyond_the_bound(tmp_path):
    ms = load_module_set("robodesign_arm")
    space = SearchSpace(ms)
    R = set_reach(space).bound
    near = _task(tmp_path, [(1.0, 0.0, 0.0), (R - 0.01, 0.0, 0.0)], FIXED, "near")
    assert reach_proof(near, space) is None
    far = _task(tmp_path, [(1.0, 0.0, 0.0), (0.0, R + 0.2, 0.0)], FIXED, "far")
    p = reach_proof(far, space)
    assert p is not None and p.kind == "goal" and p.goals == ("g1",)
    assert p.needed == pytest.approx(R + 0.2 - 1e-3 - TOL, abs=1e-9)  # to the base box face, minus the goal box corner
    assert p.bound == R and "provably out of reach" in p.message


def test_proof_base_box_moves_the_base_towards_the_goal(tmp_path):
    ms = load_module_set("robodesign_heavy")
    space = SearchSpace(ms)
    R = set_reach(space).bound
    # 0.5 m beyond the bound from the origin, but the base may come 1 m closer: no proof
    assert reach_proof(_task(tmp_path, [(R + 0.5, 0, 0)], BOX, "a"), space) is None
    p = reach_proof(_task(tmp_path, [(R + 1.5, 0, 0)], BOX, "b"), space)
    assert p is not None and p.needed == pytest.approx(R + 0.5 - TOL, abs=1e-9)


def test_proof_free_base_needs_the_spread_of_two_goals(tmp_path):
    ms = load_module_set("robodesign_arm")
    space = SearchSpace(ms)
    R = set_reach(space).bound
    # one goal very far away: the base may stand next to it
    assert reach_proof(_task(tmp_path, [(50.0, 0, 0)], None, "one"), space) is None
    # two goals 2R − 0.1 apart: a base halfway reaches both
    assert reach_proof(_task(tmp_path, [(0, 0, 0), (2 * R - 0.1, 0, 0)], None, "close"), space) is None
    p = reach_proof(_task(tmp_path, [(0, 0, 0), (0, 2 * R + 0.4, 0)], None, "apart"), space)
    assert p is not None and p.kind == "spread" and set(p.goals) == {"g0", "g1"}
    assert p.needed == pytest.approx(R + 0.2 - TOL, abs=1e-9) and p.distance == pytest.approx(2 * R + 0.4)


# -- the diagnosis ---------------------------------------------------------------------------------------------
def test_torque_shortfall_parses_both_messages():
    assert torque_shortfall("goal 3: holding the pose needs 129.9 Nm at joint 2 (limit 87.0)") == (129.9, 87.0, 2)
    assert torque_shortfall("follow goal f, pose 4: static torque 15.5 Nm > 12.0 at joint 5") == (15.5, 12.0, 5)
    assert torque_shortfall("goal 3 is 5.343 m from the first joint") is None


def _ev(stage, message="", feasible=False):
    from robodesign.design.solve import STAGES
    return {"feasible": feasible, "stage": stage, "stage_index": STAGES.index(stage) if stage in STAGES else 9,
            "message": message, "cost": 1.0 if feasible else None}


def test_diagnose_each_verdict(tmp_path):
    reachable = _task(tmp_path, [(0.6, 0.0, 0.3)], FIXED, "ok")
    prob = Problem.build(reachable, "robodesign_arm", "cyc")
    evs = [_ev("reach", "goal g0 is ..."), _ev("ik", "no IK"),
           _ev("static_torque", "goal g0: holding the pose needs 129.9 Nm at joint 1 (limit 87.0)"),
           _ev("static_torque", "goal g0: holding the pose needs 101.5 Nm at joint 1 (limit 87.0)")]
    d = diagnose(prob, evs)
    assert d.verdict == "torque" and d.label == "not found"
    assert d.torque_shortfall == pytest.approx(14.5) and d.torque_failures == 2 and d.torque_needed == 101.5
    assert "14.5 Nm short; stronger built-in sets: robodesign_heavy (joints up to 330 Nm; --modules robodesign_heavy)" \
        in d.message
    d = diagnose(prob, evs + [_ev("plan", "no path")])
    assert d.verdict == "not_found" and d.best_stage == "plan" and "ran out of budget" in d.message
    assert diagnose(prob, evs + [_ev("done", feasible=True)]).verdict == "solved"
    R = set_reach(prob.space).bound
    far = Problem.build(_task(tmp_path, [(R + 1.0, 0.0, 0.0)], FIXED, "far"), "robodesign_arm", "cyc")
    d = diagnose(far, [_ev("reach", "goal g0 is far")])
    assert d.verdict == "out_of_reach" and d.label == "provably out of reach"
    assert d.proof.needed == pytest.approx(R + 1.0 - 1e-3 - TOL, abs=1e-9)
    assert d.to_json()["proof"]["bound"] == pytest.approx(R)
