"""cProfile (or timing) of judge.check alone on the good IMPROV arm's 20 PTP_3 solutions (study seeds 0-19).
usage (from /work/main): OPENBLAS_NUM_THREADS=1 .venv/bin/python fast-check7_checkprof.py SRC [sortkey|time] [reps]"""
import sys
import time

src = sys.argv[1]
mode = sys.argv[2] if len(sys.argv) > 2 else "tottime"
reps = int(sys.argv[3]) if len(sys.argv) > 3 else 3
sys.path.insert(0, src + "/src")
import cProfile  # noqa: E402
import pstats  # noqa: E402
import numpy as np  # noqa: E402
from robodesign.solvers import ik_kernel  # noqa: E402
ik_kernel.warm_up()
from robodesign.design.solve import warm_up  # noqa: E402
warm_up()
import robodesign.design.solve as sv  # noqa: E402
from robodesign.design.evaluator import Evaluator, EvaluatorSpec  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.search_space import Candidate  # noqa: E402
from robodesign.judge import checker as ck  # noqa: E402

S = "/work/shared/cobra"
p = Problem.build(f"{S}/tasks/simple/PTP_3.json", f"{S}/modules/IMPROV", "cyc")
sols = []
orig = sv.check
sv.check = lambda task, sol, ms, **kw: (sols.append((task, sol, ms, kw)), orig(task, sol, ms, **kw))[1]
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(("1", "21", "4", "22", "5", "23", "12")))
sv.check = orig
import gc  # noqa: E402
gc.freeze()
for a in sols:
    ck.check(a[0], a[1], a[2], **a[3])
if mode == "time":
    ts = []
    for r in range(reps):
        for a in sols:
            t = time.process_time()
            ck.check(a[0], a[1], a[2], **a[3])
            ts.append(time.process_time() - t)
    print(f"check median {np.median(ts)*1e3:.3f} ms, mean {np.mean(ts)*1e3:.3f} over {len(ts)}")
else:
    pr = cProfile.Profile()
    pr.enable()
    for r in range(reps):
        for a in sols:
            ck.check(a[0], a[1], a[2], **a[3])
    pr.disable()
    pstats.Stats(pr).sort_stats(mode).print_stats(70)
