import sys, os, time
sys.argv=['x', '--src', os.environ.get('SRC', '/work/h-fast-fail6')]; sys.path.insert(0,'experiments')
import profile_evaluator as pe
from robodesign.design.problem import Problem
from robodesign.formats.assembly import Assembly
from robodesign.model import robot_build as rb
from robodesign.model.robot import Robot
import numpy as np
fam = os.environ.get('FAM', "whitman2020_g5o5")
f = pe.family_tasks(fam, 1, 0)[0]
problem = Problem.build(f, "robodesign_arm", "cyc")
rng = np.random.default_rng(0)
ms = problem.module_set
cands = [problem.space.random_candidate(rng) for _ in range(300)]
asms = []
for c in cands:
    try: asms.append(Assembly.from_order(ms, list(c.order)))
    except Exception: pass
print(len(asms), np.mean([len(rb.walk(ms,a,False).joint_ops) for a in asms]), 'joints', np.mean([len(rb.walk(ms,a,False).bodies) for a in asms]), 'bodies')
def T(label, fn, reps=5):
    best=[]
    for r in range(reps):
        t=time.process_time(); fn(); best.append(time.process_time()-t)
    print(f"{label}: {min(best)/len(asms)*1e6:.1f} us/asm")
T('from_order', lambda: [Assembly.from_order(ms, list(c.order)) for c in cands[:len(asms)]])
T('walk', lambda: [rb.walk(ms,a,False) for a in asms])
ws = [rb.walk(ms,a,False) for a in asms]
import pinocchio as pin
def remodel():
    for w in ws:
        w.model = pin.Model(); rb._model(w)
T('_model', remodel)
bp = problem.base_pose(cands[0])
T('Robot', lambda: [Robot(ms,a,base_pose=bp) for a in asms])
rs=[Robot(ms,a,base_pose=bp) for a in asms]
T('set_base_pose', lambda: [r.set_base_pose(bp) for r in rs])
T('Robot+del', lambda: [Robot(ms,a,base_pose=bp) for a in asms] and None)
