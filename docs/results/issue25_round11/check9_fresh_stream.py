"""PTP_3's first N random candidates (fresh IMPROV arms; ~23 of 900 feasible) evaluated in one process, as
bench_paired's ptp3 scenario draws them. Prints the stream's CPU seconds, the feasible candidates' median CPU ms and
stage medians, and a signature hash of every result (must not change).
usage: python fresh_stream.py CHECKOUT [N] [--prof FILE]"""
import sys, time, hashlib
src = sys.argv[1]; N = int(sys.argv[2]) if len(sys.argv) > 2 and not sys.argv[2].startswith("-") else 900
prof = sys.argv[sys.argv.index("--prof") + 1] if "--prof" in sys.argv else None
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import SHARED
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
ik_kernel.warm_up(); warm_up()
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
ev = Evaluator(EvaluatorSpec(ptp3, seed=0))
rng = np.random.default_rng(0); cands = [ptp3.space.random_candidate(rng) for _ in range(N)]
st, tf, sig = {}, [], []
if prof:
    import cProfile; pr = cProfile.Profile(); pr.enable()
t0 = time.process_time()
for c in cands:
    t = time.process_time(); e = ev.evaluate(c); dt = time.process_time() - t
    sig.append((e.stage, e.feasible, round(e.cost, 9) if e.feasible else None))
    if e.feasible:
        tf.append(dt)
        for s_ in e.stages: st.setdefault(s_["name"], []).append(s_["seconds"])
total = time.process_time() - t0
if prof:
    pr.disable(); pr.dump_stats(prof)
print(f"{src}: stream cpu {total:.2f} s, feasible {len(tf)}, median feasible {np.median(tf)*1e3:.1f} ms (mean {np.mean(tf)*1e3:.1f}), "
      f"sig {hashlib.sha1(repr(sig).encode()).hexdigest()[:10]}")
print("  stage medians (ms): " + "  ".join(f"{k} {np.median(v)*1e3:.1f}" for k, v in st.items()) + f"  check sum {sum(st['check'])*1e3:.0f} ms")
