import sys, os, time
sys.argv=['x', '--src', os.environ.get('SRC', '/work/h-fast-fail6')]; sys.path.insert(0,'experiments')
import profile_evaluator as pe
from robodesign.design.problem import Problem
from robodesign.design.solve import robot_pool
from robodesign.formats.assembly import Assembly
from robodesign.model.collision_cull import distance_field, obstacle_bounds
from robodesign.model import robot_geometry as rg
import numpy as np
f = pe.family_tasks(os.environ.get('FAM',"whitman2020_g5o5"), 1, 0)[0]
problem = Problem.build(f, "robodesign_arm", "cyc")
pool = robot_pool(problem.task)
obs = pool.obstacles
print(len(obs), 'obstacles')
def T(label, fn, n=2000):
    b=[]
    for r in range(5):
        t=time.process_time()
        for _ in range(n): fn()
        b.append(time.process_time()-t)
    print(f"{label}: {min(b)/n*1e6:.2f} us")
T('fields+bounds', lambda: obstacle_bounds([distance_field(ob.shape, ob.pose) for ob in obs]))
rng=np.random.default_rng(0)
c=problem.space.random_candidate(rng)
ms=problem.module_set
a=Assembly.from_order(ms, list(c.order)); bp=problem.base_pose(c)
r=pool.take(ms,a,bp)
def bpn():
    r._root_spheres=None; r._obstacle_bounds=None; r._base_pairs_near()
def bpn2():
    r._base_pairs_near()
T('base_pairs_near fresh', bpn)
T('base_pairs_near cached', bpn2)
def sph():
    rg._placed_spheres([(P, shape) for _, P, shape in r._root_geoms])
T('placed_spheres', sph)
print('geom made', r._geom_model is not None)
def only_spheres():
    r._root_spheres=None; r._base_pairs_near()
def only_bounds():
    r._obstacle_bounds=None; r._base_pairs_near()
T('reset spheres', only_spheres)
T('reset bounds', only_bounds)
from robodesign.model import collision_cull as cc
from line_profiler import LineProfiler
lp=LineProfiler(); lp.add_function(rg.RobotGeometry._base_pairs_near); lp.add_function(cc.ObstacleBounds.near)
lp.enable_by_count()
for _ in range(2000): only_bounds()
for _ in range(2000): bpn2()
lp.disable_by_count(); lp.print_stats(output_unit=1e-6)
