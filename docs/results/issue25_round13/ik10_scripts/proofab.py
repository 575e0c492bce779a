"""In one process: the proofs made in two passes over the 23 feasible arms, each timed with the old code (a copy of
71594ba's chain_clears and _PairDistance) and the new (src), alternating, CPU seconds."""
import sys, time, pickle
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments"); sys.path.insert(0, src + "/tests")
sys.argv[1:] = ["--src", src]
import numpy as np, coal
from profile_evaluator import SHARED
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
import robodesign.model.pair_clearance as PC
from test_pair_proof_fast import plain_clears
ik_kernel.warm_up(); warm_up()
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
feas = pickle.load(open("/tmp/s11/feas.pkl", "rb"))
CASES = []
orig = PC.chain_clears
def cc(distance, arms, limit, budget=PC.BUDGET):
    CASES.append((distance.a, distance.b, distance.Pb, distance.links, arms, limit))
    return orig(distance, arms, limit, budget)
PC.chain_clears = cc
ev = Evaluator(EvaluatorSpec(ptp3, seed=1))
for rep in range(2):
    for c in feas: ev.evaluate(c)
PC.chain_clears = orig
def old_distance(a, b, Pb, links):
    Ta = coal.Transform3s(np.eye(3), np.zeros(3)); req, res = coal.DistanceRequest(), coal.DistanceResult()
    def f(angles):
        T = PC.chain_poses(links, angles) @ Pb
        out = np.empty(len(T))
        for n, P in enumerate(T):
            res.clear()
            out[n] = coal.distance(a, Ta, b, coal.Transform3s(P[:3, :3].copy(), P[:3, 3].copy()), req, res)
        return out
    return f
def run_old():
    return [plain_clears(old_distance(a, b, Pb, links), arms, lim) for a, b, Pb, links, arms, lim in CASES]
def run_new():
    return [PC.chain_clears(PC._PairDistance(a, np.eye(4), b, Pb, links), arms, lim) for a, b, Pb, links, arms, lim in CASES]
assert run_old() == run_new()
print("proofs", len(CASES), "proven", sum(run_new()))
for r in range(3):
    for name, f in (("old", run_old), ("new", run_new)):
        t = time.process_time(); f(); dt = time.process_time() - t
        print(f"round {r} {name}: {dt:.3f} s CPU ({dt / 23 * 1e3:.1f} ms per arm)")
import cProfile, pstats
p = cProfile.Profile(); p.enable(); run_new(); p.disable()
st = pstats.Stats(p); st.sort_stats("tottime"); st.print_stats(15)
