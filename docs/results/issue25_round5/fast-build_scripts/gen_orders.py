"""Generate random orders + base poses for the identity check and benchmark (pickled)."""
import pickle, sys, glob
import numpy as np
from robodesign.design.problem import Problem

def rand_pose(rng):
    q = rng.normal(size=4); q /= np.linalg.norm(q)
    w, x, y, z = q
    R = np.array([[1-2*(y*y+z*z), 2*(x*y-z*w), 2*(x*z+y*w)],
                  [2*(x*y+z*w), 1-2*(x*x+z*z), 2*(y*z-x*w)],
                  [2*(x*z-y*w), 2*(y*z+x*w), 1-2*(x*x+y*y)]])
    T = np.eye(4); T[:3, :3] = R; T[:3, 3] = rng.uniform(-1, 1, 3)
    return T

out = []
n_per = int(sys.argv[2])
specs = [(t, "robodesign_arm") for t in sorted(glob.glob("/work/main/results/tasks/profile_*/*.json"))]
specs.append(("/work/shared/cobra/tasks/simple/PTP_3.json", "/work/shared/cobra/modules/IMPROV"))
rng = np.random.default_rng(int(sys.argv[3]) if len(sys.argv) > 3 else 0)
for task, mods in specs:
    p = Problem.build(task, mods, "cyc")
    for k in range(n_per):
        order = p.space.random_order(rng)
        kind = k % 5
        T = None if kind == 0 else (np.eye(4) if kind == 1 else rand_pose(rng))
        out.append((task, mods, tuple(order), T))
print(len(out), "orders", len(specs), "specs")
pickle.dump(out, open(sys.argv[1], "wb"))
