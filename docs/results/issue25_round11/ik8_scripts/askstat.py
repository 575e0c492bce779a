import sys, time, json, collections
src = sys.argv[1]; N = 900
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import SHARED
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
from robodesign.model import collision_cull as cc, pair_clearance as pc, geometry_kernel
ik_kernel.warm_up(); warm_up(); geometry_kernel.ready()
st = collections.Counter(); lk = []
f = cc.CollisionCuller._ask
def g(self, q, ks):
    seen = self.__dict__.setdefault("_seen", {})
    for k in ks:
        if k not in seen:
            a, b = int(self.first[k]), int(self.second[k])
            if b >= len(self.parent):
                seen[k] = "obst"
            else:
                objs = self.robot.geom_model.geometryObjects
                ends = [(self.shapes[x], np.array(objs[x].placement.homogeneous), int(self.parent[x])) for x in (a, b)]
                t = time.perf_counter()
                v = pc.never_collides(self.robot.kinematic_model, ends[0], ends[1], float(self.margin[k]) + cc.SLACK, {}, prove=False)
                lk.append(time.perf_counter() - t)
                seen[k] = str(v)
            st["pairs_" + seen[k]] += 1
        st["appear_" + seen[k]] += 1
    n0 = self.narrow
    r = f(self, q, ks)
    # attribute actual asks: first (narrow diff) of the reordered ks
    for k in ks[: self.narrow - n0]:
        st["asked_" + seen[k]] += 1
    return r
cc.CollisionCuller._ask = g
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
ev = Evaluator(EvaluatorSpec(ptp3, seed=0))
rng = np.random.default_rng(0); cands = [ptp3.space.random_candidate(rng) for _ in range(N)]
for i, c in enumerate(cands):
    ev.evaluate(c)
print(dict(st)); print("lookup median us", np.median(lk)*1e6, "n", len(lk))
