import sys, pickle, time
from types import SimpleNamespace
sys.path.insert(0, sys.argv[1] + '/src')
import numpy as np
from robodesign.solvers import ik_kernel as K
K.warm_up()
B, D = pickle.load(open('/tmp/ik7/lmcalls.pkl', 'rb'))
a = list(B[5]); a[1] = a[2] = 0
d = list(D[5]); d[2] = 0
ck = SimpleNamespace(chain=a[6], kind=a[7], sign=a[8], iq=a[9], tcp=a[10])
pk = K.DescentPack(ck, a[11], (a[12], a[13]), a[4], a[5], a[17])
N = 50000
st = a[0]
for rep in range(5):
    t = time.process_time()
    for i in range(N): K.lm_batch(*a)
    t1 = time.process_time() - t
    t = time.process_time()
    for i in range(N): K.lm_batch_packed(st, 0, 0, 40, pk.I, pk.F)
    t2 = time.process_time() - t
    t = time.process_time()
    for i in range(N): K.lm_repair(*d)
    t3 = time.process_time() - t
    t = time.process_time()
    for i in range(N): K.lm_repair_packed(d[0], d[1], 0, pk.I, pk.F)
    t4 = time.process_time() - t
    print("empty calls, us: lm_batch %.2f packed %.2f | lm_repair %.2f packed %.2f" % (t1/N*1e6, t2/N*1e6, t3/N*1e6, t4/N*1e6))
