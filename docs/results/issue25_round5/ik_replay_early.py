"""Record every solve_ik call of the GA (200 evals) on a task, then replay them on fresh robots (base contacts first,
as the base stage asks them), timing each robot's calls, and dump the solutions and stats (time excluded).
usage: ikreplay.py SRC TASKSUBSTR OUT.pkl ROUNDS"""
import sys, time, pickle, hashlib, copy
src, which, out, rounds = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
import numpy as np
from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
from robodesign.design.optimize import Budget, SerialExecutor, Study, create_optimizer
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel, ik
from robodesign.model.robot import Robot
import robodesign
assert robodesign.__file__.startswith(src), robodesign.__file__
ik_kernel.warm_up(); warm_up()
from profile_evaluator import family_tasks
fam = "whitman2020_g5o5" if "whitman" in which else "bpo2024"
f = [f for f in family_tasks(fam, 2, 0) if which in f.name][0]
problem = Problem.build(f, "robodesign_arm", "cyc")
ev = Evaluator(EvaluatorSpec(problem, evaluation_settings(), seed=0))
opt = create_optimizer("genetic", problem, seed=0, options={})
rec, order = {}, []
orig = ik.solve_ik
def spy(robot, goal, rng=None, **kw):
    key = (id(robot), robot.base_pose.tobytes())
    if key not in rec:
        rec[key] = (robot.module_set, robot.assembly, robot.base_pose.copy(), list(robot.obstacles), robot.safety_margin, [])
        order.append(key)
    rec[key][5].append((goal, copy.deepcopy(rng.bit_generator.state), kw))
    return orig(robot, goal, rng, **kw)
ik.solve_ik = spy
Study(opt, SerialExecutor(ev), Budget.parse("200evals"), batch_size=16).run()
ik.solve_ik = orig
cases = [rec[k] for k in order]
print("robots", len(cases), "calls", sum(len(c[5]) for c in cases), flush=True)

def run():
    res, per = [], []
    for ms, asm, T, obs, m, calls in cases:
        r = Robot(ms, asm, base_pose=T)
        r.set_obstacles(obs, safety_margin=m)
        r.base_collisions()
        t = time.perf_counter(); c = time.process_time()
        out = []
        for goal, state, kw in calls:
            g = np.random.default_rng(); g.bit_generator.state = state
            x = orig(r, goal, g, **kw)
            st = {k: v for k, v in x.stats.items() if k != "time"}
            out.append(([s.tobytes() for s in x.solutions], st, g.bit_generator.state))
        per.append((time.perf_counter() - t, time.process_time() - c))
        res.append(out)
    return res, per

for rd in range(rounds):
    res, per = run()
    fail = [p for p, o in zip(per, res) if not o[-1][0]]
    w, c = [p[0] for p in fail], [p[1] for p in fail]
    print(f"round {rd}: failing robots {len(fail)}: wall total {sum(w)*1e3:.1f} ms median {np.median(w)*1e3:.2f} ms; "
          f"cpu total {sum(c)*1e3:.1f} ms median {np.median(c)*1e3:.2f} ms", flush=True)
pickle.dump(res, open(out, "wb"))
print("result hash", hashlib.md5(pickle.dumps(res)).hexdigest()[:12])
