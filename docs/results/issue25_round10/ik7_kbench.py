"""Time the captured lm_batch / lm_repair calls (ik7_capture.py) with a checkout's kernels; hash their outputs.
usage: ik7_kbench.py CHECKOUT [CHECKOUT2] [rounds]  (alternating rounds; CPU ms per evaluation)"""
import sys, pickle, time, hashlib, importlib, subprocess
import numpy as np
srcs = [a for a in sys.argv[1:] if not a.isdigit()]
rounds = int(sys.argv[-1]) if sys.argv[-1].isdigit() else 5
B, D = pickle.load(open('/tmp/ik7/lmcalls.pkl', 'rb'))


def load(src):
    """The checkout's ik_kernel module (a fresh import under its own path)."""
    for k in [k for k in sys.modules if k.startswith('robodesign')]:
        del sys.modules[k]
    sys.path.insert(0, src + '/src')
    m = importlib.import_module('robodesign.solvers.ik_kernel')
    m.warm_up()
    sys.path.pop(0)
    return m


def run(m):
    h = hashlib.sha256()
    t = time.process_time()
    for a in B:
        a = list(a); E, JJ, T, q = a[14].copy(), a[15].copy(), a[16].copy(), a[18].copy()
        a[14], a[15], a[16], a[18] = E, JJ, T, q
        r = m.lm_batch(*a)
        h.update(repr(r).encode()); h.update(q.tobytes()); h.update(T.tobytes()); h.update(E.tobytes()); h.update(JJ.tobytes())
    tb = time.process_time() - t
    t = time.process_time()
    for a in D:
        a = list(a); E, JJ, T, q = a[13].copy(), a[14].copy(), a[15].copy(), a[17].copy()
        a[13], a[14], a[15], a[17] = E, JJ, T, q
        r = m.lm_repair(*a)
        h.update(repr(r).encode()); h.update(q.tobytes()); h.update(T.tobytes()); h.update(E.tobytes()); h.update(JJ.tobytes())
    td = time.process_time() - t
    return tb, td, h.hexdigest()[:12]


mods = [(s, load(s)) for s in srcs]
for _, m in mods:
    run(m)
res = {s: [] for s in srcs}
for i in range(rounds):
    for s, m in mods:
        res[s].append(run(m))
for s in srcs:
    tb = [x[0] / 20 * 1e3 for x in res[s]]; td = [x[1] / 20 * 1e3 for x in res[s]]
    print(s, 'batch ms/eval', ' '.join('%.2f' % x for x in tb), 'med %.2f' % np.median(tb),
          '| repair', ' '.join('%.2f' % x for x in td), 'med %.2f' % np.median(td), '| hash', res[s][0][2])
