"""The in_collision queries of 20 good PTP_3 evaluations (recorded), replayed on fresh cullers of the same robots:
CPU µs per query of the whole in_collision (and the cullers' builds), and, unless "plain", of collides and of
_count inside it (their timers add to the whole).
Usage: python fast-ik6_split.py CHECKOUT [plain]"""
import sys
import time

sys.path.insert(0, sys.argv[1] + "/src")
from pathlib import Path  # noqa: E402

from robodesign.design.evaluator import Evaluator, EvaluatorSpec  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.search_space import Candidate  # noqa: E402
from robodesign.design.solve import warm_up  # noqa: E402
from robodesign.model import collision_cull  # noqa: E402
from robodesign.model.collision_cull import CollisionCuller  # noqa: E402

warm_up()
SH = Path("/work/shared/cobra")
p = Problem.build(SH / "tasks/simple/PTP_3.json", SH / "modules/IMPROV", "cyc")
GOOD = ("1", "21", "4", "22", "5", "23", "12")
calls = []
real = CollisionCuller.in_collision


def rec(self, q):
    calls.append((self.robot, q.copy()))
    return real(self, q)


CollisionCuller.in_collision = rec
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
CollisionCuller.in_collision = real
print("queries", len(calls))
tally = {}
for name in () if sys.argv[2:] == ["plain"] else ("collides", "_count"):
    f = getattr(CollisionCuller, name)

    def wrap(*a, _f=f, _n=name):
        t = time.process_time()
        r = _f(*a)
        tally[_n] = tally.get(_n, 0.0) + time.process_time() - t
        return r
    setattr(CollisionCuller, name, wrap)
for r in range(3):
    tally.clear()
    collision_cull._PROOFS.clear()
    cullers = {}
    t = time.process_time()
    for robot, q in calls:
        c = cullers.get(id(robot))
        if c is None:
            c = cullers[id(robot)] = CollisionCuller(robot)
        c.in_collision(q)
    total = time.process_time() - t
    print(f"round {r}: in_collision+build {total / len(calls) * 1e6:.1f} µs/query; "
          + ", ".join(f"{k} {v / len(calls) * 1e6:.1f}" for k, v in tally.items()))
