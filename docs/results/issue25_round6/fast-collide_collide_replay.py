"""Issue 25 round 6 (fast-collide): the genetic search's in_collision queries on a generated task (``--task``, default
bpo2024 oven_hard_s0_0001: 62 robots, 4891 queries; whitman2020's ``..._0001``; 200 evaluations, seed 0; recorded once
with ``--record`` into a pickle), replayed on fresh robots
of a checkout: the process CPU time of all the queries of each robot summed (everything the queries make on first
use included: the coal geometry model, the scratch space, the culler), the robot's build excluded. Prints the CPU
ms per round and a hash of every verdict.

    python fast-collide_collide_replay.py --src CHECKOUT --cases cases.pkl [--task T] [--rounds 3] [--record]
"""
import argparse
import hashlib
import pickle
import sys
import time

ap = argparse.ArgumentParser()
ap.add_argument("--src", required=True)
ap.add_argument("--cases", required=True)
ap.add_argument("--rounds", type=int, default=3)
ap.add_argument("--record", action="store_true")
ap.add_argument("--task", default="oven_hard", help="a substring of the generated task's name (bpo2024 or whitman2020)")
args = ap.parse_args()
sys.path.insert(0, args.src + "/src")
sys.path.insert(0, "/work/main/experiments")
import numpy as np  # noqa: E402
from profile_evaluator import family_tasks  # noqa: E402

from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.solve import warm_up  # noqa: E402
from robodesign.model import geometry_kernel  # noqa: E402
from robodesign.model.robot import Robot  # noqa: E402

warm_up()
geometry_kernel.warm_up()
family = "whitman2020_g5o5" if "whitman" in args.task else "bpo2024"
task = next(f for f in family_tasks(family, 2, 0) if args.task in f.name)
problem = Problem.build(task, "robodesign_arm", "cyc")
if args.record:
    from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
    from robodesign.design.optimize import Budget, SerialExecutor, Study, create_optimizer
    from robodesign.model import robot_geometry
    rec: dict = {}
    orig = robot_geometry.RobotGeometry.in_collision

    def spy(self, q):
        key = (id(self), self.base_pose.tobytes())
        if key not in rec:
            rec[key] = (self.assembly, self.base_pose.copy(), list(self.obstacles), self.safety_margin, [])
        rec[key][4].append(np.array(q, float))
        return orig(self, q)
    robot_geometry.RobotGeometry.in_collision = spy
    ev = Evaluator(EvaluatorSpec(problem, evaluation_settings(), seed=0))
    Study(create_optimizer("genetic", problem, seed=0, options={}), SerialExecutor(ev), Budget.parse("200evals"),
          batch_size=16).run()
    robot_geometry.RobotGeometry.in_collision = orig
    pickle.dump(list(rec.values()), open(args.cases, "wb"))
cases = pickle.load(open(args.cases, "rb"))
print("# src", args.src, "robots", len(cases), "queries", sum(len(c[4]) for c in cases), flush=True)
for rd in range(args.rounds):
    cpu, verdicts = 0.0, []
    for asm, T, obs, margin, qs in cases:
        r = Robot(problem.module_set, asm, base_pose=T)
        r.set_obstacles(obs, safety_margin=margin)
        t = time.process_time()
        verdicts.append([r.in_collision(q) for q in qs])
        cpu += time.process_time() - t
    print(f"round {rd}: in_collision cpu {cpu * 1e3:.1f} ms", flush=True)
print("verdict hash", hashlib.md5(pickle.dumps(verdicts)).hexdigest()[:12])
