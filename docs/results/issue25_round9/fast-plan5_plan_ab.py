"""In-process A/B of the plan stage's plan_path calls (10 good-arm PTP_3 evaluations replayed): A with the static
test's gravity bound off (static_validity._robot_bound -> None: the RNEA path, as the session start), B on;
alternating rounds; ms CPU per call and a hash of every path and its stats. Run with PYTHONPATH=<checkout>/src."""
import sys, time, hashlib
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.solve import warm_up; warm_up()
from robodesign.design.problem import Problem
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.search_space import Candidate
from robodesign.solvers import planning, static_validity
from pathlib import Path
import numpy as np
S = Path('/work/shared/cobra')
GOOD = ("1", "21", "4", "22", "5", "23", "12")
p = Problem.build(S/"tasks/simple/PTP_3.json", S/"modules/IMPROV", "cyc")
calls = []
orig = planning.plan_path
def grab(robot, a, b, **kw):
    calls.append((robot, np.array(a), np.array(b), kw)); return orig(robot, a, b, **kw)
planning.plan_path = grab
for s in range(10):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
planning.plan_path = orig
real = static_validity._robot_bound
def side(on):
    static_validity._robot_bound = real if on else (lambda robot: None)
def digest(on):
    side(on)
    h = hashlib.sha256()
    for r, a, b, kw in calls:
        res = orig(r, a, b, **kw)
        h.update(np.asarray(res.path).tobytes()); h.update(repr(sorted((k, v) for k, v in res.stats.items() if k != 'time')).encode())
    return h.hexdigest()[:12]
print('hash A', digest(False), 'B', digest(True), flush=True)
def run(on):
    side(on)
    t0 = time.process_time()
    for _ in range(5):
        for r, a, b, kw in calls:
            orig(r, a, b, **kw)
    return (time.process_time() - t0) / (5 * len(calls)) * 1e3
ra, rb = [], []
for k in range(int(sys.argv[1]) if len(sys.argv) > 1 else 8):
    a, b = (run(False), run(True)) if k % 2 == 0 else tuple(reversed((run(True), run(False))))
    ra.append(a); rb.append(b)
    print(f"round {k}: A {a:.3f} B {b:.3f} ms/call  B/A {b/a:.3f}", flush=True)
print(f"median A {np.median(ra):.3f} B {np.median(rb):.3f} ms/call; median per-round B/A {np.median(np.array(rb)/np.array(ra)):.3f}")
