import math, time, sys
import numpy as np
sys.path.insert(0, "/work/h-lanes/tests")
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.model.robot import Robot
from robodesign.solvers import ik_kernel as K, ik_lanes as LN, ik as IK
from robodesign.solvers.ik import goal_model
from conftest import IMPROV, TASKS
imp = load_module_set(IMPROV); task = load_task(TASKS / "simple" / "PTP_3.json")
robot = Robot.from_order(imp, ["1", "21", "4", "22", "5", "23", "12"]); ck = K.chain_kernel(robot)
lo, hi = np.asarray(robot.q_lower, float), np.asarray(robot.q_upper, float)
gm = goal_model(task.goals[0].pose); tkind, tvec = gm.program(); n = robot.dof; m = K.rows_of(tkind)
params = np.array([IK._LAMBDA_FACTOR, IK._LAMBDA_BIAS, IK._MAX_STEP, IK._STALL_RATIO, IK._STALL_WINDOW], float)
starts = np.random.default_rng(0).uniform(-1, 1, (150, n))
ah = LN.Ahead((40, lo, hi, ck.chain, ck.kind, ck.sign, ck.iq, ck.tcp, gm.N_inv, tkind, tvec, params))
r = ah.next_in_goal(starts, 0, 150)[0]
R = 20000
t = time.perf_counter()
for _ in range(R): ah.next_in_goal(starts, 0, 150)
print("lanes call (answer ready):", (time.perf_counter() - t) / R * 1e6, "us")
bargs = (40, lo, hi, ck.chain, ck.kind, ck.sign, ck.iq, ck.tcp, gm.N_inv, tkind, tvec, np.zeros(m), np.zeros((m, n)), np.zeros((4, 4)), params, np.zeros(n))
K.lm_batch(starts, 0, 0, *bargs)
t = time.perf_counter()
for _ in range(R): K.lm_batch(starts, 0, 0, *bargs)
print("lm_batch call (empty):", (time.perf_counter() - t) / R * 1e6, "us")
