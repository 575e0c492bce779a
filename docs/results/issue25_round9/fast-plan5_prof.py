import sys, cProfile, pstats
src = sys.argv[1]
sys.path.insert(0, src + "/src")
from pathlib import Path
from robodesign.solvers import ik_kernel
ik_kernel.warm_up()
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.design.solve import warm_up
from robodesign.solvers import planning, timing
import robodesign.design.goal_planner as gp
warm_up()
SH = Path("/work/shared/cobra")
p = Problem.build(SH/"tasks/simple/PTP_3.json", SH/"modules/IMPROV", "cyc")
GOOD = ("1","21","4","22","5","23","12")
Evaluator(EvaluatorSpec(p)).evaluate(Candidate(GOOD))
pr = cProfile.Profile()
stage = sys.argv[2]
def wrap(f):
    def g(*a, **k):
        pr.enable()
        try: return f(*a, **k)
        finally: pr.disable()
    return g
if stage == "cap":
    gp.GoalPlanner.choose_and_plan = wrap(gp.GoalPlanner.choose_and_plan)
elif stage == "both":
    gp.GoalPlanner.choose_and_plan = wrap(gp.GoalPlanner.choose_and_plan)
    gp.GoalPlanner.time_parameterize = wrap(gp.GoalPlanner.time_parameterize)
elif stage == "tp":
    gp.GoalPlanner.time_parameterize = wrap(gp.GoalPlanner.time_parameterize)
elif stage == "plan":
    planning.plan_path = wrap(planning.plan_path)
else:
    gp.time_parameterize = wrap(gp.time_parameterize)
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
st = pstats.Stats(pr); st.sort_stats(sys.argv[3] if len(sys.argv) > 3 else "tottime").print_stats(45)
