import sys, time
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import SHARED
from robodesign.design.problem import Problem
from robodesign.model.collision_cull import DistanceField
from robodesign.model.cell import build_robot
from robodesign.formats.assembly import Assembly
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
rng = np.random.default_rng(0); c = ptp3.space.random_candidate(rng); ms = ptp3.module_set
r = build_robot(ptp3.task, ms, Assembly.from_order(ms, list(c.order)), ptp3.base_pose(c))
objs = r.geom_model.geometryObjects
ts = []
o = [o for o in list(objs)[r.n_collision_geometries:] if len(DistanceField(o.geometry, o.placement.homogeneous).values)][0]
for rep in range(7):   # a new field each time (every cell unknown), 2400 cells in batches of 6
    f = DistanceField(o.geometry, o.placement.homogeneous)
    flats = [rng.integers(len(f.values), size=6) for _ in range(400)]
    t = time.process_time()
    for fl in flats: f.fill(fl)
    ts.append((time.process_time() - t) / (len(flats) * 6) * 1e6)
print(src, "us per cell (7 fresh fields)", [round(x, 1) for x in ts], "median", round(sorted(ts)[3], 1))
