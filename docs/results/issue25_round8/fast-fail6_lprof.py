import sys, os
sys.argv=['x', '--src', os.environ.get('SRC', '/work/h-fast-fail6')]; sys.path.insert(0,'experiments')
import profile_evaluator as pe
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.solve import warm_up; warm_up()
from robodesign.design.problem import Problem
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
import numpy as np, importlib
from line_profiler import LineProfiler
fam = os.environ.get('FAM', "whitman2020_g5o5")
f = pe.family_tasks(fam, 1, 0)[0]
problem = Problem.build(f, "robodesign_arm", "cyc")
ev = Evaluator(EvaluatorSpec(problem, seed=0))
rng = np.random.default_rng(0)
cands = [problem.space.random_candidate(rng) for _ in range(1200)]
ikc=[c for c in cands if ev.evaluate(c).stage=='ik']
lp = LineProfiler()
for spec in os.environ['FUNCS'].split(','):
    mod, name = spec.rsplit(':',1)
    obj = importlib.import_module(mod)
    for part in name.split('.'):
        obj = getattr(obj, part)
    if isinstance(obj, property): obj = obj.fget
    lp.add_function(obj)
lp.enable_by_count()
for c in ikc: ev.evaluate(c)
lp.disable_by_count()
print(len(ikc))
lp.print_stats(output_unit=1e-6)
