import sys, time, json, collections
src = sys.argv[1]; N = 900
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import SHARED
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel, ik, ik_accept
from robodesign.model import collision_cull as cc, robot_geometry as rg, geometry_kernel
ik_kernel.warm_up(); warm_up(); geometry_kernel.ready()
acc = collections.Counter(); cnt = collections.Counter()
T = time.process_time
def wrap(obj, name, tag):
    f = getattr(obj, name)
    def g(*a, **k):
        t = T()
        try: return f(*a, **k)
        finally: acc[tag] += T() - t; cnt[tag] += 1
    setattr(obj, name, g)
wrap(cc.CollisionCuller, "__init__", "culler_init")
wrap(cc.CollisionCuller, "_kernel_args", "kernel_args")
wrap(cc.CollisionCuller, "_due", "due")
wrap(cc.DistanceField, "fill", "fill")
wrap(cc.CollisionCuller, "_ask", "ask")
wrap(rg.RobotGeometry, "in_collision", "in_coll") if hasattr(rg, "RobotGeometry") else None
wrap(ik_accept.Acceptance, "__call__", "accept")
wrap(ik._Kernel, "batch", "lm_batch")
wrap(ik._Kernel, "repair", "lm_repair")
wrap(ik_accept, "near_any", "near_any")
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
ev = Evaluator(EvaluatorSpec(ptp3, seed=0))
rng = np.random.default_rng(0); cands = [ptp3.space.random_candidate(rng) for _ in range(N)]
feas = json.load(open(__file__.rsplit("/", 1)[0] + "/feas.json"))
rows = []
for i, c in enumerate(cands):
    acc.clear(); cnt.clear()
    e = ev.evaluate(c)
    if i in feas:
        ik1 = [s["seconds"] for s in e.stages if s["name"] == "ik"][0]
        rows.append((i, ik1*1e3, {k: round(v*1e3, 2) for k, v in acc.items()}, dict(cnt)))
for r in rows: print(*r)
print("median ik", np.median([r[1] for r in rows]))
for k in sorted(rows[0][2]):
    print(k, "median ms", np.median([r[2].get(k, 0) for r in rows]), "calls", np.median([r[3].get(k, 0) for r in rows]))
