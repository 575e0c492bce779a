"""The torque prefilter's groups and boxes by the compiled kernel (judge.interval_kernel.prefilter_boxes) are the
numpy path's, entry for entry (issue 25): on random motions (one-arc steps, rest, equal samples, huge and
non-finite values) and random sets of steps (all, a window, gaps); and the whole certification of the solved
PTP_3 motion, scaled and nudged, decides every step and joint as with the numpy paths."""
from __future__ import annotations

import numpy as np
import pytest
from test_motion_kernel import _motions, _same_numbers

from robodesign.judge import arc_torques, interval_kernel
from robodesign.judge.arc_torques import certify_arc_torques
from robodesign.judge.motion import StepMotion
from robodesign.judge.quantities import TrajectoryQuantities
from robodesign.model.cell import solution_robot


@pytest.fixture(scope="module")
def kernels():
    assert interval_kernel.warm_up()
    return interval_kernel


def _step_sets(rng, n_steps: int):
    """All steps, a window, a sorted subset with gaps, one step."""
    a = int(rng.integers(0, n_steps))
    b = int(rng.integers(a + 1, n_steps + 1))
    gaps = np.flatnonzero(rng.random(n_steps) < 0.6)
    return [np.arange(n_steps), np.arange(a, b), gaps if len(gaps) else np.array([a]), np.array([a])]


def _numpy_boxes(monkeypatch, m, steps):
    monkeypatch.setattr(arc_torques, "judge_kernels", lambda: None)
    try:
        with np.errstate(all="ignore"):
            return arc_torques._boxes(m, steps)
    finally:
        monkeypatch.undo()


def _flat(boxes) -> list:
    c, Q, V, acc, h, dA, need = boxes
    return [c, Q[0], Q[1], V[0], V[1], acc[0], acc[1], h, dA, need]


def test_boxes_compiled_are_the_numpy_path(kernels, monkeypatch):
    rng = np.random.default_rng(12)
    sets = switching = 0
    for m in _motions(rng, 150):
        for steps in _step_sets(rng, len(m.h)):
            with np.errstate(all="ignore"):
                got = _flat(arc_torques._boxes(m, steps))
            want = _flat(_numpy_boxes(monkeypatch, m, steps))
            for g, w in zip(got, want):
                assert g.dtype == w.dtype and _same_numbers(np.asarray(g, float), np.asarray(w, float))
            sets += 1
            switching += len(want[-1]) > 0
    assert sets == 600 and switching > 100


def _reports_equal(r1, r2) -> bool:
    key = lambda r: ([(v.step, v.joint, v.time, v.value, v.certified_over) for v in r.violations],  # noqa: E731
                     r.pieces, r.evaluations, r.depth)
    return repr(key(r1)) == repr(key(r2))


def test_certification_is_the_same_on_either_path(kernels, monkeypatch, ptp3_solved):
    """certify_arc_torques on the judged motion of the solved PTP_3 arm, its motions made faster (time scaled by
    0.4–0.9: steps over the limit, steps left to the pieces) and nudged (one sample moved), with the limits as they
    are and lowered: the same violations, pieces, evaluations and depth with the kernels and on the numpy paths."""
    task, ms, sol = ptp3_solved
    robot = solution_robot(task, sol, ms)
    tr = sol.trajectory
    rng = np.random.default_rng(13)
    found = 0
    for trial in range(8):
        s = 1.0 if trial == 0 else float(rng.uniform(0.4, 0.9))
        t, q, dq = tr.t * s, tr.q.copy(), tr.dq / s
        if trial % 2 == 1:
            k = int(rng.integers(5, len(t) - 5))
            q[k, int(rng.integers(0, q.shape[1]))] += float(rng.normal(0, 0.05))
        tq = TrajectoryQuantities(robot, t, q, dq, tr.ddq / s ** 2, task, tr.goal2time)
        m = StepMotion.through(tq.t, tq.q, tq.velocities)
        steps = np.arange(len(t) - 1) if trial % 3 else np.arange(int(rng.integers(0, 100)), len(t) - 1)
        for lim in (robot.tau_max * (1 + 1e-9), robot.tau_max * rng.uniform(0.3, 1.0, robot.dof)):
            with np.errstate(all="ignore"):
                got = certify_arc_torques(robot, m, tq.external_wrenches, steps, lim)
            monkeypatch.setattr(arc_torques, "judge_kernels", lambda: None)
            with np.errstate(all="ignore"):
                want = certify_arc_torques(robot, m, tq.external_wrenches, steps, lim)
            monkeypatch.undo()
            assert _reports_equal(got, want)
            found += len(want.violations) > 0
    assert found >= 4
