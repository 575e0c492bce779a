"""Paired A/B of the descents: scalar lm_descend_ws loop vs lm_lanes on 150 starts per PTP_3 goal, random IMPROV arms."""
import math, time, sys
import numpy as np
sys.path.insert(0, "/work/h-lanes/tests")
exec(open("/work/h-lanes/docs/results/issue25_round13/lanes_scripts/proto_iter.py").read().split("imp = load_module_set")[0])
from robodesign.solvers import ik_lanes as LN
from robodesign.solvers import ik as IK
imp = load_module_set(IMPROV)
task = load_task(TASKS / "simple" / "PTP_3.json")
params = np.array([IK._LAMBDA_FACTOR, IK._LAMBDA_BIAS, IK._MAX_STEP, IK._STALL_RATIO, IK._STALL_WINDOW], float)
names = sorted(imp.modules.keys()) if hasattr(imp, "modules") else None
orders = [["1", "21", "4", "22", "5", "23", "12"], ["1", "22", "7", "29", "4", "21", "16"], ["1", "21", "4", "21", "23", "12"],
          ["1", "4", "23", "7", "21", "5", "12"]]
N = 150
ts = tl = 0.0
ratios = []
for rnd in range(5):
    for order in orders:
        robot = Robot.from_order(imp, order)
        ck = K.chain_kernel(robot)
        lo, hi = np.asarray(robot.q_lower, float), np.asarray(robot.q_upper, float)
        r_lo = np.where(np.isfinite(lo), lo, -math.pi); r_hi = np.where(np.isfinite(hi), hi, math.pi)
        for gi, g in enumerate(task.goals):
            gm = goal_model(g.pose); tkind, tvec = gm.program()
            m = K.rows_of(tkind); n = robot.dof
            starts = r_lo + (r_hi - r_lo) * np.random.default_rng(rnd * 10 + gi).random((N, n))
            tail = (ck.chain, ck.kind, ck.sign, ck.iq, ck.tcp, gm.N_inv, tkind, tvec)
            qo, To, st, its = np.zeros((N, n)), np.zeros((N, 4, 4)), np.zeros(N, np.int64), np.zeros(N, np.int64)
            a = (40, lo, hi, *tail, np.zeros(m), np.zeros((m, n)), np.zeros((4, 4)), params)
            all_descents(starts[:2], *a, 0)
            R = 10
            t = time.process_time()
            for _ in range(R): all_descents(starts, *a, 0)
            t0 = (time.process_time() - t) / R
            t = time.process_time()
            for _ in range(R):
                st[:] = LN.RUNNING
                LN.lm_lanes(starts, 0, N, N, 40, lo, hi, *tail, params, LN.new_lanes(n, 0), qo, To, st, its)
            t1 = (time.process_time() - t) / R
            ts += t0; tl += t1; ratios.append(t0 / t1)
    print(f"round {rnd}: scalar {ts*1e3:.1f} ms, lanes{LN.LANES} {tl*1e3:.1f} ms total; ratio of sums {ts/tl:.3f}, median per goal {np.median(ratios):.3f}", flush=True)
