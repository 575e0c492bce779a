"""CPU ms of each of 6 feasible PTP_3 evaluations of the good IMPROV arm in a fresh process (seeds 0-5): the first
pays the proofs (and any first-use set-up), the later ones reuse the kept verdicts. --src CHECKOUT."""
import sys, time
src = sys.argv[sys.argv.index("--src") + 1]
sys.path.insert(0, src + "/src")
from pathlib import Path
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.solve import warm_up; warm_up()
from robodesign.design.problem import Problem
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.search_space import Candidate
import robodesign
S = Path('/work/shared/cobra')
p = Problem.build(S / "tasks/simple/PTP_3.json", S / "modules/IMPROV", "cyc")
out = []
for s in range(6):
    c = time.process_time()
    e = Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(("1", "21", "4", "22", "5", "23", "12")))
    out.append(round((time.process_time() - c) * 1e3, 1))
    assert e.feasible
print(Path(robodesign.__file__).parent, "cpu ms per evaluation:", out)
