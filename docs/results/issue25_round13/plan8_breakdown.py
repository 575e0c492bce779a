"""Where the plan stage's time goes on PTP_3's feasible fresh arms (issue 25, round 13, plan8).

Usage: ``python plan8_breakdown.py CHECKOUT [FEAS_PKL]``: evaluates /tmp/s11/feas.pkl's first candidate (warm-up),
then the others once each with one Evaluator, with perf_counter accumulators around the planner's parts; prints per
part the sum over all candidates and the median over candidates (ms), excluding nothing (the heavy arm included),
and the median without OMPL plans."""
import collections
import pickle
import sys
import time

src = sys.argv[1]
feas_pkl = sys.argv[2] if len(sys.argv) > 2 else "/tmp/s11/feas.pkl"
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np  # noqa: E402
from profile_evaluator import SHARED  # noqa: E402

from robodesign.design.evaluator import Evaluator, EvaluatorSpec  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.solve import warm_up  # noqa: E402
from robodesign.model import collision_cull, sweep  # noqa: E402
from robodesign.solvers import ik_kernel, pair_certificates, planning, static_validity  # noqa: E402

ik_kernel.warm_up(); warm_up()
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
feas = pickle.load(open(feas_pkl, "rb"))
ev = Evaluator(EvaluatorSpec(ptp3, seed=1))
ev.evaluate(feas[0])
acc = collections.Counter()
calls = collections.Counter()
on = [0]


def wrap(owner, name, label):
    f = getattr(owner, name)

    def w(*a, **k):
        t = time.perf_counter()
        try:
            return f(*a, **k)
        finally:
            if on[0]:
                acc[label] += time.perf_counter() - t
                calls[label] += 1
    setattr(owner, name, w)


wrap(planning, "plan_path", "plan_path")
wrap(planning, "_plan_ompl", "ompl")
wrap(planning._Memoized, "_chunk_first_invalid", "chunk")
wrap(collision_cull.CollisionCuller, "survivors", "survivors")
wrap(collision_cull.CollisionCuller, "collides", "collides")
wrap(pair_certificates.PairCertificates, "ask", "ask")
wrap(pair_certificates.PairCertificates, "_distances", "distances")
wrap(pair_certificates.PairCertificates, "pending", "pending")
wrap(pair_certificates.PairCertificates, "of", "certs_of")
wrap(static_validity, "rnea_rows", "rnea_rows")
wrap(planning, "_row_keys", "row_keys")
wrap(sweep, "_every_pairs_arms", "every_arms")
wrap(sweep, "_setup", "sweep_setup")
wrap(pair_certificates, "_certified_of", "certified_of")
wrap(planning, "_segment_ok", "segment_ok")
wrap(planning, "_partial_shortcuts", "partial_sc")
per = []
for c in feas[1:]:
    acc.clear()
    on[0] = 1
    ev.evaluate(c)
    on[0] = 0
    per.append(dict(acc))
keys = ["plan_path", "ompl", "chunk", "survivors", "pending", "ask", "distances", "collides", "certs_of", "rnea_rows", "row_keys", "segment_ok", "partial_sc", "every_arms", "sweep_setup", "certified_of"]
print(src)
for k in keys:
    v = np.array([1e3 * p.get(k, 0.0) for p in per])
    print(f"{k:10s} sum {v.sum():8.1f} ms  median {np.median(v):6.2f} ms  calls {calls[k]}")
