import sys
src = sys.argv[1]
sys.path.insert(0, src + "/src")
from pathlib import Path
from robodesign.solvers import ik_kernel
ik_kernel.warm_up()
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.design.solve import warm_up
import robodesign.solvers.ik as IK, robodesign.solvers.ik_accept as A, robodesign.model.collision_cull as C, robodesign.model.pair_scratch as PS
from line_profiler import LineProfiler
warm_up()
SH = Path("/work/shared/cobra")
p = Problem.build(SH/"tasks/simple/PTP_3.json", SH/"modules/IMPROV", "cyc")
GOOD = ("1","21","4","22","5","23","12")
Evaluator(EvaluatorSpec(p)).evaluate(Candidate(GOOD))
lp = LineProfiler()
for f in sys.argv[2:]:
    mod, name = f.split(".", 1)
    obj = {"IK": IK, "A": A, "C": C, "PS": PS}[mod]
    parts = name.split(".")
    for x in parts: obj = getattr(obj, x)
    lp.add_function(obj)
lp.enable()
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
lp.disable()
lp.print_stats(output_unit=1e-3)
