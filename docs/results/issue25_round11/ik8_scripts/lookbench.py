import sys, time
src = sys.argv[1]; PROF = "--prof" in sys.argv
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import SHARED
from robodesign.design.problem import Problem
from robodesign.model import collision_cull as cc, pair_clearance as pc
from robodesign.model.cell import build_robot
from robodesign.formats.assembly import Assembly
ptp3 = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
rng = np.random.default_rng(0); cands = [ptp3.space.random_candidate(rng) for _ in range(900)]
ms = ptp3.module_set
cul = []
for i in (8, 14, 98, 161):
    c = cands[i]
    r = build_robot(ptp3.task, ms, Assembly.from_order(ms, list(c.order)), ptp3.base_pose(c))
    cul.append(cc.CollisionCuller(r))
def run():
    n = 0
    for cu in cul:
        cu._chains.clear()
        objs = cu.robot.geom_model.geometryObjects
        for k in cu.self_k.tolist():
            a, b = int(cu.first[k]), int(cu.second[k])
            ends = [(cu.shapes[x], np.array(objs[x].placement.homogeneous), int(cu.parent[x])) for x in (a, b)]
            pc.never_collides(cu.robot.kinematic_model, ends[0], ends[1], float(cu.margin[k]) + cc.SLACK, cu._chains, prove=False)
            n += 1
    return n
n = run()
t = time.process_time(); n = run(); dt = time.process_time() - t
print("pairs", n, "us per lookup", dt / n * 1e6)
if PROF:
    import cProfile, pstats; pr = cProfile.Profile(); pr.enable(); run(); pr.disable()
    pstats.Stats(pr).sort_stats("tottime").print_stats(15)
