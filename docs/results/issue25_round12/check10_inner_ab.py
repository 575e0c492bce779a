"""The inner spheres of every IMPROV and primitive module shape made once (a new process's first arms pay this per
shape), CPU seconds; argv[1]: checkout root. Run alternately on two checkouts."""
import sys
import time

sys.path.insert(0, sys.argv[1] + "/src")
sys.path.insert(0, "/work/main/tests")
from test_inner_spheres import module_shapes  # noqa: E402

from robodesign.model import inner_spheres as kept  # noqa: E402
from robodesign.model.inner_spheres import inner_spheres  # noqa: E402

import scipy.spatial  # noqa: E402,F401  (its import outside the timing)

shapes = module_shapes()
kept._INNER.clear()   # (building the robots above may have made some: all made again below)
t = time.process_time()
for s in shapes:
    inner_spheres(s)
print(f"{sys.argv[1]}: inner spheres of {len(shapes)} module shapes, CPU {time.process_time() - t:.3f} s")
