"""Old and new DistanceField.fill side by side in one process (alternating, fresh fields each time)."""
import sys, time
sys.path.insert(0, "/tmp/ik8_c2/src"); sys.path.insert(0, "/work/main/experiments")
SIZE = int(sys.argv[1]); sys.argv[1:] = ["--src", "/tmp/ik8_c2"]
import numpy as np, coal
from profile_evaluator import SHARED
from robodesign.design.problem import Problem
from robodesign.model import collision_cull as cc
from robodesign.model.cell import build_robot
from robodesign.formats.assembly import Assembly
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
rng = np.random.default_rng(0); c = ptp3.space.random_candidate(rng); ms = ptp3.module_set
r = build_robot(ptp3.task, ms, Assembly.from_order(ms, list(c.order)), ptp3.base_pose(c))
o = [o for o in list(r.geom_model.geometryObjects)[r.n_collision_geometries:] if len(cc.DistanceField(o.geometry, o.placement.homogeneous).values)][0]
new_fill = cc.DistanceField.fill
def old_exact(self, c):
    self._res.clear()
    return float(coal.distance(self._point, coal.Transform3s(cc._EYE, c), self.shape, self.tf, self._req, self._res))
def old_fill(self, flat):
    v = self.values
    dz, dy = int(self.grid_dim[2]), int(self.grid_dim[1])
    for f in np.unique(flat).tolist():
        if np.isnan(v[f]):
            idx = self.grid_lo + np.array([f // (dy * dz), f // dz % dy, f % dz])
            v[f] = old_exact(self, (idx + 0.5) * self.cell)
    return v[flat]
res = {"old": [], "new": []}
size = SIZE
for rep in range(10):
    for name, fn in (("old", old_fill), ("new", new_fill)) if rep % 2 else (("new", new_fill), ("old", old_fill)):
        f = cc.DistanceField(o.geometry, o.placement.homogeneous)
        g_ = np.random.default_rng(rep); flats = [g_.integers(len(f.values), size=int(g_.choice([1, 3, 7, 24], p=[318/1319, 429/1319, 326/1319, 246/1319]))) for _ in range(300)]
        t = time.process_time()
        for fl in flats: fn(f, fl)
        res[name].append((time.process_time() - t) / sum(map(len, flats)) * 1e6)
for k, v in res.items(): print(k, "batch", size, "us per cell median", round(float(np.median(v)), 2), [round(x, 1) for x in v])
