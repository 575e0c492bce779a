import sys, time, hashlib
src, task, cost, budget, seed = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
sys.path.insert(0, src + "/src")
from pathlib import Path
SHARED = Path("/work/shared/cobra")
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.optimize import Budget, SerialExecutor, Study, create_optimizer
from robodesign.design.problem import Problem
from robodesign.design.solve import warm_up
from robodesign.solvers import ik_kernel
ik_kernel.warm_up(); warm_up()
p = Problem.build(SHARED / "tasks" / "simple" / f"{task}.json", SHARED / "modules" / "IMPROV", cost, base_search=True)
rows = []
st = Study(create_optimizer("genetic", p, seed=seed), SerialExecutor(Evaluator(EvaluatorSpec(p, seed=seed))), Budget(evaluations=budget),
           on_evaluation=lambda i, e, b: rows.append((e.stage, bool(e.feasible), round(e.cost, 9) if e.feasible else None)))
t = time.process_time(); st.run(); cpu = time.process_time() - t
print(f"{src} {task} {cost} seed {seed}: cpu {cpu:.2f} s, {len(rows)/cpu:.1f} ev/cpu-s, feasible {sum(r[1] for r in rows)}, sig {hashlib.sha1(repr(rows).encode()).hexdigest()[:10]}")
