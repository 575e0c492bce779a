import sys, time, pickle
src = sys.argv[1]; PA = int(sys.argv[2])
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import SHARED
import robodesign.model.collision_cull as CC
CC.PROVE_AFTER = PA if PA else CC.PROVE_AFTER
if len(sys.argv) > 4: CC.PROVE_NEW = int(sys.argv[4])
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
ik_kernel.warm_up(); warm_up()
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
ev = Evaluator(EvaluatorSpec(ptp3, seed=0))
rng = np.random.default_rng(int(sys.argv[3]) if len(sys.argv) > 3 else 0); cands = [ptp3.space.random_candidate(rng) for _ in range(900)]
st = {}
t0 = time.process_time(); tf = []; sig = []
for c in cands:
    t = time.process_time(); e = ev.evaluate(c); dt = time.process_time() - t
    sig.append((e.stage, e.feasible, round(e.cost, 9) if e.feasible else None))
    if e.feasible:
        tf.append(dt)
        for s_ in e.stages: st.setdefault(s_['name'], []).append(s_['seconds'])
import hashlib
print(f"PA={PA} total cpu s {time.process_time() - t0:.2f} feasible {len(tf)} median feasible ms {np.median(tf)*1e3:.1f} mean {np.mean(tf)*1e3:.1f} sig {hashlib.sha1(repr(sig).encode()).hexdigest()[:10]}")

print("  ".join(f"{k} {np.median(v)*1e3:.1f}" for k, v in st.items()))
