"""A new arm's two sweep set-ups (the planner's ``pair_arms`` and the judge's posed-arm SweepChecker on the static
obstacles) timed on 60 random IMPROV arms of PTP_3 (seeded), CPU ms per arm; argv[1]: checkout root. Run alternately
on two checkouts: ``python check10_setup_ab.py CHECKOUT``."""
import sys
import time

sys.path.insert(0, sys.argv[1] + "/src")
sys.path.insert(0, "/work/main/tests")
import numpy as np  # noqa: E402
from conftest import IMPROV, TASKS  # noqa: E402

from robodesign.design.problem import Problem  # noqa: E402
from robodesign.formats.assembly import Assembly  # noqa: E402
from robodesign.model import sweep  # noqa: E402
from robodesign.model.cell import build_robot  # noqa: E402
from robodesign.model.sweep_kernel import warm_up  # noqa: E402

warm_up()
problem = Problem.build(TASKS / "simple" / "PTP_3.json", IMPROV, "cyc")
ms = problem.module_set
rng = np.random.default_rng(3)
robots = []
for _ in range(60):
    c = problem.space.random_candidate(rng)
    robots.append(build_robot(problem.task, ms, Assembly.from_order(ms, c.order), problem.base_pose(c)))
sweep.SweepChecker(robots[0], posed_arms=True)   # (first-use costs outside the timing)
times = []
for robot in robots[1:]:
    t = time.process_time()
    sweep.pair_arms(robot)
    sweep.SweepChecker(robot, obstacles=list(range(len(robot.obstacles))), posed_arms=True)
    times.append(time.process_time() - t)
print(f"{sys.argv[1]}: two set-ups per new arm, CPU ms median {np.median(times) * 1e3:.3f}, "
      f"mean {np.mean(times) * 1e3:.3f} over {len(times)} arms")
