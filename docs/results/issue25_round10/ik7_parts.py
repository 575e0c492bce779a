import sys, pickle, time
sys.path.insert(0, sys.argv[1] + '/src')
import numpy as np
from robodesign.solvers import ik_kernel as K
from robodesign.core.jit_cache import njit
K.warm_up()
B, D = pickle.load(open('/tmp/ik7/lmcalls.pkl', 'rb'))
a = B[5]
starts, _, _, iters, lo, hi, chain, kind, sign, iq, tcp, Ninv, tkind, tvec, E, JJ, T, params, q = a
@njit
def tfk(N, q, chain, kind, sign, iq, tcp, T, ws):
    Jv, Jw, work, A, rhs, x, dq, M4, tmp4, origins, axes, Rd, Jp, Jr, JL, G = ws
    for i in range(N):
        q[0] += 1e-9
        K.fk_jacobian_ws(q, chain, kind, sign, iq, tcp, T, Jv, Jw, M4, tmp4, origins, axes)
@njit
def tgr(N, T, Ninv, tkind, tvec, E, JJ, ws):
    Jv, Jw, work, A, rhs, x, dq, M4, tmp4, origins, axes, Rd, Jp, Jr, JL, G = ws
    c = 0
    for i in range(N):
        T[0, 3] += 1e-12
        c += K.goal_rows_ws(T, Jv, Jw, Ninv, tkind, tvec, E, JJ, work, Rd, Jp, Jr, JL, G)
    return c
@njit
def tch(N, JJ, E, ws):
    Jv, Jw, work, A, rhs, x, dq, M4, tmp4, origins, axes, Rd, Jp, Jr, JL, G = ws
    m, n = JJ.shape
    for i in range(N):
        lam = 1e-3 + i * 1e-12
        for r in range(m):
            for c in range(r + 1):
                s = 0.0
                for j in range(n):
                    s += JJ[r, j] * JJ[c, j]
                A[r, c] = s
                A[c, r] = s
            A[r, r] += lam
            rhs[r] = E[r]
        K.chol_solve(A, rhs, x)
        for j in range(n):
            s = 0.0
            for r in range(m):
                s += JJ[r, j] * x[r]
            dq[j] = s
@njit
def tall(N, starts, iters, lo, hi, chain, kind, sign, iq, tcp, Ninv, tkind, tvec, E, JJ, T, params, q):
    t = 0
    for i in range(N):
        t += K.lm_batch(starts, 0, 1, iters, lo, hi, chain, kind, sign, iq, tcp, Ninv, tkind, tvec, E, JJ, T, params, q)[1]
    return t
ws = K.Workspace(6, 6, 6)
q = starts[0].copy()
K.fk_jacobian_ws(q, chain, kind, sign, iq, tcp, T, ws[0], ws[1], ws[7], ws[8], ws[9], ws[10])
K.goal_rows_ws(T, ws[0], ws[1], Ninv, tkind, tvec, E, JJ, ws[2], ws[11], ws[12], ws[13], ws[14], ws[15])
print("E", E)
N = 200000
for rep in range(3):
    t = time.process_time(); tfk(N, q, chain, kind, sign, iq, tcp, T, ws); t1 = time.process_time() - t
    t = time.process_time(); tgr(N, T, Ninv, tkind, tvec, E, JJ, ws); t2 = time.process_time() - t
    JJ2 = JJ.copy(); JJ2[:] = np.random.default_rng(0).normal(size=JJ.shape)
    t = time.process_time(); tch(N, JJ2, E, ws); t3 = time.process_time() - t
    t = time.process_time(); its = tall(2000, starts, 40, lo, hi, chain, kind, sign, iq, tcp, Ninv, tkind, tvec, E, JJ, T, params, q); t4 = time.process_time() - t
    print("fk %.0f ns  goal_rows %.0f ns  solve %.0f ns  | lm_batch per iteration %.0f ns (%d its)" % (t1/N*1e9, t2/N*1e9, t3/N*1e9, t4/its*1e9, its))
