"""The record of a build's pair proofs (collision_cull._PROOFS): a later robot of the build does not try again the
pairs an earlier one could not prove, and its culler decides exactly as one without the record (the same verdicts,
the same pairs switched off in the end, as coal's verdicts), while asking pair_clearance far less."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV, TASKS

from robodesign.formats.assembly import Assembly
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.model import collision_cull, geometry_kernel, pair_clearance
from robodesign.model.cell import build_robot
from robodesign.model.collision_cull import CollisionCuller
from robodesign.solvers.schedule import static_cell

pytestmark = pytest.mark.skipif(not geometry_kernel.ready() and not geometry_kernel.warm_up(), reason="no kernel")


def _trace(robots, Q):
    """Per robot (a culler each, in turn): the verdicts of Q, the active flags after them and ``proven``."""
    out = []
    for robot in robots:
        c = CollisionCuller(robot)
        out.append(([c.in_collision(q) for q in Q], c.active.tolist(), c.proven))
    return out


@pytest.mark.parametrize("order", [("1", "21", "4", "22", "5", "23", "12"), ("1", "22", "7", "29", "4", "21", "16")])
def test_a_build_tries_each_pair_once_and_decides_the_same(order, monkeypatch):
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    rng = np.random.default_rng(int(order[1]))
    bases = [task.nominal_base_pose.copy() for _ in range(4)]
    for B in bases[1:]:
        B[:3, 3] += rng.normal(0.0, 0.05, 3)

    def robots():
        return [build_robot(static_cell(task), ms, Assembly.from_order(ms, order), B) for B in bases]
    Q = np.array([robots()[0].random_configuration(rng) for _ in range(400)])
    calls = [0]
    real = pair_clearance.never_collides

    def counted(*a, **k):
        calls[0] += 1
        return real(*a, **k)
    monkeypatch.setattr(pair_clearance, "never_collides", counted)
    collision_cull._PROOFS.clear()
    kept = _trace(robots(), Q)
    kept_calls, calls[0] = calls[0], 0
    fresh = []
    for robot in robots():   # the reference: every robot's culler with the build's record cleared before it
        collision_cull._PROOFS.clear()
        fresh += _trace([robot], Q)
    assert kept == fresh
    for robot, (verdicts, _, _) in zip(robots(), kept):
        ref = [bool(pin.computeCollisions(robot.model, robot.data, robot.geom_model, robot.geom_data, q, True))
               for q in Q[:100]]
        assert verdicts[:100] == ref
    assert all(any(v) and not all(v) for v, _, _ in kept) and kept[0][2] >= 1
    assert calls[0] >= 4 and kept_calls < calls[0] / 2
