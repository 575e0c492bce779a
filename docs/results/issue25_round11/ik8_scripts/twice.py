"""The stream; each feasible candidate evaluated a second time right after: IK stage ms first vs again, and
time spent in instrumented pieces during the first IK stage."""
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
from robodesign.model import collision_cull as cc, inner_spheres as isp, pair_clearance as pc, robot_geometry as rg
ik_kernel.warm_up(); warm_up()
from robodesign.model import geometry_kernel; geometry_kernel.ready()
acc = collections.Counter()
def wrap(obj, name, tag):
    f = getattr(obj, name)
    def g(*a, **k):
        t = time.perf_counter()
        try: return f(*a, **k)
        finally: acc[tag] += time.perf_counter() - t
    setattr(obj, name, g)
wrap(cc.CollisionCuller, "__init__", "culler_init")
wrap(cc.CollisionCuller, "_kernel_args", "kernel_args")
wrap(cc.CollisionCuller, "_due", "due")
wrap(cc.DistanceField, "fill", "fill")
wrap(cc.CollisionCuller, "_ask", "ask")
wrap(cc.CollisionCuller, "in_collision", "cull_in_coll")
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
ev = Evaluator(EvaluatorSpec(ptp3, seed=0))
rng = np.random.default_rng(0); cands = [ptp3.space.random_candidate(rng) for _ in range(N)]
feas = json.load(open(__file__.rsplit("/", 1)[0] + "/feas.json"))
rows = []
for i, c in enumerate(cands):
    acc.clear()
    e = ev.evaluate(c)
    if i in feas:
        a1 = dict(acc); acc.clear()
        ik1 = [s["seconds"] for s in e.stages if s["name"] == "ik"][0]
        e2 = ev.evaluate(c)
        ik2 = [s["seconds"] for s in e2.stages if s["name"] == "ik"][0]
        rows.append((i, len(c.order), ik1*1e3, ik2*1e3, {k: round(v*1e3, 1) for k, v in a1.items()}, {k: round(v*1e3,1) for k, v in acc.items()}))
for r in rows: print(*r)
print("median ik first", np.median([r[2] for r in rows]), "again", np.median([r[3] for r in rows]))
for k in ["culler_init", "kernel_args", "due", "fill", "ask", "cull_in_coll"]:
    print(k, "median first", np.median([r[4].get(k, 0) for r in rows]), "again", np.median([r[5].get(k, 0) for r in rows]))
