"""Record the certificate kernels' calls of the plan stage on PTP_3's feasible fresh arms (issue 25, round 13, plan8).

Usage: ``python plan8_record_kernels.py CHECKOUT OUT.pkl``: evaluates /tmp/s11/feas.pkl's candidates (the first as
warm-up) and pickles every ``clear_pending`` and ``keep_and_clear`` call's arguments as they were passed (copies),
for plan8_kernel_replay.py."""
import pickle
import sys

src, out = sys.argv[1], sys.argv[2]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
from profile_evaluator import SHARED  # noqa: E402

from robodesign.design.evaluator import Evaluator, EvaluatorSpec  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.solve import warm_up  # noqa: E402
from robodesign.solvers import certificate_kernel, ik_kernel  # noqa: E402

ik_kernel.warm_up(); warm_up(); certificate_kernel.warm_up()
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
feas = pickle.load(open("/tmp/s11/feas.pkl", "rb"))
ev = Evaluator(EvaluatorSpec(ptp3, seed=1))
ev.evaluate(feas[0])
calls = []
for name in ("clear_pending", "keep_and_clear"):
    f = getattr(certificate_kernel, name)

    def w(*a, _f=f, _n=name):
        calls.append((_n, tuple(x.copy() if hasattr(x, "copy") else x for x in a)))
        return _f(*a)
    setattr(certificate_kernel, name, w)
for c in feas[1:]:
    ev.evaluate(c)
pickle.dump(calls, open(out, "wb"))
print(len(calls), "calls", sum(n == "clear_pending" for n, _ in calls), "clear_pending")
