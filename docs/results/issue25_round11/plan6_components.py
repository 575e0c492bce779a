"""Component CPU/wall seconds of the planner in the 900-candidate PTP_3 stream (/tmp/s11/fresh_stream.py's), by
wrapping its functions with perf_counter. usage: SRC=<checkout> python plan6_components.py (ask.distances: the
coal distance calls, _certify on the old code, which also keeps the certificate)"""
import sys, time
import os
src = os.environ.get("SRC", "/work/h-plan6")
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
import numpy as np
pc_ = time.perf_counter
from robodesign.solvers import pair_certificates as pc, planning as pl, static_validity as sv
from robodesign.model import collision_cull as cc
T = {}
def wrap(cls, name, key):
    f = getattr(cls, name)
    def w(*a, **k):
        t = pc_(); o = f(*a, **k); T[key] = T.get(key, 0) + pc_() - t; return o
    setattr(cls, name, w)
wrap(pc.PairCertificates, "ask", "ask"); wrap(pc.PairCertificates, "_distances" if hasattr(pc.PairCertificates, "_distances") else "_certify", "ask.distances")
wrap(pc.PairCertificates, "pending", "pending"); wrap(cc.CollisionCuller, "survivors", "survivors")
wrap(cc.CollisionCuller, "collides", "collides"); wrap(pl._Memoized, "_chunk_first_invalid", "chunk")
wrap(pl, "plan_path", "plan_path"); wrap(pl, "_plan_ompl", "ompl")
import robodesign.model.rnea_batch as rb
wrap(sv, "rnea_rows", "rnea_rows")
from profile_evaluator import SHARED
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
ik_kernel.warm_up(); warm_up()
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
ev = Evaluator(EvaluatorSpec(ptp3, seed=0))
rng = np.random.default_rng(0); cands = [ptp3.space.random_candidate(rng) for _ in range(900)]
t0 = time.process_time()
for c in cands: ev.evaluate(c)
print("total", time.process_time() - t0)
print("  ".join(f"{k} {v:.3f}" for k, v in T.items()))
