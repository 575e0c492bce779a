"""Per-part CPU split of judge.check on the good IMPROV arm's 20 PTP_3 solutions (wrappers with process_time on a
few functions; median per check over the rounds). usage: python fast-check7_split.py SRC [reps]"""
import sys
import time

src = sys.argv[1]
reps = int(sys.argv[2]) if len(sys.argv) > 2 else 5
sys.path.insert(0, src + "/src")
import numpy as np  # noqa: E402
from robodesign.solvers import ik_kernel  # noqa: E402
ik_kernel.warm_up()
from robodesign.design.solve import warm_up  # noqa: E402
warm_up()
import robodesign.design.solve as sv  # noqa: E402
from robodesign.design.evaluator import Evaluator, EvaluatorSpec  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.search_space import Candidate  # noqa: E402
from robodesign.judge import checker as ck, quantities as qm, arc_torques as at  # noqa: E402
from robodesign.model import cell as _cell  # noqa: E402
from robodesign.model import sweep as sw  # noqa: E402

S = "/work/shared/cobra"
p = Problem.build(f"{S}/tasks/simple/PTP_3.json", f"{S}/modules/IMPROV", "cyc")
sols = []
orig = sv.check
sv.check = lambda task, sol, ms, **kw: (sols.append((task, sol, ms, kw)), orig(task, sol, ms, **kw))[1]
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(("1", "21", "4", "22", "5", "23", "12")))
sv.check = orig
acc = {}


def timed(mod, name, label, prop=False):
    """Wrap mod.name (a function, or a cached_property's function) to add its CPU time to acc[label]."""
    f = getattr(mod, name)
    inner = f.func if prop else f

    def w(*a, **k):
        t = time.process_time()
        try:
            return inner(*a, **k)
        finally:
            acc[label] = acc.get(label, 0.0) + time.process_time() - t
    if prop:
        f.func = w
    else:
        setattr(mod, name, w)


from robodesign.judge import robots as jr  # noqa: E402
timed(jr, "take", "robot take")
timed(sw.SweepChecker, "__init__", "SweepChecker.__init__")
timed(sw.SweepChecker, "check", "sweep check")
timed(ck, "certify_arc_torques", "arc torques")
TQ = qm.TrajectoryQuantities
for nm in ("link_torques", "_motion_link_sides", "motion_link_torques", "motion", "_witness", "joint_poses",
           "tcp_poses", "tcp_twists", "one_sided_accelerations"):
    timed(TQ.__dict__[nm], None, nm, prop=True) if False else None
for nm in ("link_torques", "_motion_link_sides", "motion_link_torques", "motion", "_witness", "joint_poses",
           "tcp_poses", "tcp_twists", "one_sided_accelerations"):
    cp = TQ.__dict__[nm]
    f0 = cp.func

    def mk(f0, nm):
        def w(self):
            t = time.process_time()
            try:
                return f0(self)
            finally:
                acc[nm] = acc.get(nm, 0.0) + time.process_time() - t
        return w
    cp.func = mk(f0, nm)
timed(ck, "_costs", "costs")
import gc  # noqa: E402
gc.freeze()
for a in sols:
    ck.check(a[0], a[1], a[2], **a[3])
tot = []
per = {}
for r in range(reps):
    acc.clear()
    t = time.process_time()
    for a in sols:
        ck.check(a[0], a[1], a[2], **a[3])
    tot.append((time.process_time() - t) / len(sols) * 1e3)
    for k, v in acc.items():
        per.setdefault(k, []).append(v / len(sols) * 1e3)
print(f"check: median {np.median(tot):.3f} ms per check over {reps} rounds of {len(sols)} ({np.round(tot, 2).tolist()})")
for k, v in sorted(per.items(), key=lambda kv: -np.median(kv[1])):
    print(f"  {k:28s} {np.median(v):.3f} ms")
