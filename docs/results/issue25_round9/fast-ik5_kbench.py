"""Time the captured lm_batch/lm_descend calls with a kernel module; check outputs against the checkout's kernel.
usage: kbench.py CHECKOUT [variant.py] [rounds]"""
import sys, pickle, time, importlib.util, hashlib
sys.path.insert(0, sys.argv[1] + '/src')
import numpy as np
from robodesign.solvers import ik_kernel as ref
B, D = pickle.load(open('/tmp/fik5/lmcalls.pkl', 'rb'))
mods = [('ref', ref)]
if len(sys.argv) > 2 and sys.argv[2].endswith('.py'):
    spec = importlib.util.spec_from_file_location('kvar', sys.argv[2]); var = importlib.util.module_from_spec(spec); spec.loader.exec_module(var)
    mods.append(('var', var))
rounds = int(sys.argv[-1]) if sys.argv[-1].isdigit() else 5
def run(m):
    h = hashlib.sha256()
    t = time.process_time()
    for a in B:
        a = list(a); E, JJ, T, q = a[14].copy(), a[15].copy(), a[16].copy(), a[18].copy()
        a[14], a[15], a[16], a[18] = E, JJ, T, q
        r = m.lm_batch(*a)
        h.update(repr(r).encode()); h.update(q.tobytes()); h.update(T.tobytes()); h.update(E.tobytes())
    tb = time.process_time() - t
    t = time.process_time()
    for a in D:
        a = list(a); q = a[0].copy(); a[0] = q
        r = m.lm_descend(*a)
        h.update(repr(r).encode()); h.update(q.tobytes()); h.update(a[14].tobytes())
    td = time.process_time() - t
    return tb, td, h.hexdigest()[:12]
for m in mods: run(m[1])
res = {n: [] for n, _ in mods}
for i in range(rounds):
    for n, m in mods:
        res[n].append(run(m))
for n in res:
    tb = [x[0] / 20 * 1e3 for x in res[n]]; td = [x[1] / 20 * 1e3 for x in res[n]]
    print(n, 'batch ms/eval', ' '.join('%.2f' % x for x in tb), 'med %.2f' % np.median(tb), '| descend', 'med %.2f' % np.median(td), res[n][0][2])
