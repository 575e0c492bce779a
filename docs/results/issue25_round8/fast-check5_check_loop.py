"""judge.check of the good arm's 20 PTP_3 solutions (study seeds 0-19) in a loop, mean CPU ms per check on stderr. usage: --src X --reps R"""
import sys, time
src = sys.argv[sys.argv.index("--src") + 1]
reps = int(sys.argv[sys.argv.index("--reps") + 1])
sys.path.insert(0, src + "/src")
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.solve import warm_up; warm_up()
from robodesign.design.problem import Problem
from robodesign.judge import checker as ck
from pathlib import Path
S = Path('/work/shared/cobra')
GOOD = ("1", "21", "4", "22", "5", "23", "12")
p = Problem.build(S/"tasks/simple/PTP_3.json", S/"modules/IMPROV", "cyc")
sols = []
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.search_space import Candidate
import robodesign.design.solve as sv
orig = sv.check
def grab(task, sol, ms, **kw):
    sols.append((task, sol, ms, kw)); return orig(task, sol, ms, **kw)
sv.check = grab
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
sv.check = orig
import gc; gc.freeze()
for a in sols: ck.check(a[0], a[1], a[2], **a[3])
t = time.process_time()
for _ in range(reps):
    for a in sols: ck.check(a[0], a[1], a[2], **a[3])
print("check ms CPU mean", (time.process_time() - t) / (reps * len(sols)) * 1e3, file=sys.stderr)
