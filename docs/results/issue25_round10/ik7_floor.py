import sys, time
sys.path.insert(0, sys.argv[1] + '/src')
import numpy as np
from numba import njit
from robodesign.solvers import ik_kernel as K
K.warm_up()
@njit(nogil=True)
def noop6(starts, a, stop, iters, I, F):
    return stop, 0, False
@njit(nogil=True)
def unp6(starts, a, stop, iters, I, F):
    r = K._unpack(I, F)
    return stop, r[-1], False
from types import SimpleNamespace
n = 6
ck = SimpleNamespace(chain=np.tile(np.eye(4), (n, 1, 1)), kind=np.zeros(n, np.int64), sign=np.ones(n), iq=np.arange(n, dtype=np.int64), tcp=np.eye(4))
tk = np.array([2, 3], np.int64); tv = np.zeros((2, 12))
pk = K.DescentPack(ck, np.eye(4), (tk, tv), -np.ones(n), np.ones(n), np.ones(5))
st = np.zeros((150, n))
noop6(st, 0, 0, 40, pk.I, pk.F); unp6(st, 0, 0, 40, pk.I, pk.F)
N = 100000
for rep in range(3):
    t = time.process_time()
    for i in range(N): noop6(st, 0, 0, 40, pk.I, pk.F)
    t1 = time.process_time() - t
    t = time.process_time()
    for i in range(N): unp6(st, 0, 0, 40, pk.I, pk.F)
    t2 = time.process_time() - t
    t = time.process_time()
    for i in range(N): K.lm_batch_packed(st, 0, 0, 40, pk.I, pk.F)
    t3 = time.process_time() - t
    print("us per call: no-op 6 args %.2f, + _unpack %.2f, lm_batch_packed empty %.2f" % (t1/N*1e6, t2/N*1e6, t3/N*1e6))
