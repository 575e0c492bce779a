"""CPU µs per CollisionCuller.in_collision's kernel call on the good PTP_3 arm: the 36-argument survivors against
the packed survivors_packed (same checkout, same states), alternating 5 rounds.
Usage: PYTHONPATH=CHECKOUT/src python fast-ik6_callbench.py"""
import sys
import time

import numpy as np

sys.path.insert(0, "/work/h-fast-ik6/tests")
from conftest import IMPROV, TASKS  # noqa: E402

from robodesign.formats.assembly import Assembly  # noqa: E402
from robodesign.formats.module_io import load_module_set  # noqa: E402
from robodesign.formats.task_io import load_task  # noqa: E402
from robodesign.model import geometry_kernel  # noqa: E402
from robodesign.model.cell import build_robot  # noqa: E402
from robodesign.model.collision_cull import CollisionCuller  # noqa: E402
from robodesign.solvers.schedule import static_cell  # noqa: E402

geometry_kernel.warm_up()
task = load_task(TASKS / "simple" / "PTP_3.json")
ms = load_module_set(IMPROV)
robot = build_robot(static_cell(task), ms, Assembly.from_order(ms, ("1", "21", "4", "22", "5", "23", "12")),
                    task.nominal_base_pose)
c = CollisionCuller(robot)
args, grids, packed = c._kernel_args()
rng = np.random.default_rng(0)
Q = [robot.random_configuration(rng) for _ in range(2000)]
for q in Q:
    c.in_collision(q)   # fill the cells
for r in range(5):
    for name, f, a in (("survivors(36)", geometry_kernel.survivors, args),
                       ("survivors_packed(5)", geometry_kernel.survivors_packed, packed)):
        t = time.process_time()
        for _ in range(5):
            for q in Q:
                f(q, *a)
        print(f"round {r} {name}: {(time.process_time() - t) / (5 * len(Q)) * 1e6:.2f} µs per call")
