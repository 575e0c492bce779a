import sys, time, json
src = sys.argv[1]; PROF = "--prof" in sys.argv
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import SHARED
from robodesign.design.problem import Problem
from robodesign.model import collision_cull as cc, inner_spheres as isp, geometry_kernel
from robodesign.model.cell import build_robot
from robodesign.formats.assembly import Assembly
geometry_kernel.ready()
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
rng = np.random.default_rng(0); cands = [ptp3.space.random_candidate(rng) for _ in range(900)]
ms = ptp3.module_set
feas = json.load(open(__file__.rsplit("/", 1)[0] + "/feas.json"))
def robots():
    return [build_robot(ptp3.task, ms, Assembly.from_order(ms, list(cands[i].order)), ptp3.base_pose(cands[i])) for i in feas]
for r in robots():
    cc.CollisionCuller(r)._kernel_args()     # warm: shapes' spheres and hulls
def run(rs):
    isp._PLACED.clear(); cc._PROOFS.clear()
    t = time.process_time()
    for r in rs:
        c = cc.CollisionCuller(r); c._kernel_args()
    return (time.process_time() - t) / len(rs)
ts = []
for _ in range(5):
    rs = robots()
    for r in rs: r.geom_model   # (the robot's own lazy geometry made outside the timing)
    ts.append(run(rs))
print("culler init + kernel args, ms per robot:", [round(t * 1e3, 3) for t in ts], "min", round(min(ts)*1e3, 3))
if PROF:
    import cProfile, pstats; rs = robots(); [r.geom_model for r in rs]; pr = cProfile.Profile(); pr.enable(); run(rs); pr.disable()
    pstats.Stats(pr).sort_stats("tottime").print_stats(25)
