"""In-process A/B of judge.check on the good IMPROV arm's 20 PTP_3 solutions (study seeds 0-19), branch fast-check7.
Side A puts back the former code of this branch's four cuts: the prefilter's boxes by numpy (arc_torques._boxes with
the kernel off), both RNEA pools made at a model's first ask (rnea_batch as at 67dfe23), the cost terms computed at
every ask and named_costs built at every call, SweepChecker.subset item by item (as at 67dfe23); side B runs this
branch. A and B alternate check by check, so the
machine's swings hit both alike; the verdicts (violations, costs, goals) must be equal.
usage (from /work/main): OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock .venv/bin/python
       fast-check7_check_ab.py SRC [rounds]"""
import sys
import time

src = sys.argv[1]
rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 9
sys.path.insert(0, src + "/src")
import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402
from robodesign.solvers import ik_kernel  # noqa: E402
ik_kernel.warm_up()
from robodesign.design.solve import warm_up  # noqa: E402
warm_up()
import robodesign.design.solve as sv  # noqa: E402
from robodesign.design.evaluator import Evaluator, EvaluatorSpec  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.search_space import Candidate  # noqa: E402
from robodesign.formats import costs  # noqa: E402
from robodesign.judge import arc_torques as at, checker as ck  # noqa: E402
from robodesign.model import rnea_batch as rb, sweep as sw  # noqa: E402

S = "/work/shared/cobra"
p = Problem.build(f"{S}/tasks/simple/PTP_3.json", f"{S}/modules/IMPROV", "cyc")
sols = []
orig = sv.check
sv.check = lambda task, sol, ms, **kw: (sols.append((task, sol, ms, kw)), orig(task, sol, ms, **kw))[1]
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(("1", "21", "4", "22", "5", "23", "12")))
sv.check = orig

_FORMER_POOLS = {}


def former_pool(model, link_side):
    """rnea_batch._pools as at 67dfe23: both pools made at a model's first ask."""
    hit = _FORMER_POOLS.get(id(model))
    if hit is None or not hit[0] == model:
        if len(_FORMER_POOLS) >= 64:
            _FORMER_POOLS.clear()
        link = pin.Model(model)
        link.armature = np.zeros(model.nv)
        hit = _FORMER_POOLS[id(model)] = (pin.Model(model), pin.ModelPool(model, 1), pin.ModelPool(link, 1))
    return hit[2 if link_side else 1]


def former_named():
    out = {n: costs.CostFunction(((n, 1.0),)) for n in costs._REGISTRY}
    out.update({n: costs.CostFunction(terms, name=n) for n, terms in costs._COMPOUNDS.items()})
    return out


def former_boxes(motion, steps):
    kern = at.judge_kernels
    at.judge_kernels = lambda: None
    try:
        return NEW["boxes"](motion, steps)
    finally:
        at.judge_kernels = kern


def former_subset(self, cols):
    """SweepChecker.subset as at 67dfe23."""
    out = object.__new__(type(self))
    out.__dict__.update(self.__dict__)
    cols = list(cols)
    out.pairs = [self.pairs[c] for c in cols]
    out.W = self.W[:, cols]
    if getattr(self, "_owner", None) is not None:
        out._owner = self._owner[:, cols]
    out.margins, out.is_env = self.margins[cols], self.is_env[cols]
    out.pair_names = [self.pair_names[c] for c in cols]
    if getattr(self, "_mov", None):
        out._mov, out._ref, out._obst = ([x[c] for c in cols] for x in (self._mov, self._ref, self._obst))
    out.queries = 0
    return out


NEW = {"subset": sw.SweepChecker.subset, "pool": rb._pool, "named": ck.named_costs,
       "term": costs.CostContext.term_value, "boxes": at._boxes}


def set_side(side):
    a = side == "A"
    rb._pool = former_pool if a else NEW["pool"]
    ck.named_costs = former_named if a else NEW["named"]
    costs.CostContext.term_value = (lambda self, n: float(costs._REGISTRY[n].fn(self))) if a else NEW["term"]
    at._boxes = former_boxes if a else NEW["boxes"]
    sw.SweepChecker.subset = former_subset if a else NEW["subset"]


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
      f"A (former code) {np.median(ta):.3f}, B (fast-check7) {np.median(tb):.3f}; per-round ratio A/B median "
      f"{np.median(r):.3f} (min {r.min():.3f}, max {r.max():.3f}); verdicts equal")
print("A rounds", np.round(ta, 3).tolist())
print("B rounds", np.round(tb, 3).tolist())
