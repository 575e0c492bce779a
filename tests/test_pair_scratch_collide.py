"""The collision culler's own scratch space (issue 25, round 6): ``model.pair_scratch.PairScratch`` holds just the
pairs asked, and a query on it is the query ``pin.computeCollision`` makes on the robot's whole scratch space: the
same answers, the same placements bit for bit, and the same state of every asked pair's request and result (GJK
guesses, contacts) after the same sequence of queries. The culler asks coal from a robot's first query on, without
making the robot's whole scratch space, with the verdicts of coal asked about every pair; the margins and active
flags it bounds with are those the scratch space has when it is made."""
import warnings

import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV, TASKS, boxes_around

from robodesign.formats.assembly import Assembly, random_serial_order
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.model import geometry_kernel
from robodesign.model.cell import build_robot
from robodesign.model.pair_scratch import PairScratch
from robodesign.model.robot import Robot
from robodesign.solvers.schedule import static_cell

GOOD = ("1", "21", "4", "22", "5", "23", "12")


def ptp3_robot():
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    return build_robot(static_cell(task), ms, Assembly.from_order(ms, GOOD), task.nominal_base_pose)


def random_robots(n, seed):
    """``n`` random robodesign_arm robots (3–7 DoF) at random bases among boxes, with a safety margin."""
    ms = load_module_set("robodesign_arm")
    rng = np.random.default_rng(seed)
    for i in range(n):
        T = np.eye(4)
        T[:3, :3] = pin.exp3(rng.normal(0.0, 0.3, 3))
        T[:3, 3] = rng.uniform(-0.3, 0.3, 3)
        robot = Robot(ms, Assembly.from_order(ms, random_serial_order(ms, rng, dof=int(rng.integers(3, 8)))),
                      base_pose=T)
        robot.set_obstacles(boxes_around(robot, seed * 100 + i, 5), safety_margin=float(rng.choice([0.0, 0.01])))
        yield robot


def saved(x) -> str:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        return x.saveToString()


def replay(robot, Q, rng):
    """The same random pair queries (random subsets in random order, repeats too) on the robot's whole scratch space
    and on a PairScratch; both answers. The placements, every asked pair's final request and the last query's results
    are checked equal."""
    gm, gd = robot.geom_model, robot.geom_data
    sc = PairScratch(gm, robot.request_margins(gd))
    data = robot.model.createData()
    n = len(gm.collisionPairs)
    ref, got, asked = [], [], set()
    for q in Q:
        ks = rng.choice(n, size=int(rng.integers(1, 12)), replace=True).tolist()
        pin.updateGeometryPlacements(robot.model, robot.data, gm, gd, q)
        ref += [pin.computeCollision(gm, gd, k) for k in ks]
        sc.add(ks)
        local = [sc.local[k] for k in ks]
        pin.updateGeometryPlacements(robot.model, data, sc.model, sc.data, q)
        got += [pin.computeCollision(sc.model, sc.data, j) for j in local]
        for g, i in sc._objects.items():
            assert sc.data.oMg[i].homogeneous.tobytes() == gd.oMg[g].homogeneous.tobytes()
        asked |= set(ks)
    for k in sorted(asked):
        j = sc.local[k]
        cp, sp = gm.collisionPairs[k], sc.model.collisionPairs[j]
        objs, sobjs = gm.geometryObjects, sc.model.geometryObjects
        assert (objs[cp.first].name, objs[cp.second].name) == (sobjs[sp.first].name, sobjs[sp.second].name)
        assert saved(sc.data.collisionRequests[j]) == saved(gd.collisionRequests[k])
        if k in ks:   # (asked by the last query: a result lives until the pair is asked again, the model grown)
            assert saved(sc.data.collisionResults[j]) == saved(gd.collisionResults[k])
    return ref, got


def test_the_pair_scratch_answers_and_keeps_the_state_of_the_whole_one():
    rng = np.random.default_rng(3)
    robots = [ptp3_robot(), *random_robots(12, 5)]
    hits = 0
    for robot in robots:
        Q = np.array([robot.random_configuration(rng) for _ in range(25)])
        Q = np.vstack([Q, Q + rng.normal(0.0, 0.02, Q.shape)])   # near states: warm GJK starts
        ref, got = replay(robot, Q, rng)
        assert ref == got
        hits += sum(ref)
    assert hits > 20   # some pairs collide


def test_new_requests_are_those_of_the_robots_scratch_space():
    for robot in [ptp3_robot(), *random_robots(4, 8)]:
        gm, gd = robot.geom_model, robot.geom_data
        sc = PairScratch(gm, robot.request_margins(gd))
        ks = list(range(len(gm.collisionPairs)))[::-1]
        sc.add(ks[:7])
        sc.add(ks)   # made in two steps: the first ones carried over
        local = [sc.local[k] for k in ks[:7] + ks]
        assert local[:7] == local[7:14] == list(range(7)) and sorted(local[7:]) == list(range(len(ks)))
        for k, j in zip(ks, local[7:]):
            assert saved(sc.data.collisionRequests[j]) == saved(gd.collisionRequests[k])


def test_pair_requests_before_the_scratch_space_are_its_own():
    for robot in [ptp3_robot(), *random_robots(4, 9)]:
        m, active = robot.pair_requests()
        assert robot._geom_data is None
        gd = robot.geom_data
        m2, active2 = robot.pair_requests()
        assert np.array_equal(m, m2) and np.array_equal(active, active2) and active.all()
        assert m.tobytes() == np.array([r.security_margin for r in gd.collisionRequests]).tobytes()
        assert m[-1] == robot.safety_margin and (m[:robot.n_self_collision_pairs] == 0.0).all()
        gd.deactivateCollisionPair(2)
        assert not robot.pair_requests()[1][2]


@pytest.mark.skipif(not geometry_kernel.available(), reason="numba unavailable or ROBODESIGN_JIT=0")
def test_the_culler_answers_from_the_first_query_without_the_whole_scratch_space():
    assert geometry_kernel.warm_up() and geometry_kernel.ready()
    rng = np.random.default_rng(11)
    both = 0
    for robot, ref in zip(random_robots(10, 4), random_robots(10, 4)):   # the same robots twice
        Q = np.array([robot.random_configuration(rng) for _ in range(40)])
        verdicts = [robot.in_collision(q) for q in Q]
        assert robot._culler is not None and robot._geom_data is None
        assert verdicts == [bool(pin.computeCollisions(ref.model, ref.data, ref.geom_model, ref.geom_data, q, True))
                            for q in Q]
        both += 0 < sum(verdicts) < len(Q)
    assert both >= 3
