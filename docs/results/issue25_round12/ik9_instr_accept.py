import sys, time, collections
src = sys.argv[1]; n = int(sys.argv[2]) if len(sys.argv) > 2 else 900
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments"); sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import SHARED
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel, ik_accept, ik
from robodesign.model import collision_cull as cc
import robodesign; print(robodesign.__file__); ik_kernel.warm_up(); warm_up()
T = collections.Counter(); N = collections.Counter()
def wrap(obj, name, key):
    f = getattr(obj, name)
    def w(*a, **k):
        t = time.perf_counter()
        try: return f(*a, **k)
        finally: T[key] += time.perf_counter() - t; N[key] += 1
    setattr(obj, name, w)
wrap(cc.CollisionCuller, "__init__", "cull_init")
wrap(cc.CollisionCuller, "in_collision", "cull_incoll")
wrap(cc.CollisionCuller, "_ask", "cull_ask")
wrap(cc.CollisionCuller, "_due", "cull_due")
wrap(cc.CollisionCuller, "_kernel_args", "cull_kargs")
wrap(ik, "solve_ik", "solve_ik")
from robodesign.model import geometry_kernel as gk
wrap(gk, "survivors_packed", "kernel_surv")
from robodesign.model import robot_geometry as rg
wrap(rg.RobotGeometry if hasattr(rg, "RobotGeometry") else None, "in_collision", "robot_incoll") if hasattr(rg, "RobotGeometry") else None

# idea 1 accounting
orig_call = ik_accept.Acceptance.__call__
def call(self, q):
    st = self.stats
    before = st["rejected_collision"]
    # is it a duplicate (pre-test)? recompute canonical like accept does
    t = time.perf_counter()
    v = orig_call(self, q)
    T["accept"] += time.perf_counter() - t; N["accept"] += 1
    T["acc_" + v] += time.perf_counter() - t; N["acc_" + v] += 1
    N["v_" + v] += 1
    if v in ("duplicate", "collision"):
        # would it be a duplicate? check near_any on raw q (approx)
        if self.sols and ik_accept.near_any(q, self.sols, self.distinct_tol):
            N["dup_tested_" + v] += 1
            if before + 1 <= ik._REPAIR_AFTER: N["dup_deferrable_" + v] += 1
    return v
ik_accept.Acceptance.__call__ = call
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
ev = Evaluator(EvaluatorSpec(ptp3, seed=0))
rng = np.random.default_rng(0)
cands = [ptp3.space.random_candidate(rng) for _ in range(n)]
t0 = time.process_time(); st = collections.Counter()
for c in cands:
    e = ev.evaluate(c)
    for s in e.stages: st[s["name"]] += s["seconds"]
print("cpu", time.process_time() - t0)
print("stages", {k: round(v, 3) for k, v in st.items()})
for k in sorted(T): print(f"{k:14s} {T[k]*1e3:9.1f} ms  n={N[k]}  per={T[k]/N[k]*1e6:8.1f} us")
for k in sorted(N):
    if k not in T: print(k, N[k])
