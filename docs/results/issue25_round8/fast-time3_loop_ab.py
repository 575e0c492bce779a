"""Time scaling in a tight loop: the time_parameterize calls of 20 good-arm PTP_3 evaluations (captured from the
evaluator of the checkout under test), replayed 20 times; prints ms CPU per call and a hash of every trajectory
(t, q, dq, ddq bytes). Run per checkout, alternating, from /work/main:

    PYTHONPATH=<checkout>/src OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock .venv/bin/python <this file>
"""
import hashlib
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fast_time3_capture import capture  # noqa: E402

from robodesign.solvers import timing  # noqa: E402

calls = capture(20)
h = hashlib.sha256()
for r, P, kw in calls:
    tr = timing.time_parameterize(r, P, **kw)
    for x in (tr.t, tr.q, tr.dq, tr.ddq):
        h.update(x.tobytes())
t0 = time.process_time()
for _ in range(20):
    for r, P, kw in calls:
        timing.time_parameterize(r, P, **kw)
print(f"{timing.__file__}: {len(calls)} calls, ms CPU per call {(time.process_time() - t0) / (20 * len(calls)) * 1e3:.3f}, "
      f"trajectories {h.hexdigest()[:12]}")
