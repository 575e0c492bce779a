import sys, time
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
N = int(sys.argv[2])
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import family_tasks
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
ik_kernel.warm_up(); warm_up()
problem = Problem.build(family_tasks("whitman2020_g5o5", 1, 0)[0], "robodesign_arm", "cyc")
ev = Evaluator(EvaluatorSpec(problem, seed=0))
rng = np.random.default_rng(0)
cands = [problem.space.random_candidate(rng) for _ in range(N)]
ev.evaluate(cands[0])
rows = []
for c in cands[1:]:
    t = time.process_time(); e = ev.evaluate(c); d = time.process_time() - t
    if e.stage == "ik" and not e.feasible:
        st = {s["name"]: s["seconds"] for s in e.stages}
        rows.append((d, st, e.message[:90], len(c.order)))
rows.sort(key=lambda r: r[0])
m = len(rows)//2
for d, st, msg, n in rows[m-8:m+8]:
    print(f"{d*1e3:.2f}", " ".join(f"{k}={v*1e3:.2f}" for k, v in st.items()), f"sum={sum(st.values())*1e3:.2f}", n, msg)
import collections
print(collections.Counter(r[2].split("(")[-1] for r in rows))
