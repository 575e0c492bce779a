"""CPU time of plan_path on the good arm's captured planning calls (argv[1]: checkout): median over 15 repeats of the
sum over 5 seeds' calls; also the same for check()."""
import sys, time, statistics
from pathlib import Path
sys.path.insert(0, str(Path(sys.argv[1]) / "src"))
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.design import solve as S
from robodesign.solvers import planning as G
S.warm_up()
SHARED = Path("/work/shared/cobra")
GOOD = ("1", "21", "4", "22", "5", "23", "12")
p = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
plans, checks = [], []
o_plan, o_check = G.plan_path, S.check
G.plan_path = lambda *a, **k: (plans.append((a, k)), o_plan(*a, **k))[1]
S.check = lambda *a, **k: (checks.append((a, k)), o_check(*a, **k))[1]
for s in range(5):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
G.plan_path, S.check = o_plan, o_check
tp, tc = [], []
for rep in range(15):
    t = time.process_time()
    for a, k in plans: o_plan(*a, **k)
    tp.append((time.process_time() - t) / 5)
    t = time.process_time()
    for a, k in checks: o_check(*a, **k)
    tc.append((time.process_time() - t) / 5)
print("plan ms per evaluation (median, min): %.2f %.2f   check: %.2f %.2f" % (
    statistics.median(tp) * 1e3, min(tp) * 1e3, statistics.median(tc) * 1e3, min(tc) * 1e3))
