"""In-flow mean µs per failing-at-IK candidate of wrapped functions (module:attr.path), whitman2020 profile task."""
import sys, time, gc, importlib, functools
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
N = int(sys.argv[2]); targets = sys.argv[3].split(",")
fam = sys.argv[4] if len(sys.argv) > 4 else "whitman2020_g5o5"
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import family_tasks
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
ik_kernel.warm_up(); warm_up()
problem = Problem.build(family_tasks(fam, 1, 0)[0], "robodesign_arm", "cyc")
ev = Evaluator(EvaluatorSpec(problem, seed=0))
rng = np.random.default_rng(0)
cands = [problem.space.random_candidate(rng) for _ in range(N)]
ev.evaluate(cands[0])
acc = {}; cnt = {}
def wrap(name, f):
    @functools.wraps(f)
    def w(*a, **k):
        t = time.perf_counter()
        try:
            return f(*a, **k)
        finally:
            acc[name] = acc.get(name, 0.0) + time.perf_counter() - t; cnt[name] = cnt.get(name, 0) + 1
    return w
for t in targets:
    mod, attr = t.rsplit(":", 1)
    obj = importlib.import_module(mod)
    parts = attr.split(".")
    owner = obj
    for a in parts[:-1]:
        owner = getattr(owner, a)
    f = owner.__dict__[parts[-1]] if isinstance(owner, type) else getattr(owner, parts[-1])
    if isinstance(f, property):
        setattr(owner, parts[-1], property(wrap(t, f.fget), f.fset))
    else:
        setattr(owner, parts[-1], wrap(t, f))
sums = {}; n = 0; tot = []
for c in cands[1:]:
    acc.clear()
    t = time.perf_counter(); e = ev.evaluate(c); d = time.perf_counter() - t
    if e.stage == "ik" and not e.feasible:
        n += 1; tot.append(d)
        for k, v in acc.items(): sums[k] = sums.get(k, []) + [v]
print(n, "failing; total median", round(np.median(tot) * 1e6), "mean", round(np.mean(tot) * 1e6))
for k in targets:
    v = sums.get(k, [0]); v = v + [0] * (n - len(v))
    print(f"{k:60s} mean {np.mean(v)*1e6:8.1f} median {np.median(v)*1e6:8.1f}")
if "--resid" in sys.argv[5:] or True:
    parts = [k for k in targets if k not in ("robodesign.design.evaluator:Evaluator.evaluate",) and "nested" not in k]
    ev_ = np.array(sums.get("robodesign.design.evaluator:Evaluator.evaluate", [0]*n))
    import itertools
    tot_parts = np.zeros(n)
    for k in parts:
        v = sums.get(k, [0]); v = v + [0] * (n - len(v))
        tot_parts += np.array(v)
    if len(ev_) == n: print("residual median", np.median(ev_ - tot_parts) * 1e6, "mean", np.mean(ev_ - tot_parts) * 1e6)
