"""In-process A/B of judge.check on the good IMPROV arm's 20 PTP_3 solutions (study seeds 0-19), branch fast-check5:
side A switches this branch's four kernels off (the numpy paths they replace: TCP twists, the motion's arcs and
extremes, the torque prefilter's whole-step bounds), side B runs them; A and B alternate check by check, so the
machine's swings hit both alike. The verdicts (violations, costs, goals) must be equal.
usage (from /work/main): OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock .venv/bin/python
       docs/results/issue25_round8/fast-check5_check_ab.py SRC [rounds]"""
import sys
import time

src = sys.argv[1]
rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 9
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
from robodesign.judge import arc_torques as at, checker as ck, motion as mo, quantities as qm  # noqa: E402

S = "/work/shared/cobra"
p = Problem.build(f"{S}/tasks/simple/PTP_3.json", f"{S}/modules/IMPROV", "cyc")
sols = []
orig = sv.check
sv.check = lambda task, sol, ms, **kw: (sols.append((task, sol, ms, kw)), orig(task, sol, ms, **kw))[1]
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(("1", "21", "4", "22", "5", "23", "12")))
sv.check = orig
NEW = {"tw": qm._twists_compiled, "mk": mo.judge_kernels}


def set_side(side):
    """A: the numpy paths (the kernels' callers see no kernel); B: this branch."""
    qm._twists_compiled = (lambda *a: None) if side == "A" else NEW["tw"]
    mo.judge_kernels = at.judge_kernels = (lambda: None) if side == "A" else NEW["mk"]


def key(v):
    return (v.valid, str([x.to_json() for x in v.violations]), repr(v.costs), repr(v.cost), v.goals)


import gc  # noqa: E402
gc.freeze()
verd = {}
for side in ("A", "B"):
    set_side(side)
    verd[side] = [key(ck.check(a[0], a[1], a[2], **a[3])) for a in sols]
assert verd["A"] == verd["B"], "verdicts differ"
ta, tb = [], []
for r in range(rounds):
    sa = sb = 0.0
    for rep in range(3):
        for i, a in enumerate(sols):
            for side in (("A", "B") if (i + r + rep) % 2 == 0 else ("B", "A")):
                set_side(side)
                t = time.process_time()
                ck.check(a[0], a[1], a[2], **a[3])
                d = time.process_time() - t
                if side == "A":
                    sa += d
                else:
                    sb += d
    ta.append(sa / (3 * len(sols)) * 1e3)
    tb.append(sb / (3 * len(sols)) * 1e3)
r = np.array(ta) / np.array(tb)
print(f"judge.check, ms CPU per check, median of {rounds} rounds (60 checks per side each, alternating check by check): "
      f"A (numpy paths) {np.median(ta):.3f}, B (kernels) {np.median(tb):.3f}; per-round ratio A/B median "
      f"{np.median(r):.3f} (min {r.min():.3f}, max {r.max():.3f}); verdicts equal")
print("A rounds", np.round(ta, 3).tolist())
print("B rounds", np.round(tb, 3).tolist())
