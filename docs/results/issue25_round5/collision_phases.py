"""Issue 25 round 5 (fast-ikfail), a one-off diagnosis: record every robot's in_collision queries in the genetic
search (bpo2024 oven_hard_s0_0001, 200 evaluations), then replay them on fresh robots and time the phases of the
collision queries (ms summed over the robots): gmodel (the coal geometry model), gdata (its scratch space with the
margins), first, plain (queries 2-12: every pair), cull (query 13: the culler's set-up + its first query), rest
(the culled queries); cinit/kargs: CollisionCuller.__init__ and _kernel_args alone. It prints a hash of every
robot's verdicts and of the final state of its scratch space (coal's serialisation of every collision request and
result: GJK guesses, contacts) — equal hashes mean the same coal queries with the same answers.
usage: python collision_phases.py SRC OUT.pkl [rounds]   (run from anywhere; /work/main/experiments for tasks)"""
import sys, time, pickle, hashlib
src, out = sys.argv[1], sys.argv[2]
rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 3
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
import numpy as np
from robodesign.model import collision_cull
_CI = collision_cull.CollisionCuller.__init__
_KA = collision_cull.CollisionCuller._kernel_args
TT = {"cinit": 0.0, "kargs": 0.0}
def ci(self, robot):
    t = time.perf_counter(); _CI(self, robot); TT["cinit"] += time.perf_counter() - t
def ka(self):
    t = time.perf_counter(); x = _KA(self); TT["kargs"] += time.perf_counter() - t; return x
import pinocchio as pin
from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
from robodesign.design.optimize import Budget, SerialExecutor, Study, create_optimizer
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
from robodesign.model import robot_geometry
from robodesign.model.robot import Robot
ik_kernel.warm_up(); warm_up()
from profile_evaluator import family_tasks
f = [f for f in family_tasks("bpo2024", 2, 0) if "oven_hard" in f.name][0]
problem = Problem.build(f, "robodesign_arm", "cyc")
ev = Evaluator(EvaluatorSpec(problem, evaluation_settings(), seed=0))
opt = create_optimizer("genetic", problem, seed=0, options={})
rec = {}
orig = robot_geometry.RobotGeometry.in_collision
def spy(self, q):
    key = (id(self), self.base_pose.tobytes())
    if key not in rec:
        rec[key] = (self.module_set, self.assembly, self.base_pose.copy(), list(self.obstacles), self.safety_margin, [])
    rec[key][5].append(np.array(q, float))
    return orig(self, q)
robot_geometry.RobotGeometry.in_collision = spy
Study(opt, SerialExecutor(ev), Budget.parse("200evals"), batch_size=16).run()
robot_geometry.RobotGeometry.in_collision = orig
cases = list(rec.values())
print("robots", len(cases), "queries", sum(len(c[5]) for c in cases))

def state(r):
    gd = r._geom_data
    if gd is None:
        return None
    return hashlib.md5(b"".join(x.saveToString().encode() for x in gd.collisionRequests)
                       + b"".join(x.saveToString().encode() for x in gd.collisionResults)).hexdigest()

results, times = [], []
for rd in range(rounds):
    tt = {"gmodel": 0.0, "gdata": 0.0, "build": 0.0, "first": 0.0, "plain": 0.0, "cull": 0.0, "rest": 0.0}
    res = []
    ncull = 0
    for ms, asm, T, obs, m, qs in cases:
        t = time.perf_counter()
        r = Robot(ms, asm, base_pose=T)
        r.set_obstacles(obs, safety_margin=m)
        t1 = time.perf_counter(); tt["build"] += t1 - t
        if len(qs) > 0:
            r.geom_model; t2 = time.perf_counter(); tt["gmodel"] += t2 - t1
            r.geom_data; t3 = time.perf_counter(); tt["gdata"] += t3 - t2
            r._plain_queries = -1   # as when in_collision makes geom_data (its count restarts after the first query)
        v = []
        for i, q in enumerate(qs):
            t = time.perf_counter()
            v.append(r.in_collision(q))
            dt = time.perf_counter() - t
            tt["first" if i == 0 else "plain" if i < 12 else "cull" if i == 12 else "rest"] += dt
        res.append((v, state(r)))
        ncull = ncull + (r._culler is not None)
    results = res
    print({k: round(x * 1e3, 1) for k, x in TT.items()}); TT.update(cinit=0.0, kargs=0.0)
    if rd == 0:
        collision_cull.CollisionCuller.__init__ = ci; collision_cull.CollisionCuller._kernel_args = ka
    times.append(tt)
    print({k: round(x * 1e3, 1) for k, x in tt.items()}, "ms total over robots", "cullers", ncull, flush=True)
pickle.dump(results, open(out, "wb"))
import robodesign; print(robodesign.__file__)
print("verdict hash", hashlib.md5(pickle.dumps(results)).hexdigest()[:12])
#print("counts", sorted(len(c[5]) for c in cases))
