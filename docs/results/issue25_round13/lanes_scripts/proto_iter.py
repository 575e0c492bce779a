import math, time, sys
import numpy as np
from numba import njit
sys.path.insert(0, "/work/h-lanes/tests")
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.model.robot import Robot
from robodesign.solvers import ik_kernel as K
from robodesign.solvers.ik import goal_model
from conftest import IMPROV, TASKS

@njit(nogil=True)
def all_descents(starts, iters, lo, hi, chain, kind, sign, iq, tcp, Ninv, tkind, tvec, E, JJ, T, params, mode):
    n = starts.shape[1]
    ws = K.Workspace(n, E.shape[0], chain.shape[0])
    q = np.empty(n)
    tot = 0
    Jv, Jw, work, A, rhs, x, dq, M4, tmp4, origins, axes, Rd, Jp, Jr, JL, G = ws
    for r in range(starts.shape[0]):
        for j in range(n):
            q[j] = starts[r, j]
        if mode == 0:
            st, its = K.lm_descend_ws(q, iters, lo, hi, chain, kind, sign, iq, tcp, Ninv, tkind, tvec, E, JJ, T, params, ws)
            tot += its
        elif mode == 1:
            K.fk_jacobian_ws(q, chain, kind, sign, iq, tcp, T, Jv, Jw, M4, tmp4, origins, axes)
            tot += 1
        else:
            K.fk_jacobian_ws(q, chain, kind, sign, iq, tcp, T, Jv, Jw, M4, tmp4, origins, axes)
            K.goal_rows_ws(T, Jv, Jw, Ninv, tkind, tvec, E, JJ, work, Rd, Jp, Jr, JL, G)
            tot += 1
    return tot

imp = load_module_set(IMPROV)
task = load_task(TASKS / "simple" / "PTP_3.json")
for order in (["1", "21", "4", "21", "23", "12"], ["1", "22", "7", "29", "4", "21", "16"]):
    robot = Robot.from_order(imp, order)
    ck = K.chain_kernel(robot)
    lo, hi = np.asarray(robot.q_lower, float), np.asarray(robot.q_upper, float)
    r_lo = np.where(np.isfinite(lo), lo, -math.pi); r_hi = np.where(np.isfinite(hi), hi, math.pi)
    params = np.array([0.02, 1e-6, 1.0, 0.9, 3.0])  # placeholder, replaced below
    from robodesign.solvers import ik as IK
    params = np.array([IK._LAMBDA_FACTOR, IK._LAMBDA_BIAS, IK._MAX_STEP, IK._STALL_RATIO, IK._STALL_WINDOW], float)
    for g in task.goals:
        gm = goal_model(g.pose); tkind, tvec = gm.program()
        m = K.rows_of(tkind)
        starts = r_lo + (r_hi - r_lo) * np.random.default_rng(1).random((3000, robot.dof))
        a = (40, lo, hi, ck.chain, ck.kind, ck.sign, ck.iq, ck.tcp, gm.N_inv, tkind, tvec, np.zeros(m), np.zeros((m, robot.dof)), np.zeros((4, 4)), params)
        for mode in (0, 1, 2):
            all_descents(starts[:10], *a, mode)
        t = time.process_time(); its = all_descents(starts, *a, 0); t0 = time.process_time() - t
        t = time.process_time(); all_descents(starts, *a, 1); t1 = time.process_time() - t
        t = time.process_time(); all_descents(starts, *a, 2); t2 = time.process_time() - t
        print(f"dof {robot.dof} rows {m} kinds {tkind.tolist()}: {its/3000:.1f} it/descent, {t0/its*1e9:.0f} ns/it, "
              f"{t0/3000*1e6:.1f} us/descent; fk {t1/3000*1e9:.0f} ns, fk+rows {t2/3000*1e9:.0f} ns", flush=True)
