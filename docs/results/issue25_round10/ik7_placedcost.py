import sys, time
sys.path.insert(0, sys.argv[1] + "/src"); sys.path.insert(0, "/work/h-ik7/tests")   # (ptp3_robot)
import numpy as np
from test_inner_spheres import ptp3_robot
from robodesign.model.inner_spheres import placed_inner_spheres
from robodesign.model.collision_cull import CollisionCuller
robot = ptp3_robot()
gm = robot.geom_model
objs = list(gm.geometryObjects)[:robot.n_collision_geometries]
shapes = [o.geometry for o in objs]; Rs = [o.placement.rotation for o in objs]; ts = [o.placement.translation for o in objs]
placed_inner_spheres(shapes, Rs, ts)
N = 2000
for rep in range(3):
    t = time.process_time()
    for i in range(N): placed_inner_spheres(shapes, Rs, ts)
    t1 = time.process_time() - t
    t = time.process_time()
    for i in range(300): CollisionCuller(robot)
    t2 = time.process_time() - t
    print("placed_inner_spheres %.1f us, CollisionCuller() %.1f us" % (t1 / N * 1e6, t2 / 300 * 1e6))
