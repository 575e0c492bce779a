import sys, time, collections
src = sys.argv[1]; n = int(sys.argv[2]) if len(sys.argv) > 2 else 900
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments"); sys.argv[1:] = ["--src", src]
import numpy as np
from typing import Any, cast
from profile_evaluator import SHARED
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel, ik_accept, ik
from robodesign.model import collision_cull as cc, geometry_kernel
ik_kernel.warm_up(); warm_up()
T = collections.Counter(); N = collections.Counter()
pc = time.perf_counter
IN_IK = [False]
def in_collision(self, q):
    t0 = pc()
    args, grids, packed = self._one = self._one or self._kernel_args()
    n, nu, proven, due = cast(Any, geometry_kernel.survivors_packed)(q, *packed, self._last_hit)
    t1 = pc()
    for k in self._due_k[:due].tolist():
        self._due(k)
    t2 = pc()
    if proven >= 0:
        self._last_hit = proven
    hit = proven >= 0 or (bool(n) and self._ask(q, args[-2][:n].tolist()))
    t3 = pc()
    if nu:
        self._fill(grids, args[-1][:nu].copy())
    t4 = pc()
    if IN_IK[0]:
        kind = "proven" if proven >= 0 else ("cleared" if n == 0 else ("askhit" if hit else "askfree"))
        N[kind] += 1; T[kind] += t4 - t0; T[kind+"_kern"] += t1 - t0; T["due"] += t2 - t1; T[kind+"_ask"] += t3 - t2; T["fill"] += t4 - t3
        N["npairs_" + kind] += int(n)
    return hit
cc.CollisionCuller.in_collision = in_collision
orig = ik.solve_ik
def solve_ik(*a, **k):
    IN_IK[0] = True
    t = pc()
    try: return orig(*a, **k)
    finally: IN_IK[0] = False; T["solve_ik"] += pc() - t
ik.solve_ik = solve_ik
import robodesign.design.goal_planner as gp
gp.solve_ik = solve_ik
orig_init = cc.CollisionCuller.__init__
def init(self, r):
    t = pc(); orig_init(self, r); T["cull_init"] += pc() - t; N["cull_init"] += 1
cc.CollisionCuller.__init__ = init
orig_call = ik_accept.Acceptance.__call__
def call(self, q):
    t = pc(); v = orig_call(self, q); T["acc_" + v] += pc() - t; N["acc_" + v] += 1; return v
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
for k in sorted(set(T) | set(N)): print(f"{k:18s} {T[k]*1e3:9.1f} ms  n={N[k]}  per={T[k]/max(N[k],1)*1e6:8.1f} us")
