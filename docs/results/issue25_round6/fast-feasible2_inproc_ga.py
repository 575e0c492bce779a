"""In one process (run from /work/main, argv[1]: checkout): the genetic search of bench_front_ga.py on the two
whitman2020 g5o5 tasks, 200 evaluations each, with and without the planner's pair certificates, alternating (the
same code otherwise; the same search path): CPU seconds of the study and the plan stage's seconds, per round."""
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(sys.argv[1]).resolve() / "src"))
from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings  # noqa: E402
from robodesign.design.optimize import Budget, SerialExecutor, Study, create_optimizer  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.solve import warm_up  # noqa: E402
from robodesign.solvers import ik_kernel  # noqa: E402
from robodesign.solvers import planning as PL  # noqa: E402

sys.path.append("experiments")   # (after robodesign is imported: profile_evaluator puts its own src/ first)
from profile_evaluator import family_tasks  # noqa: E402

print('# src:', PL.__file__, flush=True)
ik_kernel.warm_up()
warm_up()
real = PL.PairCertificates.of
rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 3
files = family_tasks("whitman2020_g5o5", 2, 0)
res = {}
for r in range(rounds):
    for on in ((False, True) if r % 2 == 0 else (True, False)):
        PL.PairCertificates.of = real if on else (lambda *a: None)
        for f in files:
            problem = Problem.build(f, "robodesign_arm", "cyc")
            ev = Evaluator(EvaluatorSpec(problem, evaluation_settings(), seed=0))
            opt = create_optimizer("genetic", problem, seed=0, options={})
            c0 = time.process_time()
            out = Study(opt, SerialExecutor(ev), Budget.parse("200evals"), batch_size=16).run()
            cpu = time.process_time() - c0
            plan = sum(s["seconds"] for e in out.history for s in e.stages if s["name"] == "plan")
            res.setdefault((f.name, on), []).append((cpu, plan))
            print(f"round {r + 1} {f.name[:34]} certificates={on}: cpu {cpu:.2f} s, plan {plan:.2f} s", flush=True)
for f in files:
    a, b = res[(f.name, False)], res[(f.name, True)]
    print(f"{f.name[:34]}: median cpu {statistics.median(x[0] for x in a):.2f} → {statistics.median(x[0] for x in b):.2f}"
          f" s, plan {statistics.median(x[1] for x in a):.2f} → {statistics.median(x[1] for x in b):.2f} s; per round"
          f" plan ratio " + " ".join(f"{y[1] / x[1]:.2f}" for x, y in zip(a, b)))
