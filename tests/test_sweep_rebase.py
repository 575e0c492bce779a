"""The sweep's set-up at another base pose from a robot built alike (model/sweep_rebase.py, issue 25): every
attribute, array for array (dtype, shape, strides, bytes), and the posed arms field by field, equals a fresh
sweep._setup of the robot, over seeded random base poses, several assemblies, with and without the task's
obstacles and for several checker flags; a robot whose base geometry is coaxial with a root joint otherwise
is set up anew."""
from __future__ import annotations

import make_tasks as mt  # assets/tasks, on the path by conftest
import numpy as np
import pytest
from conftest import IMPROV, TASKS
from test_interval_trees import _pose

from robodesign import load_module_set
from robodesign.formats.assembly import Assembly
from robodesign.formats.task_io import load_task
from robodesign.model import sweep, sweep_rebase
from robodesign.model.cell import build_robot
from robodesign.model.sweep_bounds import PosedArms

_ORDERS = [(IMPROV, ("1", "21", "4", "22", "5", "23", "12")), (IMPROV, ("1", "21", "5", "22", "4", "23", "12")),
           (IMPROV, ("1", "4", "22", "5", "23", "12")), ("robodesign_arm", tuple(mt.DEFAULT_ORDER))]
_FLAGS = [(True, True, None, True, True), (True, True, None, True, False), (True, False, None, False, False)]


def _same(a, b) -> bool:
    """Equal values of the same kinds: arrays by dtype, shape, strides and bytes; PosedArms field by field (but
    its robot and motion caches); sequences item by item."""
    if isinstance(a, np.ndarray):
        return (isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape and a.strides == b.strides
                and a.tobytes() == b.tobytes())
    if isinstance(a, PosedArms):
        skip = {"robot", "_gathers", "_last", "_poses"}
        da, db = ({k: v for k, v in vars(x).items() if k not in skip} for x in (a, b))
        return da.keys() == db.keys() and all(_same(da[k], db[k]) for k in da)
    if isinstance(a, (list, tuple)):
        return type(a) is type(b) and len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return type(a) is type(b) and a == b


@pytest.mark.parametrize("name,order", _ORDERS)
def test_a_rebased_setup_is_a_fresh_one(name, order):
    ms = load_module_set(name)
    task = load_task(TASKS / "simple" / "PTP_3.json")
    assembly = Assembly.from_order(ms, order)
    rng = np.random.default_rng(len(order) * 3 + int(order[2]))   # (seeded per assembly)
    taken = 0
    for cell in (task, None):
        for flags in _FLAGS:
            sweep_rebase._KEPT.clear()
            first = build_robot(cell, ms, assembly, _pose(rng))
            sweep_rebase.keep(first, sweep._setup_key(first, flags), sweep._setup(first, *flags))
            for _ in range(4):
                robot = build_robot(cell, ms, assembly, _pose(rng))
                got = sweep_rebase.rebased(robot, sweep._setup_key(robot, flags))
                fresh = sweep._setup(robot, *flags)
                if got is None:   # coaxial otherwise: set up anew (not with these arms)
                    assert sweep_rebase.root_coaxial(robot) != sweep_rebase.root_coaxial(first)
                    continue
                taken += 1
                assert got.keys() == fresh.keys()
                for k in fresh:
                    assert _same(got[k], fresh[k]), k
    assert taken >= 20
    sweep_rebase._KEPT.clear()


def test_a_checker_at_another_base_pose_finds_a_fresh_ones_events(ptp3_solved):
    """End to end: a SweepChecker over a rebased set-up gives a fresh set-up's events and query counts."""
    task, ms, sol = ptp3_solved
    rng = np.random.default_rng(8)
    Q = np.asarray(sol.trajectory.q)
    key = lambda es: [(e.sample, e.s, e.first, e.second, e.distance, e.environment) for e in es]  # noqa: E731
    found = 0
    for _ in range(6):
        T = np.eye(4)
        T[:3, 3] = rng.normal(0.0, 0.05, 3)
        robot = build_robot(task, ms, sol.assembly(ms), T @ np.asarray(sol.base_pose, dtype=float))
        sweep._SETUPS.clear()
        a = sweep.SweepChecker(robot, posed_arms=True)    # rebased (kept from the robot before) but the first
        sweep._SETUPS.clear()
        sweep_rebase._KEPT.clear()
        b = sweep.SweepChecker(robot, posed_arms=True)    # fresh
        ea, eb = a.check(Q, first_only=False), b.check(Q, first_only=False)
        assert key(ea) == key(eb) and a.queries == b.queries
        found += len(ea) + a.queries
    assert found > 0
