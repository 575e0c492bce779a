"""In one process, alternating: the in_collision queries of 20 good PTP_3 evaluations (recorded) replayed on fresh
cullers of the same robots, with CollisionCuller (the packed kernel counting the asks) and with tests/
test_packed_bounds.DictCounting (the path before this branch re-created: the 36-argument kernel, the asks counted per
pair in a dictionary); the distance fields and build proofs cleared before each replay. CPU µs per query.
Usage: python fast-ik6_inproc_ab.py CHECKOUT [rounds]"""
import statistics
import sys
import time

sys.path.insert(0, sys.argv[1] + "/src")
sys.path.insert(0, sys.argv[1] + "/tests")
from pathlib import Path  # noqa: E402

from test_packed_bounds import DictCounting  # noqa: E402

from robodesign.design.evaluator import Evaluator, EvaluatorSpec  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.search_space import Candidate  # noqa: E402
from robodesign.design.solve import warm_up  # noqa: E402
from robodesign.model import collision_cull  # noqa: E402
from robodesign.model.collision_cull import CollisionCuller  # noqa: E402

warm_up()
SH = Path("/work/shared/cobra")
p = Problem.build(SH / "tasks/simple/PTP_3.json", SH / "modules/IMPROV", "cyc")
calls = []
real = CollisionCuller.in_collision


def rec(self, q):
    calls.append((self.robot, q.copy()))
    return real(self, q)


CollisionCuller.in_collision = rec
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(("1", "21", "4", "22", "5", "23", "12")))
CollisionCuller.in_collision = real


def replay(kind):
    """CPU µs per query, the verdicts and the narrow-phase asks of one replay with cullers of class ``kind``."""
    for record in (collision_cull._PROOFS, collision_cull._FIELDS, collision_cull._BOUNDS):
        record.clear()
    cullers, verdicts = {}, []
    t = time.process_time()
    for robot, q in calls:
        c = cullers.get(id(robot))
        if c is None:
            c = cullers[id(robot)] = kind(robot)
        verdicts.append(c.in_collision(q))
    return (time.process_time() - t) / len(calls) * 1e6, verdicts, sum(c.narrow for c in cullers.values())


times = {CollisionCuller: [], DictCounting: []}
ref = None
for r in range(int(sys.argv[2]) if len(sys.argv) > 2 else 7):
    for kind in (DictCounting, CollisionCuller) if r % 2 else (CollisionCuller, DictCounting):
        us, v, narrow = replay(kind)
        assert ref is None or (v, narrow) == ref
        ref = (v, narrow)
        times[kind].append(us)
print(f"queries {len(calls)}, colliding {sum(ref[0])}, narrow-phase asks {ref[1]} (the same in every replay)")
for kind, ts in times.items():
    print(f"{kind.__name__}: median {statistics.median(ts):.2f} µs/query; rounds " + " ".join(f"{t:.2f}" for t in ts))
ratio = [b / a for a, b in zip(times[DictCounting], times[CollisionCuller])]
print(f"new/old per round: median {statistics.median(ratio):.3f}; " + " ".join(f"{x:.3f}" for x in ratio))
