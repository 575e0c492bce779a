"""In-process A/B of plan_path: the planning module of checkout A (--a, default main) and of this checkout, loaded
side by side over the same other modules; the plan_path calls of 10 good-arm PTP_3 evaluations replayed, A and B
alternating; prints ms CPU per call per round and a hash of every path."""
import sys, time, hashlib, importlib.util
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.solve import warm_up; warm_up()
from robodesign.design.problem import Problem
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.search_space import Candidate
from robodesign.solvers import planning
from pathlib import Path
import numpy as np
A = sys.argv[1] if len(sys.argv) > 1 else '/work/main'
spec = importlib.util.spec_from_file_location('planning_a', A + '/src/robodesign/solvers/planning.py')
pa = importlib.util.module_from_spec(spec); sys.modules['planning_a'] = pa; spec.loader.exec_module(pa)
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
def digest(f):
    h = hashlib.sha256()
    for r, a, b, kw in calls:
        res = f(r, a, b, **kw)
        h.update(np.asarray(res.path).tobytes()); h.update(repr(sorted((k, v) for k, v in res.stats.items() if k != 'time')).encode())
    return h.hexdigest()[:12]
print('hash A', digest(pa.plan_path), 'B', digest(orig), flush=True)
def run(f):
    t0 = time.process_time()
    for _ in range(5):
        for r, a, b, kw in calls:
            f(r, a, b, **kw)
    return (time.process_time() - t0) / (5 * len(calls)) * 1e3
ra, rb = [], []
for k in range(int(sys.argv[2]) if len(sys.argv) > 2 else 8):
    a, b = (run(pa.plan_path), run(orig)) if k % 2 == 0 else tuple(reversed((run(orig), run(pa.plan_path))))
    ra.append(a); rb.append(b)
    print(f"round {k}: A {a:.3f} B {b:.3f} ms/call  B/A {b/a:.3f}", flush=True)
print(f"median A {np.median(ra):.3f} B {np.median(rb):.3f} ms/call; median per-round B/A {np.median(np.array(rb)/np.array(ra)):.3f}")
