"""In-process A/B of judge.check on the good arm's PTP_3 solutions (5 study seeds): the session start's TCP twists
(numpy matmul and cross) and sweep kernels (base_s7's sweep_kernel.py) against this checkout's, alternating; the
verdicts must be equal. usage: --src CHECKOUT --base BASE_CHECKOUT"""
import importlib.util
import sys
import time
from functools import cached_property

src = sys.argv[sys.argv.index("--src") + 1]
base = sys.argv[sys.argv.index("--base") + 1]
sys.path.insert(0, src + "/src")
sys.path.insert(0, src + "/tests")
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
from robodesign.judge.quantities import TrajectoryQuantities  # noqa: E402
from robodesign.model import sweep_bounds, sweep_kernel  # noqa: E402
from test_quantities_fast import _former_twists  # noqa: E402

S = "/work/shared/cobra"
p = Problem.build(f"{S}/tasks/simple/PTP_3.json", f"{S}/modules/IMPROV", "cyc")
sols = []
orig = sv.check
sv.check = lambda task, sol, ms, **kw: (sols.append((task, sol, ms, kw)), orig(task, sol, ms, **kw))[1]
for s in range(5):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(("1", "21", "4", "22", "5", "23", "12")))
sv.check = orig
spec = importlib.util.spec_from_file_location("base_sweep_kernel", f"{base}/src/robodesign/model/sweep_kernel.py")
bk = importlib.util.module_from_spec(spec)
sys.modules["base_sweep_kernel"] = bk
spec.loader.exec_module(bk)
bk.warm_up()
new_tw = TrajectoryQuantities.__dict__["tcp_twists"]
old_tw = cached_property(_former_twists)
old_tw.__set_name__(TrajectoryQuantities, "tcp_twists")
import gc  # noqa: E402
gc.freeze()


def side(which):
    sweep_bounds._READY[:] = [bk if which == "base" else sweep_kernel]
    TrajectoryQuantities.tcp_twists = old_tw if which == "base" else new_tw


def run():
    return [ck.check(a[0], a[1], a[2], **a[3]) for a in sols]


sweep_bounds._kernel()
verdicts = {}
for which in ("base", "new"):
    side(which)
    verdicts[which] = [(str(v.violations), v.costs, v.cost) for v in run()]
assert verdicts["base"] == verdicts["new"]
ta, tb = [], []
for rep in range(9):
    for lst, which in ((ta, "base"), (tb, "new")):
        side(which)
        t = time.process_time()
        for _ in range(4):
            run()
        lst.append((time.process_time() - t) / (4 * len(sols)) * 1e3)
r = np.array(ta) / np.array(tb)
print(f"check ms CPU (median of 9 alternating rounds, 20 checks each): base {np.median(ta):.3f}, new {np.median(tb):.3f}; "
      f"per-round ratio base/new median {np.median(r):.3f} (min {r.min():.3f}, max {r.max():.3f})")
print("base rounds", np.round(ta, 3).tolist())
print("new rounds ", np.round(tb, 3).tolist())
