"""In-process A/B of judge.check on the good arm's PTP_3 solutions (5 study seeds): the session start's interval
RNEA kernel (base_s7's interval_kernel.py: every row with its rate fields) against this checkout's (the mass-matrix
columns value-only), alternating; the verdicts must be equal. Also times the kernel call alone on the check's
rates_and_mass_bound rows. usage: --src CHECKOUT --base BASE_CHECKOUT"""
import importlib.util
import sys
import time

src = sys.argv[sys.argv.index("--src") + 1]
base = sys.argv[sys.argv.index("--base") + 1]
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
from robodesign.judge import checker as ck  # noqa: E402
from robodesign.judge import interval_kernel, interval_rnea  # noqa: E402

S = "/work/shared/cobra"
p = Problem.build(f"{S}/tasks/simple/PTP_3.json", f"{S}/modules/IMPROV", "cyc")
sols = []
orig = sv.check
sv.check = lambda task, sol, ms, **kw: (sols.append((task, sol, ms, kw)), orig(task, sol, ms, **kw))[1]
for s in range(5):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(("1", "21", "4", "22", "5", "23", "12")))
sv.check = orig
spec = importlib.util.spec_from_file_location("base_interval_kernel", f"{base}/src/robodesign/judge/interval_kernel.py")
bk = importlib.util.module_from_spec(spec)
sys.modules["base_interval_kernel"] = bk
spec.loader.exec_module(bk)
bk.warm_up()
interval_kernel.warm_up()


class BaseKernel:
    """base_s7's kernel: every row with its rate fields (the new nrates argument dropped)."""
    @staticmethod
    def link_torques(*args):
        return bk.link_torques(*args[:-1])


calls = []
new_compiled = interval_rnea.IntervalDynamics._compiled


def spy(self, kernel, Q, V, a, gravity, nrates):
    calls.append((self, Q, V, a, gravity, nrates))
    return new_compiled(self, kernel, Q, V, a, gravity, nrates)


import gc  # noqa: E402
gc.freeze()


def side(which):
    interval_rnea._kernel = (lambda: BaseKernel) if which == "base" else (lambda: interval_kernel)


def run():
    return [ck.check(a[0], a[1], a[2], **a[3]) for a in sols]


verdicts = {}
for which in ("base", "new"):
    side(which)
    verdicts[which] = [(str(v.violations), v.costs, v.cost) for v in run()]
assert verdicts["base"] == verdicts["new"]
interval_rnea.IntervalDynamics._compiled = spy
run()
interval_rnea.IntervalDynamics._compiled = new_compiled
print("kernel calls per check", len(calls) / len(sols), "rows", [len(c[3][0]) for c in calls[:3]],
      "rate rows", [c[5] for c in calls[:3]])
ta, tb, ka, kb = [], [], [], []
for rep in range(9):
    for lst, kl, which in ((ta, ka, "base"), (tb, kb, "new")):
        side(which)
        t = time.process_time()
        for _ in range(4):
            run()
        lst.append((time.process_time() - t) / (4 * len(sols)) * 1e3)
        k = interval_rnea._kernel()
        t = time.process_time()
        for _ in range(4):
            for c in calls:
                new_compiled(c[0], k, *c[1:])
        kl.append((time.process_time() - t) / (4 * len(sols)) * 1e3)
for name, a, b in (("check", ta, tb), ("interval kernel per check", ka, kb)):
    r = np.array(a) / np.array(b)
    print(f"{name} ms CPU (median of 9 alternating rounds, 20 checks each): base {np.median(a):.3f}, "
          f"new {np.median(b):.3f}; per-round ratio base/new median {np.median(r):.3f} (min {r.min():.3f}, "
          f"max {r.max():.3f})")
    print("  base rounds", np.round(a, 3).tolist())
    print("  new rounds ", np.round(b, 3).tolist())
