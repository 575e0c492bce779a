import sys, time
sys.path.insert(0, sys.argv[1] + "/src"); sys.path.insert(0, sys.argv[1] + "/tests")
import numpy as np
from robodesign.model import geometry_kernel
from test_inner_spheres import ptp3_robot
from test_hull_proofs import _without_hulls
from robodesign.model.collision_cull import culler_of
geometry_kernel.warm_up()
robot = ptp3_robot()
c = culler_of(robot)
args = list(c._kernel_args()[0])
no = _without_hulls(args)
rng = np.random.default_rng(0)
Q = np.array([robot.random_configuration(rng) for _ in range(3000)])
S = geometry_kernel.survivors
for a in (args, no):
    for q in Q[:10]: S(q, *a)
for rep in range(3):
    for name, a in (("with hulls", args), ("spheres only", no)):
        t = time.process_time()
        hits = sum(S(q, *a)[2] >= 0 for q in Q)
        print(name, "%.2f us/query" % ((time.process_time() - t) / len(Q) * 1e6), "proven", hits)
n = [S(q, *args)[0] for q in Q[:500]]
print("surviving pairs per query: mean", np.mean(n))
