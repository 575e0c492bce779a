import sys, time, importlib.util
sys.path.insert(0, "/work/h-fast-check4/src")
import numpy as np
from robodesign.judge import interval_kernel as nk
spec = importlib.util.spec_from_file_location("bk", "/tmp/base_s7/src/robodesign/judge/interval_kernel.py")
bk = importlib.util.module_from_spec(spec); spec.loader.exec_module(bk)
bk.warm_up(); nk.warm_up()
rng = np.random.default_rng(0)
P, n = 82, 6
Q0, Q1, V0, V1, am, ar = rng.uniform(-2, 2, (P, n)), rng.uniform(0, .01, (P, n)), rng.uniform(-1, 1, (P, n)), rng.uniform(0, .01, (P, n)), rng.uniform(-3, 3, (P, n)), rng.uniform(0, .1, (P, n))
acc0 = np.tile([0, 0, 9.81], (P, 1)); C, S = np.cos(Q0), np.sin(Q0)
par = np.arange(n, dtype=np.int64); kinds = np.zeros(n, np.int64); signs = np.ones(n)
R = np.array([np.linalg.qr(rng.normal(size=(3, 3)))[0] for _ in range(n)]); SP = rng.normal(size=(n, 3, 3))
mass = rng.uniform(1, 3, n); SC = rng.normal(size=(n, 3, 3)) * .1; IC = rng.normal(size=(n, 3, 3)) * .01
args = (Q0, Q1, V0, V1, am, ar, acc0, C, S, par, kinds, signs, R, SP, mass, SC, IC)
def bench(f, n=300):
    out = []
    for r in range(7):
        t = time.process_time()
        for _ in range(n): f()
        out.append((time.process_time() - t) / n * 1e6)
    return np.median(out)
A = bk.link_torques(*args); B = nk.link_torques(*args, P); C2 = nk.link_torques(*args, 22)
assert np.array_equal(A, B) and np.array_equal(A[:2], C2[:2])
for _ in range(2):
    print("base", bench(lambda: bk.link_torques(*args)), "new all", bench(lambda: nk.link_torques(*args, P)),
          "new 22", bench(lambda: nk.link_torques(*args, 22)), "new 0", bench(lambda: nk.link_torques(*args, 0)))
