"""In-process A/B of time_parameterize on the paths of 20 good-arm PTP_3 evaluations: solvers.timing.sample_torques
as it was (the 'before' RNEA at every sample; c341f7b) against this checkout's (only where q̈ changes), swapped in
the same module, alternating; every t, q, dq, ddq and every sample_torques result compared bit for bit first.
usage: --src CHECKOUT"""
import sys
import time
src = sys.argv[sys.argv.index("--src") + 1]
sys.path.insert(0, src + "/src")
from robodesign.solvers import ik_kernel  # noqa: E402
ik_kernel.warm_up()
from robodesign.design.solve import warm_up  # noqa: E402
warm_up()
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

import robodesign.design.goal_planner as gp  # noqa: E402
from robodesign.design.evaluator import Evaluator, EvaluatorSpec  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.search_space import Candidate  # noqa: E402
from robodesign.solvers import timing  # noqa: E402

S = Path('/work/shared/cobra')
GOOD = ("1", "21", "4", "22", "5", "23", "12")
p = Problem.build(S / "tasks/simple/PTP_3.json", S / "modules/IMPROV", "cyc")


def former(robot, traj):
    """sample_torques at c341f7b."""
    n = len(traj.t)
    before_acc = np.vstack([traj.ddq[:1], traj.ddq[:-1]]) if n >= 2 else traj.ddq[:0]
    link = robot.link_torques(np.vstack([traj.q, traj.q[:len(before_acc)]]),
                              np.vstack([traj.dq, traj.dq[:len(before_acc)]]), np.vstack([traj.ddq, before_acc]))
    after = robot.drivetrain_torques(traj.q, traj.dq, traj.ddq, link_torques=link[:n])
    if n < 2:
        return np.abs(after)
    before = robot.drivetrain_torques(traj.q, traj.dq, before_acc, link_torques=link[n:])
    return np.maximum(np.abs(after), np.abs(before))


calls, samples = [], []
orig, new_st = gp.time_parameterize, timing.sample_torques
gp.time_parameterize = lambda robot, path, **kw: (calls.append((robot, np.array(path), kw)), orig(robot, path, **kw))[1]
timing.sample_torques = lambda robot, tr: (samples.append((robot, tr)), new_st(robot, tr))[1]
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
gp.time_parameterize, timing.sample_torques = orig, new_st
rows = sum(len(tr.t) for _, tr in samples)
same = sum(int(np.sum(np.all(np.vstack([tr.ddq[:1], tr.ddq[:-1]]) == tr.ddq, axis=1))) for _, tr in samples)
assert all(new_st(r, tr).tobytes() == former(r, tr).tobytes() for r, tr in samples)
import gc  # noqa: E402
gc.freeze()


def run(which):
    timing.sample_torques = former if which == "base" else new_st
    return [timing.time_parameterize(r, P, **kw) for r, P, kw in calls]


A, B = run("base"), run("new")
assert all(x.tobytes() == y.tobytes() for a, b in zip(A, B) for x, y in ((a.t, b.t), (a.q, b.q), (a.dq, b.dq),
                                                                          (a.ddq, b.ddq)))
ta, tb, sa, sb = [], [], [], []
for rep in range(9):
    for lst, sl, which, f in ((ta, sa, "base", former), (tb, sb, "new", new_st)):
        t = time.process_time()
        for _ in range(5):
            run(which)
        lst.append((time.process_time() - t) / (5 * len(calls)) * 1e3)
        t = time.process_time()
        for _ in range(5):
            for r, tr in samples:
                f(r, tr)
        sl.append((time.process_time() - t) / (5 * len(samples)) * 1e3)
timing.sample_torques = new_st
print(f"{len(calls)} time_parameterize calls, {len(samples)} sample_torques calls ({rows} samples, {same} with q̈ "
      f"unchanged); results identical")
for name, a, b in (("time_parameterize ms CPU per call", ta, tb), ("sample_torques ms CPU per call", sa, sb)):
    rr = np.array(a) / np.array(b)
    print(f"{name} (median of 9 alternating rounds): base {np.median(a):.3f}, new {np.median(b):.3f}; per-round "
          f"ratio base/new median {np.median(rr):.3f} (min {rr.min():.3f}, max {rr.max():.3f})")
    print("  base rounds", np.round(a, 3).tolist())
    print("  new rounds ", np.round(b, 3).tolist())
