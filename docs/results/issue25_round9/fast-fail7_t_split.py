"""Per IK-failing whitman2020 candidate: total CPU, stage seconds, give_back, gc time, rest."""
import sys, time, gc
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
N = int(sys.argv[2]); fam = sys.argv[3] if len(sys.argv) > 3 else "whitman2020_g5o5"
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import family_tasks
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.model import cell
from robodesign.solvers import ik_kernel
ik_kernel.warm_up(); warm_up()
problem = Problem.build(family_tasks(fam, 1, 0)[0], "robodesign_arm", "cyc")
ev = Evaluator(EvaluatorSpec(problem, seed=0))
rng = np.random.default_rng(0)
cands = [problem.space.random_candidate(rng) for _ in range(N)]
ev.evaluate(cands[0])
acc = {"gb": 0.0, "gc": 0.0}
orig = cell.RobotPool.give_back
def gb(self, r):
    t = time.perf_counter(); orig(self, r); acc["gb"] += time.perf_counter() - t
cell.RobotPool.give_back = gb
gcs = {}
def cb(phase, info):
    if phase == "start": gcs["t"] = time.perf_counter()
    else: acc["gc"] += time.perf_counter() - gcs["t"]
gc.callbacks.append(cb)
rows = []
for c in cands[1:]:
    acc["gb"] = acc["gc"] = 0.0
    t = time.perf_counter(); e = ev.evaluate(c); d = time.perf_counter() - t
    if e.stage == "ik" and not e.feasible:
        st = {s["name"]: s["seconds"] for s in e.stages}
        rows.append((d, st.get("assembly", 0), st.get("base", 0), st.get("reach", 0), st.get("ik", 0), acc["gb"], acc["gc"]))
R = np.array(rows) * 1e3
names = ["total", "assembly", "base", "reach", "ik", "give_back", "gc"]
print(len(R), "failing at ik")
for k, n in enumerate(names):
    print(f"{n:10s} median {np.median(R[:,k]):.3f} mean {np.mean(R[:,k]):.3f}")
rest = R[:,0] - R[:,1:5].sum(1) - R[:,5]
print(f"rest-gb    median {np.median(rest):.3f} mean {np.mean(rest):.3f}")
