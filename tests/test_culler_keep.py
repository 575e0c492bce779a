"""A robot's collision culler taken up again when its geometry comes back to the state it was made for
(model/culler_keep.py): the same object, restarted as a new one (GJK guesses, counts, last pair), and the same verdicts
as a new culler's and coal's on every state; a geometry in another state gets a new culler."""
from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV, TASKS

from robodesign.formats.assembly import Assembly
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.model import collision_cull, geometry_kernel
from robodesign.model.cell import build_robot
from robodesign.model.collision_cull import PROVE_AFTER, CollisionCuller, culler_of
from robodesign.solvers.schedule import static_cell

pytestmark = pytest.mark.skipif(not geometry_kernel.ready() and not geometry_kernel.warm_up(), reason="no kernel")

ORDERS = [("1", "21", "4", "22", "5", "23", "12"), ("1", "22", "7", "29", "4", "21", "16"),
          ("1", "21", "5", "23", "4", "22", "12")]


def _coal(robot, Q) -> list:
    """coal's verdict of every row of ``Q`` (every pair asked)."""
    return [bool(pin.computeCollisions(robot.model, robot.data, robot.geom_model, robot.geom_data, q, True)) for q in Q]


@pytest.mark.parametrize("order", ORDERS)
def test_a_culler_comes_back_with_its_state_and_decides_as_a_new_one(order):
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    rng = np.random.default_rng(sum(map(int, order)))
    B = task.nominal_base_pose.copy()
    B2 = B.copy()
    B2[:3, 3] += rng.normal(0.0, 0.05, 3)
    robot = build_robot(static_cell(task), ms, Assembly.from_order(ms, order), B)
    Q = np.array([robot.random_configuration(rng) for _ in range(300)])
    first = culler_of(robot)
    before = [robot.in_collision(q) for q in Q]
    assert any(before) and not all(before) and before == _coal(robot, Q)
    robot.set_base_pose(B2)                       # another state: a new culler
    other = culler_of(robot)
    assert other is not first and [robot.in_collision(q) for q in Q[:100]] == _coal(robot, Q[:100])
    robot.set_base_pose(B)                        # back: a new one (only the latest culler is kept)
    assert culler_of(robot) not in (first, other) and [robot.in_collision(q) for q in Q[:100]] == _coal(robot, Q[:100])
    first = culler_of(robot)
    robot.set_base_pose(B2)                       # away without a query, then back: the same one, restarted
    robot.set_base_pose(B)
    again = culler_of(robot)
    assert again is first and again._last_hit == -1 and again.narrow == 0
    assert (again.until_proof == PROVE_AFTER).all() and not again._deferred.any()
    new_request = coal.CollisionRequest()   # a new request's guesses and bound
    assert len(again.scratch.data.collisionRequests) > 0
    for r in again.scratch.data.collisionRequests:
        assert np.array_equal(r.cached_gjk_guess, new_request.cached_gjk_guess)
        assert np.array_equal(r.cached_support_func_guess, new_request.cached_support_func_guess)
        assert r.distance_upper_bound == new_request.distance_upper_bound
    new = CollisionCuller(robot)
    Q2 = np.array([robot.random_configuration(rng) for _ in range(300)])
    kept = [robot.in_collision(q) for q in Q2]
    assert kept == [new.in_collision(q) for q in Q2] == _coal(robot, Q2)
    assert robot._culler is first


def test_another_margin_or_obstacle_pose_gets_a_new_culler():
    """The state holds the pairs' margins and the obstacles' placements: a robot set to another safety margin, or with
    an obstacle moved, gets a new culler (with their verdicts: coal's); moved and back, the kept one again."""
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    rng = np.random.default_rng(5)
    robot = build_robot(static_cell(task), ms, Assembly.from_order(ms, ORDERS[0]), task.nominal_base_pose)
    Q = np.array([robot.random_configuration(rng) for _ in range(100)])
    [robot.in_collision(q) for q in Q]
    first = culler_of(robot)
    pose = np.array(robot.geom_model.geometryObjects[robot.obstacle_geometry_ids[0]].placement.homogeneous)
    moved = pose.copy()
    moved[:3, 3] += 0.3
    robot.move_obstacle(0, moved)                 # moved and back without a query: the same one
    robot.move_obstacle(0, pose)
    assert culler_of(robot) is first and [robot.in_collision(q) for q in Q] == _coal(robot, Q)
    robot.move_obstacle(0, moved)                 # moved: a new one
    assert culler_of(robot) is not first and [robot.in_collision(q) for q in Q] == _coal(robot, Q)
    robot.move_obstacle(0, pose)
    first = culler_of(robot)
    margin = robot.safety_margin
    robot.set_obstacles(robot.obstacles, safety_margin=margin + 0.02)
    c = culler_of(robot)
    assert c is not first and [robot.in_collision(q) for q in Q] == _coal(robot, Q)
    assert collision_cull.culler_of(robot) is c
