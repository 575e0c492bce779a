"""The sweep's conservative advancement asks its sub-step queries through one pair query made per advance (issue 25,
thirteenth round: what a query reads looked up once, not per sub-step). Its answers (the fraction and distance of a
contact, or None) and its query counts equal, bit for bit, the former loop's over :meth:`SweepChecker.distance` on
random IMPROV arms in PTP_3's cell, random steps and pairs (seeded), on the linear motion and on a curved one."""
from __future__ import annotations

import numpy as np
from test_sweep import random_q
from test_sweep_fresh import _improv_robots

from robodesign.model import sweep


def _former(chk, qa, qb, bound, c, free, at=None):
    """SweepChecker._advance as it was: each sub-step through ``distance``."""
    s = 0.0
    for _ in range(chk.max_substeps):
        s += free / bound
        if s >= 1.0:
            return None
        q = qa + s * (qb - qa) if at is None else at(s)
        dist = chk.distance(q, c)
        free = dist - chk.margins[c]
        if free <= chk.tolerance:
            return s, float(dist)
    return s, float(free + chk.margins[c])


def _key(hit):
    return None if hit is None else (np.float64(hit[0]).tobytes(), np.float64(hit[1]).tobytes(), type(hit[0]))


def test_advance_as_the_former_loop():
    rng = np.random.default_rng(41)
    hits = misses = 0
    for robot in _improv_robots(8, 42):
        a, b = sweep.SweepChecker(robot, posed_arms=True), sweep.SweepChecker(robot, posed_arms=True)
        for _ in range(30):
            qa, qb = random_q(robot, rng)[0], random_q(robot, rng)[0]
            bend = rng.normal(0.0, 0.3, robot.dof)
            at = None if rng.random() < 0.5 else (lambda s, qa=qa, qb=qb, bend=bend: qa + s * (qb - qa) +
                                                  s * (1 - s) * bend)
            c = int(rng.integers(len(a.pairs)))
            d0 = a.distance(qa, c)
            assert b.distance(qa, c) == d0
            free = d0 - a.margins[c]
            if free <= 0:
                continue
            bound = np.float64(float(np.abs(qb - qa).sum()) * rng.uniform(0.5, 3.0))
            a.max_substeps = b.max_substeps = int(rng.choice([5, 2000]))
            want, got = _former(a, qa, qb, bound, c, free, at), b._advance(qa, qb, bound, c, free, at)
            assert _key(got) == _key(want) and a.queries == b.queries
            hits += want is not None
            misses += want is None
    assert hits > 20 and misses > 20
