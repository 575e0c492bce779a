import sys, time
src = sys.argv[1]
sys.path.insert(0, src + "/src"); sys.path.insert(0, "/work/main/experiments")
SPECS = sys.argv[2:]; sys.argv[1:] = ["--src", src]
import numpy as np
from line_profiler import LineProfiler
from profile_evaluator import family_tasks
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
ik_kernel.warm_up(); warm_up()
problem = Problem.build(family_tasks("whitman2020_g5o5", 1, 0)[0], "robodesign_arm", "cyc")
ev = Evaluator(EvaluatorSpec(problem, seed=0))
rng = np.random.default_rng(0)
cands = [problem.space.random_candidate(rng) for _ in range(300)]
fail = [c for c in cands if (lambda e: e.stage == "ik" and not e.feasible)(ev.evaluate(c))]
ev = Evaluator(EvaluatorSpec(problem, seed=1)); ev.evaluate(cands[0])
import robodesign.design.solve as S, robodesign.model.robot as R, robodesign.model.cell as C, robodesign.formats.assembly as A
import robodesign.model.robot_build as RB, robodesign.design.goal_planner as GP, robodesign.solvers.ik as IK
import robodesign.design.evaluator as E, robodesign.model.robot_geometry as RG
lp = LineProfiler()
for spec in SPECS:
    lp.add_function(eval(spec))
lp.enable_by_count()
for c in fail * 3: ev.evaluate(c)
lp.disable_by_count()
print("n", len(fail)*3)
lp.print_stats(output_unit=1e-6)
