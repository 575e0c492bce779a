import math, time, sys
import numpy as np
from numba import njit
sys.path.insert(0, "/work/h-lanes/tests")
from robodesign.formats.module_io import load_module_set
from robodesign.model.robot import Robot
from robodesign.solvers import ik_kernel as K
from conftest import IMPROV

def make(L):
    @njit(nogil=True)
    def fk_lanes(q, chain, kind, sign, iq, tcp, T, Jv, Jw, M, tmp, origins, axes):
        # q: n x L ; T: 4x4xL ; Jv, Jw: 3 x n x L ; M,tmp: 4x4xL; origins, axes: nk x 3 x L
        nk = chain.shape[0]
        n = q.shape[0]
        for r in range(4):
            for c in range(4):
                for l in range(L):
                    M[r, c, l] = 1.0 if r == c else 0.0
        for j in range(n):
            for r in range(3):
                for l in range(L):
                    Jv[r, j, l] = 0.0
                    Jw[r, j, l] = 0.0
        ca = np.empty(L); sa = np.empty(L)
        for k in range(nk):
            P = chain[k]
            for r in range(3):
                for c in range(4):
                    p0, p1, p2 = P[0, c], P[1, c], P[2, c]
                    for l in range(L):
                        s = M[r, 0, l] * p0 + M[r, 1, l] * p1 + M[r, 2, l] * p2
                        if c == 3:
                            s += M[r, 3, l]
                        tmp[r, c, l] = s
            sg = sign[k]
            jq = iq[k]
            if kind[k] == 0:
                for l in range(L):
                    v = q[jq, l] * sg
                    ca[l] = math.cos(v)
                    sa[l] = math.sin(v)
                for r in range(3):
                    for l in range(L):
                        a, b = tmp[r, 0, l], tmp[r, 1, l]
                        M[r, 0, l] = a * ca[l] + b * sa[l]
                        M[r, 1, l] = -a * sa[l] + b * ca[l]
                        M[r, 2, l] = tmp[r, 2, l]
                        M[r, 3, l] = tmp[r, 3, l]
            else:
                for r in range(3):
                    for l in range(L):
                        v = q[jq, l] * sg
                        M[r, 0, l] = tmp[r, 0, l]
                        M[r, 1, l] = tmp[r, 1, l]
                        M[r, 2, l] = tmp[r, 2, l]
                        M[r, 3, l] = tmp[r, 3, l] + tmp[r, 2, l] * v
            for r in range(3):
                for l in range(L):
                    origins[k, r, l] = M[r, 3, l]
                    axes[k, r, l] = M[r, 2, l] * sg
        for r in range(3):
            for c in range(4):
                t0, t1, t2 = tcp[0, c], tcp[1, c], tcp[2, c]
                for l in range(L):
                    s = M[r, 0, l] * t0 + M[r, 1, l] * t1 + M[r, 2, l] * t2
                    if c == 3:
                        s += M[r, 3, l]
                    T[r, c, l] = s
        for l in range(L):
            T[3, 0, l] = 0.0; T[3, 1, l] = 0.0; T[3, 2, l] = 0.0; T[3, 3, l] = 1.0
        for k in range(nk):
            j = iq[k]
            if kind[k] == 0:
                for l in range(L):
                    zx, zy, zz = axes[k, 0, l], axes[k, 1, l], axes[k, 2, l]
                    dx, dy, dz = T[0, 3, l] - origins[k, 0, l], T[1, 3, l] - origins[k, 1, l], T[2, 3, l] - origins[k, 2, l]
                    Jv[0, j, l] += zy * dz - zz * dy
                    Jv[1, j, l] += zz * dx - zx * dz
                    Jv[2, j, l] += zx * dy - zy * dx
                    Jw[0, j, l] += zx
                    Jw[1, j, l] += zy
                    Jw[2, j, l] += zz
            else:
                for l in range(L):
                    Jv[0, j, l] += axes[k, 0, l]
                    Jv[1, j, l] += axes[k, 1, l]
                    Jv[2, j, l] += axes[k, 2, l]
    @njit(nogil=True)
    def run(Q, reps, chain, kind, sign, iq, tcp):
        n = Q.shape[1]; nk = chain.shape[0]
        T = np.empty((4, 4, L)); Jv = np.empty((3, n, L)); Jw = np.empty((3, n, L))
        M = np.empty((4, 4, L)); tmp = np.empty((4, 4, L)); o = np.empty((nk, 3, L)); a = np.empty((nk, 3, L))
        q = np.empty((n, L))
        acc = 0.0
        for rep in range(reps):
            for b in range(0, Q.shape[0] - L + 1, L):
                for l in range(L):
                    for j in range(n):
                        q[j, l] = Q[b + l, j]
                fk_lanes(q, chain, kind, sign, iq, tcp, T, Jv, Jw, M, tmp, o, a)
                acc += T[0, 3, 0]
        return acc, T, Jv, Jw
    return run

@njit(nogil=True)
def run_scalar(Q, reps, chain, kind, sign, iq, tcp):
    n = Q.shape[1]; nk = chain.shape[0]
    T = np.empty((4, 4)); Jv = np.empty((3, n)); Jw = np.empty((3, n))
    M = np.empty((4, 4)); tmp = np.empty((4, 4)); o = np.empty((nk, 3)); a = np.empty((nk, 3))
    acc = 0.0
    for rep in range(reps):
        for b in range(Q.shape[0]):
            K.fk_jacobian_ws(Q[b], chain, kind, sign, iq, tcp, T, Jv, Jw, M, tmp, o, a)
            acc += T[0, 3]
    return acc, T, Jv, Jw

imp = load_module_set(IMPROV)
robot = Robot.from_order(imp, ["1", "21", "4", "21", "23", "12"])
ck = K.chain_kernel(robot)
rng = np.random.default_rng(0)
Q = rng.uniform(-3, 3, (1024, robot.dof))
args = (ck.chain, ck.kind, ck.sign, ck.iq, ck.tcp)
run_scalar(Q, 1, *args)
runs = {L: make(L) for L in (1, 2, 4, 8)}
for L, f in runs.items():
    f(Q, 1, *args)
    # exactness on last block
    _, T, Jv, Jw = f(Q, 1, *args)
    b = (Q.shape[0] // L - 1) * L
    for l in range(L):
        T1 = np.empty((4, 4)); Jv1 = np.empty((3, robot.dof)); Jw1 = np.empty((3, robot.dof))
        K.fk_jacobian(Q[b + l].copy(), *args, T1, Jv1, Jw1)
        assert T1.tobytes() == np.ascontiguousarray(T[:, :, l]).tobytes(), L
        assert Jv1.tobytes() == np.ascontiguousarray(Jv[:, :, l]).tobytes()
        assert Jw1.tobytes() == np.ascontiguousarray(Jw[:, :, l]).tobytes()
reps = 200
for rnd in range(3):
    t = time.process_time(); run_scalar(Q, reps, *args); ts = (time.process_time() - t) / (reps * 1024) * 1e9
    line = f"scalar {ts:.0f} ns/fk"
    for L, f in runs.items():
        t = time.process_time(); f(Q, reps, *args); tl = (time.process_time() - t) / (reps * 1024) * 1e9
        line += f" | L={L} {tl:.0f} ns ({ts / tl:.2f}x)"
    print(line, flush=True)
