"""The collision bounds on packed arguments (geometry_kernel.pack, survivors_packed, which CollisionCuller.in_collision
calls): pack's views are the arguments and share the packed arrays' memory, the kernel reads the same arrays in the
same order, and on real cells (PTP_3's mesh, boxes around the arm) its outputs equal those of survivors on the
separate arrays state by state, while the culler's verdicts equal coal's over every pair; its count of the asks
before a pair's proof takes the same pairs to their proof in the same order as a count per pair in a dictionary
(the culler's before), with the same verdicts, pairs switched off and proofs."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from conftest import IMPROV, TASKS, boxes_around

from robodesign.formats.assembly import Assembly
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.model import collision_cull, geometry_kernel, pair_clearance
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
              10: (S,), 11: (S,), 12: (3 * (G + 1),), 13: (U, 3), 14: (U,), 15: (S,), 16: (P,), 17: (P,), 18: (P,),
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
            left, due = np.zeros(0, np.int64), np.zeros(len(args[-2]), np.int64)
            assert geometry_kernel.survivors_packed(q, *packed[:4], left, due, -1) == (n, nu, proven, 0)
            assert np.array_equal(args[-2][:n], separate[-2][:n]) and np.array_equal(args[-1][:nu], separate[-1][:nu])
            verdicts.append(c.in_collision(q))
            checked += n
        ref = [bool(pin.computeCollisions(robot.model, robot.data, robot.geom_model, robot.geom_data, q, True))
               for q in Q]
        assert verdicts == ref and any(ref) and not all(ref)
    assert checked > 1000


class DictCounting(CollisionCuller):
    """The culler as it counted before: survivors on the separate arrays (and the hull proof of the pair coal found
    colliding last on a separate pack), then per pair in a dictionary (until PROVE_AFTER asks, for a pair whose proof
    was put off there until PROVE_NEW) for every query whose pairs survive, the pairs reaching their count decided
    in that order."""

    def __init__(self, robot):
        super().__init__(robot)
        self.asks = {}   # per pair asked: how often (until its count)
        self.until = {}  # per pair put off: PROVE_NEW

    def in_collision(self, q):
        args, grids, _ = self._one = self._one or self._kernel_args()
        n, nu, proven = geometry_kernel.survivors(q, *args)
        if proven < 0 <= self._last_hit:   # the hull proof on the pair coal found colliding last (a separate pack)
            packed = (*geometry_kernel.pack(args)[0], np.zeros(0, np.int64), np.zeros(self.n_pairs + 1, np.int64))
            proven = geometry_kernel.survivors_packed(q, *packed, self._last_hit)[2]
        ks = args[-2][:n].tolist()
        if self.provable:
            for k in ks:
                c, end = self.asks.get(k, 0) + 1, self.until.get(k, collision_cull.PROVE_AFTER)
                if c <= end:
                    self.asks[k] = c
                    if c == end:
                        was = bool(self._deferred[k])
                        self._due(k)
                        if self._deferred[k] and not was:
                            self.until[k] = collision_cull.PROVE_NEW
        if proven >= 0:
            self._last_hit = proven
        hit = proven >= 0 or (bool(n) and self._ask(q, ks))
        if nu:
            self._fill(grids, args[-1][:nu].copy())
        return hit


@pytest.mark.parametrize("order", ORDERS + [("1", "21", "7", "22", "5", "23", "16")])
def test_the_kernels_count_takes_the_same_pairs_to_their_proof(order, monkeypatch):
    assert geometry_kernel.warm_up() and geometry_kernel.ready()
    task = load_task(TASKS / "simple" / "PTP_3.json")
    ms = load_module_set(IMPROV)
    rng = np.random.default_rng(int(order[2]))
    robot = build_robot(static_cell(task), ms, Assembly.from_order(ms, order), task.nominal_base_pose)
    Q = np.array([robot.random_configuration(rng) for _ in range(200)])
    Q = np.vstack([Q, Q + rng.normal(0.0, 0.05, Q.shape)])
    traces = []
    for kind in (CollisionCuller, DictCounting):
        tried = []
        real = CollisionCuller._due
        monkeypatch.setattr(CollisionCuller, "_due", lambda self, k, _r=real: (tried.append(k), _r(self, k))[1])
        monkeypatch.setattr(collision_cull, "PROVE_NEW", 24)   # (pairs put off at 8 asks reach their proof here)
        for record in (collision_cull._PROOFS, collision_cull._FIELDS, collision_cull._BOUNDS, pair_clearance._KNOWN):
            record.clear()   # (each culler from the same start: no proofs, no distance known in the grid cells)
        c = kind(robot)
        verdicts = [c.in_collision(q) for q in Q]
        traces.append((verdicts, tried, c.active.tolist(), c.proven, c.narrow, c._deferred.tolist()))
        if kind is CollisionCuller:
            ends = np.where(c._deferred, collision_cull.PROVE_NEW, collision_cull.PROVE_AFTER)
            asked = {k: int(e - v) for k, (e, v) in enumerate(zip(ends, c.until_proof)) if v < e}
        monkeypatch.undo()
    assert traces[0] == traces[1] and len(traces[0][1]) >= 3 and traces[0][3] >= 1
    # pairs put off at their 8th ask and decided again at their 24th
    assert sum(traces[0][5]) >= 1 and len(traces[0][1]) > len(set(traces[0][1]))
    assert asked == c.asks and len(asked) >= 10
    ref = [bool(pin.computeCollisions(robot.model, robot.data, robot.geom_model, robot.geom_data, q, True)) for q in Q]
    assert traces[0][0] == ref
