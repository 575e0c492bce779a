import sys, time, importlib.util
src = sys.argv[sys.argv.index("--src") + 1]
sys.path.insert(0, src + "/src")
exec(open("/work/h-fast-check3/docs/results/issue25_round7/fast-check3_check_loop.py").read().split("import gc")[0].split("sys.path.insert(0, src + \"/src\")")[1])
import numpy as np
from robodesign.judge.quantities import TrajectoryQuantities
from robodesign.model.cell import solution_robot
from robodesign.model.sweep import SweepChecker
from robodesign.model import sweep_kernel as sk
spec = importlib.util.spec_from_file_location("base_sk", "/tmp/base_s7/src/robodesign/model/sweep_kernel.py")
bk = importlib.util.module_from_spec(spec); spec.loader.exec_module(bk)
task, sol, ms, kw = sols[0]
r = solution_robot(task, sol, ms)
tq = TrajectoryQuantities.from_solution(r, sol, task)
ch = SweepChecker(r, posed_arms=True)
Q = tq.q; m = tq.motion; path = m.path_bound(); J = tq.joint_poses
dQ = np.maximum(path, np.abs(np.diff(Q, axis=0)))
ch.check(Q, first_only=False, path=path, at=lambda k, s: m.at(k, s), poses=J)
pa = ch._posed; TG = pa.poses()
sched, cum_rows = pa.schedule(Q, dQ, ch.W, ch._owner, J)
sp = ch._spheres; mov = np.array(ch._mov, dtype=np.int64); ref = np.array(ch._ref, dtype=np.int64)
cs = np.flatnonzero(np.array(ch._obst) < 0)
cen, rad = sp
def cases(K):
    args = (J, *pa._k_tree, np.ascontiguousarray(dQ), *pa._k_drift, 1 + pa.SLACK)
    o1 = np.empty((len(TG), len(cs)))
    o2 = np.empty((len(ch.pairs), len(TG) - 1), np.int64)
    F = np.random.default_rng(0).random((len(TG), len(ch.pairs)))
    return {"posed_arms": lambda: K.posed_arms(*args),
            "sphere_gaps": lambda: (K.sphere_gaps(TG, cen, mov[cs], ref[cs], rad[mov[cs]] + rad[ref[cs]], o1), o1.copy())[1],
            "open_steps": lambda: (K.open_steps(F, np.ascontiguousarray(sched), dQ.max(axis=1), ch.W.sum(axis=0), 4e-6, 1.0, 500.0, o2), o2.copy())[1]}
A, B = cases(bk), cases(sk)
for name in A:
    a, b = A[name](), B[name]()
    same = np.array_equal(a, b) and a.tobytes() == b.tobytes()
    ta, tb = [], []
    for rep in range(7):
        for lst, f in ((ta, A[name]), (tb, B[name])):
            t = time.process_time()
            for _ in range(40): f()
            lst.append((time.process_time() - t) / 40 * 1e3)
    print(f"{name:12s} identical={same} base {np.median(ta):.3f} ms new {np.median(tb):.3f} ms")
