"""The record of a build's pair proofs (collision_cull._PROOFS) and when the culler proves: a later robot of the build
does not try again the pairs an earlier one could not prove, proves at once the pairs an earlier one put off, and its
culler gives the verdicts of one without the record (coal's), every pair it switches off proven."""
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
from robodesign.model.collision_cull import SLACK, CollisionCuller
from robodesign.solvers.schedule import static_cell

pytestmark = pytest.mark.skipif(not geometry_kernel.ready() and not geometry_kernel.warm_up(), reason="no kernel")


def _off_pairs_are_proven(c, never_collides=pair_clearance.never_collides) -> int:
    """Every pair culler ``c`` switched off is one ``never_collides`` proves for its robot at its limit; their number."""
    objs = c.robot.geom_model.geometryObjects
    off = np.flatnonzero(~c.active).tolist()
    for k in off:
        a, b = int(c.first[k]), int(c.second[k])
        a_end, b_end = ((objs[g].geometry, np.array(objs[g].placement.homogeneous), int(objs[g].parentJoint)) for g in (a, b))
        assert never_collides(c.robot.kinematic_model, a_end, b_end, float(c.margin[k]) + SLACK)
    return len(off)


@pytest.mark.parametrize("order", [("1", "21", "4", "22", "5", "23", "12"), ("1", "22", "7", "29", "4", "21", "16")])
def test_a_build_tries_each_pair_once_and_decides_the_same(order, monkeypatch):
    """Four robots of one build at nearby base poses: with the build's record their cullers give the verdicts of
    cullers without it (and coal's), every pair they switch off is proven, a pair is proven once, and they ask
    pair_clearance less often than without it. With the record the later robots prove at their 8th ask the pairs the
    first put off; without it only the verdicts kept by pair_clearance serve them."""
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    rng = np.random.default_rng(int(order[1]))
    bases = [task.nominal_base_pose.copy() for _ in range(4)]
    for B in bases[1:]:
        B[:3, 3] += rng.normal(0.0, 0.05, 3)

    def robots():
        return [build_robot(static_cell(task), ms, Assembly.from_order(ms, order), B) for B in bases]
    Q = np.array([robots()[0].random_configuration(rng) for _ in range(400)])
    calls, proofs = [0], [0]
    real, real_proof = pair_clearance.never_collides, pair_clearance.chain_clears

    def counted(*a, **k):
        calls[0] += 1
        return real(*a, **k)

    def proof(*a, **k):
        proofs[0] += 1
        return real_proof(*a, **k)
    monkeypatch.setattr(pair_clearance, "never_collides", counted)
    monkeypatch.setattr(pair_clearance, "chain_clears", proof)
    collision_cull._PROOFS.clear()
    pair_clearance._KNOWN.clear()
    kept, off, put_off = [], [], []
    for robot in robots():
        c = CollisionCuller(robot)
        kept.append([c.in_collision(q) for q in Q])
        off.append(_off_pairs_are_proven(c, real))
        put_off.append(int(c._deferred.sum()))
        base_pairs = sum(int(c.second[k]) < len(c.parent) and c.parent[int(c.first[k])] == 0 for k in range(c.n_pairs))
    kept_calls, calls[0], kept_proofs = calls[0], 0, proofs[0]
    fresh = []
    for robot in robots():   # the reference: every robot's culler with the build's record cleared before it
        collision_cull._PROOFS.clear()
        c = CollisionCuller(robot)
        fresh.append([c.in_collision(q) for q in Q])
        _off_pairs_are_proven(c, real)
    assert kept == fresh
    for robot, verdicts in zip(robots(), kept):
        ref = [bool(pin.computeCollisions(robot.model, robot.data, robot.geom_model, robot.geom_data, q, True))
               for q in Q[:100]]
        assert verdicts[:100] == ref
    assert all(any(v) and not all(v) for v in kept)
    # the first robot puts its proofs off (400 states: no pair is asked PROVE_NEW times), the later ones prove them
    # (each pair put off is tried once in the whole build, pair_clearance's record serving the lookups after it; a pair
    # on the base at another base pose may round to another key there, and be tried again)
    assert off[0] == 0 and min(off[1:]) >= 1 and put_off[0] >= off[1] and put_off[-1] == 0
    assert 1 <= kept_proofs <= sum(put_off) + 3 * base_pairs and calls[0] >= 4 and kept_calls < calls[0]


def test_a_new_pair_is_proven_only_after_many_asks_or_in_the_builds_next_robot(monkeypatch):
    """A fresh build's culler runs no proof before a pair's PROVE_NEW-th ask: at its PROVE_AFTER-th it takes only a
    verdict kept by pair_clearance (another build's proof of the same pair), and puts the proof off; asked PROVE_NEW
    times, the pair is proven. The build's next robot proves the pairs put off at their PROVE_AFTER-th ask."""
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    order = ("1", "21", "4", "22", "5", "23", "12")
    proofs = []
    real = pair_clearance.chain_clears
    monkeypatch.setattr(pair_clearance, "chain_clears", lambda *a, **k: (proofs.append(1), real(*a, **k))[1])
    collision_cull._PROOFS.clear()
    pair_clearance._KNOWN.clear()
    robot = build_robot(static_cell(task), ms, Assembly.from_order(ms, order), task.nominal_base_pose)
    c = CollisionCuller(robot)
    pairs = [k for k in range(c.n_pairs) if c.second[k] < len(c.parent) and c.active[k]]
    q = np.zeros(robot.dof)
    for _ in range(collision_cull.PROVE_AFTER):
        c.collides(q, pairs)
    put_off = np.flatnonzero(c._deferred).tolist()
    assert proofs == [] and c.proven == 0 and len(put_off) >= 5
    assert (c.until_proof[put_off] == collision_cull.PROVE_NEW - collision_cull.PROVE_AFTER).all()
    # the build's next robot: the pairs put off are proven at their PROVE_AFTER-th ask
    second = CollisionCuller(build_robot(static_cell(task), ms, Assembly.from_order(ms, order), task.nominal_base_pose))
    for _ in range(collision_cull.PROVE_AFTER - 1):
        second.collides(q, pairs)
    assert proofs == []
    second.collides(q, pairs)
    assert len(proofs) >= 1 and second.proven >= 1 and _off_pairs_are_proven(second) == second.proven
    # another build (pair_clearance's record kept, the build's cleared): the kept verdicts at the PROVE_AFTER-th ask
    n_proofs = len(proofs)
    collision_cull._PROOFS.clear()
    third = CollisionCuller(build_robot(static_cell(task), ms, Assembly.from_order(ms, order), task.nominal_base_pose))
    for _ in range(collision_cull.PROVE_AFTER):
        third.collides(q, pairs)
    assert len(proofs) == n_proofs and third.proven == second.proven
    # a fresh build asked PROVE_NEW times: its proofs are made then
    pair_clearance._KNOWN.clear()
    collision_cull._PROOFS.clear()
    fourth = CollisionCuller(build_robot(static_cell(task), ms, Assembly.from_order(ms, order), task.nominal_base_pose))
    for i in range(collision_cull.PROVE_NEW):
        assert fourth.proven == 0
        fourth.collides(q, [k for k in pairs if fourth.active[k]])
    assert len(proofs) > n_proofs and fourth.proven == second.proven
