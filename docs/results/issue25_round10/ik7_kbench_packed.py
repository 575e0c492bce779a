"""The captured lm_batch / lm_repair calls (ik7_capture.py) run by A's plain kernels and by B's packed kernels
(ik_inputs.DescentPack, lm_batch_packed / lm_repair_packed): the same results bit for bit (a hash of every return,
q, T, E and JJ), and CPU ms per evaluation of each, in alternating rounds.
usage: ik7_kbench_packed.py CHECKOUT_A CHECKOUT_B [rounds]"""
import sys, pickle, time, hashlib, importlib
from types import SimpleNamespace
import numpy as np
A, B_, rounds = sys.argv[1], sys.argv[2], int(sys.argv[3]) if len(sys.argv) > 3 else 5
BATCH, REP = pickle.load(open('/tmp/ik7/lmcalls.pkl', 'rb'))


def load(src):
    for k in [k for k in sys.modules if k.startswith('robodesign')]:
        del sys.modules[k]
    sys.path.insert(0, src + '/src')
    m = importlib.import_module('robodesign.solvers.ik_kernel')
    m.warm_up()
    sys.path.pop(0)
    return m


def plain(m):
    """Each call with its own argument list, made beforehand (as _Kernel held them), outside the timing."""
    bs = [[x.copy() if isinstance(x, np.ndarray) else x for x in a] for a in BATCH]
    rs = [[x.copy() if isinstance(x, np.ndarray) else x for x in a] for a in REP]
    h = hashlib.sha256()
    t = time.process_time()
    out = [m.lm_batch(*a) for a in bs] + [m.lm_repair(*a) for a in rs]
    dt = time.process_time() - t
    for r, a in zip(out, bs + rs):
        q, T, E, JJ = (a[18], a[16], a[14], a[15]) if len(a) == 19 else (a[17], a[15], a[13], a[14])
        h.update(repr(tuple(r)).encode()); h.update(q.tobytes()); h.update(T.tobytes()); h.update(E.tobytes()); h.update(JJ.tobytes())
    return dt, h.hexdigest()[:12]


def packs(m):
    """One DescentPack per captured call, its outputs set to the call's."""
    out = []
    for a in BATCH:
        ck = SimpleNamespace(chain=a[6], kind=a[7], sign=a[8], iq=a[9], tcp=a[10])
        pk = m.DescentPack(ck, a[11], (a[12], a[13]), a[4], a[5], a[17])
        pk.E[:], pk.JJ[:], pk.T[:], pk.q[:] = a[14], a[15], a[16], a[18]
        out.append(pk)
    for a in REP:
        ck = SimpleNamespace(chain=a[5], kind=a[6], sign=a[7], iq=a[8], tcp=a[9])
        pk = m.DescentPack(ck, a[10], (a[11], a[12]), a[3], a[4], a[16])
        pk.E[:], pk.JJ[:], pk.T[:], pk.qr[:] = a[13], a[14], a[15], a[17]
        out.append(pk)
    return out


def packed(m):
    ps = packs(m)
    h = hashlib.sha256()
    t = time.process_time()
    out = [m.lm_batch_packed(a[0], a[1], a[2], a[3], pk.I, pk.F) for a, pk in zip(BATCH, ps)]
    out += [m.lm_repair_packed(a[0], a[1], a[2], pk.I, pk.F) for a, pk in zip(REP, ps[len(BATCH):])]
    dt = time.process_time() - t
    for i, (r, pk) in enumerate(zip(out, ps)):
        q = pk.q if i < len(BATCH) else pk.qr
        h.update(repr(tuple(r)).encode()); h.update(q.tobytes()); h.update(pk.T.tobytes()); h.update(pk.E.tobytes()); h.update(pk.JJ.tobytes())
    return dt, h.hexdigest()[:12]


ma = load(A); mb = load(B_)
runs = [('A plain', lambda: plain(ma)), ('B plain', lambda: plain(mb)), ('B packed', lambda: packed(mb))]
for _, f in runs:
    f()
res = {n: [] for n, _ in runs}
for i in range(rounds):
    for n, f in runs:
        res[n].append(f())
for n, _ in runs:
    ts = [x[0] / 20 * 1e3 for x in res[n]]
    print('%-9s ms/eval (batch + repair):' % n, ' '.join('%.2f' % x for x in ts), 'med %.2f' % np.median(ts),
          '| hashes', sorted(set(x[1] for x in res[n])))
