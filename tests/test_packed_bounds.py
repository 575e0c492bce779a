"""The collision bounds on packed arguments (geometry_kernel.pack, survivors_packed, which CollisionCuller.in_collision
calls): pack's views are the arguments and share the packed arrays' memory, the kernel reads the same arrays in the
same order, and on real cells (PTP_3's mesh, boxes around the arm) its outputs equal those of survivors on the
separate arrays state by state, while the culler's verdicts equal coal's over every pair."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV, TASKS, boxes_around

from robodesign.formats.assembly import Assembly
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.model import geometry_kernel
from robodesign.model.cell import build_robot
from robodesign.model.collision_cull import CollisionCuller
from robodesign.solvers.schedule import static_cell

pytestmark = pytest.mark.skipif(not geometry_kernel.available(), reason="numba unavailable or ROBODESIGN_JIT=0")

ORDERS = [("1", "21", "4", "22", "5", "23", "12"), ("1", "22", "7", "29", "4", "21", "16")]


def random_args(rng):
    """survivors' arguments after q with random sizes (some zero) and random values."""
    J, G, S, U, P, O = (int(x) for x in rng.integers(0, 6, 6))
    J, G = J + 1, G + 1
    shapes = {0: (J,), 1: (J, 3, 3), 2: (J, 3), 3: (J,), 4: (J, 3), 5: (J,), 6: (G,), 7: (G, 3), 8: (S,), 9: (S,),
              10: (S,), 11: (S,), 12: (G + 1,), 13: (U, 3), 14: (U,), 15: (S,), 16: (P,), 17: (P,), 18: (P,),
              19: (P,), 20: (O, 3, 3), 21: (O, 3), 22: (O, 3), 23: (O, 3), 24: (O, 3), 25: (O, 3), 26: (O,),
              28: (int(rng.integers(0, 9)),), 29: (int(rng.integers(0, 9)),), 30: (J + 1, 3, 3), 31: (J + 1, 3),
              32: (G, 3), 33: (int(rng.integers(1, 9)),), 34: (P + 1,)}
    args = []
    for k in range(35):
        if k == 27:
            args.append(float(rng.uniform(0.01, 0.1)))
        elif k in geometry_kernel._INTS:
            args.append(rng.integers(-1000, 1000, shapes[k]).astype(np.int64))
        elif k == 29:
            args.append(rng.random(shapes[k]) < 0.5)
        else:
            args.append(rng.normal(0.0, 1.0, shapes[k]))
    return tuple(args)


def test_the_views_are_the_arguments_and_the_kernel_reads_them_in_order():
    rng = np.random.default_rng(5)
    for _ in range(60):
        args = random_args(rng)
        (I, F, grid, active), views = geometry_kernel.pack(args)
        assert grid is args[28] and active is args[29] and views[28] is grid and views[29] is active
        assert views[27] == args[27]
        for k in [*geometry_kernel._INTS, *geometry_kernel._FLOATS]:
            if k != 27:
                assert views[k].dtype == args[k].dtype and views[k].shape == args[k].shape
                assert np.array_equal(views[k], args[k]) and views[k].flags.c_contiguous
                assert views[k].size == 0 or np.shares_memory(views[k], I if k in geometry_kernel._INTS else F)
        ints = geometry_kernel._int_views(I)
        floats = geometry_kernel._float_views(F, I)
        for k, a in zip(geometry_kernel._INTS, ints):
            assert a.shape == views[k].shape and np.array_equal(a, views[k])
        for k, a in zip(geometry_kernel._FLOATS, floats):
            assert a == views[k] if k == 27 else (a.shape == views[k].shape and np.array_equal(a, views[k]))


def robots():
    """Two arms in the PTP_3 cell and in a cell of boxes around them."""
    assert geometry_kernel.warm_up() and geometry_kernel.ready()
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    for i, order in enumerate(ORDERS):
        robot = build_robot(static_cell(task), ms, Assembly.from_order(ms, order), task.nominal_base_pose)
        yield robot
        robot.set_obstacles(boxes_around(robot, 40 + i), safety_margin=0.01)
        yield robot


def test_the_packed_kernel_equals_the_separate_one_and_the_verdicts_coals():
    rng = np.random.default_rng(11)
    checked = 0
    for robot in robots():
        c = CollisionCuller(robot)
        args, _, packed = c._kernel_args()
        separate = [np.array(a) if isinstance(a, np.ndarray) else a for a in args]
        separate[28], separate[29] = args[28], args[29]    # the grid and the active flags: the same objects
        Q = np.array([robot.random_configuration(rng) for _ in range(150)])
        Q = np.vstack([Q, Q + rng.normal(0.0, 0.05, Q.shape)])
        verdicts = []
        for q in Q:
            n, nu, proven = geometry_kernel.survivors(q, *separate)
            assert geometry_kernel.survivors_packed(q, *packed) == (n, nu, proven)
            assert np.array_equal(args[-2][:n], separate[-2][:n]) and np.array_equal(args[-1][:nu], separate[-1][:nu])
            verdicts.append(c.in_collision(q))
            checked += n
        ref = [bool(pin.computeCollisions(robot.model, robot.data, robot.geom_model, robot.geom_data, q, True))
               for q in Q]
        assert verdicts == ref and any(ref) and not all(ref)
    assert checked > 1000
