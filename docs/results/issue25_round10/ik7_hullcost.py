"""The compiled bounds' cost per query on the PTP_3 arm (3,000 random states): the hull test off (last = -1) and on
pair (10, 17) (the pair coal finds colliding in the IK stage). usage: ik7_hullcost.py CHECKOUT
(At f4080ab, which tested every surviving self pair, the same states cost ~15 us with hulls against ~11 without.)"""
import sys, time
sys.path.insert(0, sys.argv[1] + "/src"); sys.path.insert(0, sys.argv[1] + "/tests")
import numpy as np
from robodesign.model import geometry_kernel
from test_inner_spheres import ptp3_robot
from test_hull_proofs import _packed
from robodesign.model.collision_cull import culler_of
geometry_kernel.warm_up()
robot = ptp3_robot()
c = culler_of(robot)
args = list(c._kernel_args()[0])
packed = _packed(args)
k = [i for i in range(c.n_pairs) if (c.first[i], c.second[i]) == (10, 17)][0]
rng = np.random.default_rng(0)
Q = np.array([robot.random_configuration(rng) for _ in range(3000)])
S = geometry_kernel.survivors_packed
for q in Q[:10]:
    S(q, *packed, -1)
for rep in range(3):
    for name, last in (("no hull test", -1), ("hull test on (10, 17)", k)):
        t = time.process_time()
        hits = sum(S(q, *packed, last)[2] >= 0 for q in Q)
        print("%-22s %.2f us/query, proven %d" % (name, (time.process_time() - t) / len(Q) * 1e6, hits))
