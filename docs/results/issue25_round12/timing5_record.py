"""timing5 (issue 25, round 12): record every time_parameterize call of the 23 fresh feasible PTP_3 candidates (feas.pkl, each a new arm) and of the
known-good arm (20 seeds); then replay them, timing the parts (process CPU; --src-less: PYTHONPATH=CHECKOUT/src python timing5_record.py CHECKOUT). The candidates are
/tmp/s11/feas.pkl (the 23 feasible of bench_fresh_stream.py's 900). Also exec'd by timing5_replay_paired.py and timing5_stage_shares.py
(everything before its parts' timers)."""
import sys, time, pickle, statistics, hashlib
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import SHARED, GOOD
from robodesign.design import goal_planner
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel, topp_kernel, timing
ik_kernel.warm_up(); topp_kernel.warm_up(); warm_up()
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
feas = pickle.load(open("/tmp/s11/feas.pkl", "rb"))
calls = {"fresh": [], "good": []}
real = goal_planner.time_parameterize
cur = None
def record(robot, path, **kw):
    calls[cur].append((robot, np.array(path, dtype=float), kw))
    return real(robot, path, **kw)
goal_planner.time_parameterize = record
cur = "fresh"
ev = Evaluator(EvaluatorSpec(ptp3, seed=1))
for c in feas: ev.evaluate(c)
cur = "good"
for s in range(20): Evaluator(EvaluatorSpec(ptp3, seed=s)).evaluate(Candidate(GOOD))
goal_planner.time_parameterize = real
print({k: len(v) for k, v in calls.items()})

from collections import defaultdict
from robodesign.solvers import toppra_loop, blended_path
from robodesign.model import rnea_batch
acc = defaultdict(float); cnt = defaultdict(int)
def wrap(mod, name, label):
    f = getattr(mod, name)
    def w(*a, **k):
        t = time.process_time()
        try:
            return f(*a, **k)
        finally:
            acc[label] += time.process_time() - t; cnt[label] += 1
    setattr(mod, name, w)
    return f
def unwrap_all(saved):
    for mod, name, f in saved: setattr(mod, name, f)
from robodesign.solvers import topp_kernel as tk
from robodesign.model import robot as robot_mod
targets2 = [(rnea_batch.pin, "rneaInParallel", "rnea_pin"), (tk, "rest_to_rest", "k.rest_to_rest"), (tk, "constraint_rows", "k.constraint_rows"), (tk, "profile_rows", "k.profile_rows"), (tk, "zoh_rows", "k.zoh_rows")]
targets = [(timing, "_toppra_profile", "toppra_profile"), (timing, "_fit_limits", "fit_limits"),
           (timing, "_PathTerms", "PathTerms"),
           (timing, "rnea_rows", "PathTerms.rnea"), (timing, "pass_velocities", "pass_velocities"),
           (toppra_loop, "_compiled_rows", "pass.constraint_rows"), (timing, "velocity_xbound", "velocity_xbound"),
           (timing, "_sample", "fit._sample"), (timing, "sample_torques", "fit.sample_torques"),
           (timing, "_limit_ratio", "fit._limit_ratio")]
def run(group, reps=5, parts=False):
    saved = [(m, n, wrap(m, n, l)) for m, n, l in (targets if parts == 1 else targets2)] if parts else []
    acc.clear(); cnt.clear()
    cpu = []
    for _ in range(reps):
        t = time.process_time()
        for robot, path, kw in calls[group]:
            timing.time_parameterize(robot, path, **kw)
        cpu.append(time.process_time() - t)
    unwrap_all(saved)
    nev = 23 if group == "fresh" else 20
    return statistics.median(cpu) / nev * 1e3, {k: acc[k] / reps / nev * 1e3 for k in acc}
def digest(group):
    d = hashlib.sha256()
    for robot, path, kw in calls[group]:
        tr = timing.time_parameterize(robot, path, **kw)
        for x in (tr.t, tr.q, tr.dq, tr.ddq): d.update(x.tobytes())
    return d.hexdigest()[:16]
for g in ("fresh", "good"):
    print(g, "hash", digest(g))
    ms, _ = run(g, 7)
    print(g, f"ms per evaluation {ms:.3f}")
    ms, parts = run(g, 5, 2)
    print(g, f"(wrapped) {ms:.3f}", "  ".join(f"{k} {v:.3f}" for k, v in sorted(parts.items())))
