import sys, time, timeit
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
import numpy as np
from profile_evaluator import family_tasks
from robodesign.design.problem import Problem
from robodesign.design.solve import robot_pool
from robodesign.model.collision_cull import distance_field, obstacle_bounds
from robodesign.model.robot_geometry import _placed_spheres
problem = Problem.build(family_tasks("whitman2020_g5o5", 1, 0)[0], "robodesign_arm", "cyc")
rng = np.random.default_rng(0)
c = problem.space.random_candidate(rng)
from robodesign import Assembly
pool = robot_pool(problem.task)
r = pool.take(problem.module_set, Assembly.from_order(problem.module_set, list(c.order)), problem.base_pose(c))
def fields():
    poses = [ob.pose for ob in r.obstacles]
    return obstacle_bounds([distance_field(ob.shape, T) for ob, T in zip(r.obstacles, poses)])
fields()
n=20000
print("fields", timeit.timeit(fields, number=n)/n*1e6)
objs = [(P, shape) for _, P, shape in r._root_geoms]
import inspect
args = (objs, r._root_key) if len(inspect.signature(_placed_spheres).parameters) == 2 else (objs,)
print("spheres", len(objs), timeit.timeit(lambda: _placed_spheres(*args), number=n)/n*1e6)
print("base_pairs_near", timeit.timeit(lambda: r._base_pairs_near(), number=n)/n*1e6)
print("base_collisions", timeit.timeit(lambda: r.base_collisions(), number=n)/n*1e6)
print("reach_bound", timeit.timeit(lambda: (setattr(r, "_reach", None), r.reach_bound()), number=n)/n*1e6)
from robodesign.model.box_screen import all_clear, boxes_of
from robodesign.model.collision_cull import SLACK
root, C, rr = r._root_spheres
T = r.base_pose
b = r._obstacle_bounds
print("place", timeit.timeit(lambda: C @ T[:3, :3].T + T[:3, 3], number=n)/n*1e6)
Cw = C @ T[:3, :3].T + T[:3, 3]
print("lim", timeit.timeit(lambda: rr + (r.safety_margin + SLACK), number=n)/n*1e6)
lim = rr + (r.safety_margin + SLACK)
print("boxes_of", timeit.timeit(lambda: boxes_of(b), number=n)/n*1e6)
bx = boxes_of(b)
print("all_clear", all_clear(bx, Cw, lim), timeit.timeit(lambda: all_clear(bx, Cw, lim), number=n)/n*1e6)
