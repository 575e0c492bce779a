"""In one process (run from /work/main; argv[1]: the branch's checkout, argv[2]: ptp3 | ga, argv[3]: rounds):
_Memoized.first_invalid of this session's start (1b535a2, read from /tmp/base_s7 and bound to the branch's module)
against the branch's, alternating, the same code otherwise.
ptp3: plan_path of the good PTP_3 arm's captured planning calls (5 seeds, replayed 4 times): CPU ms per evaluation.
ga: the genetic search of bench_front_ga.py on the two whitman2020 g5o5 tasks (200 evaluations each): CPU seconds
and the plan stage's seconds, and the evaluations' verdicts and costs (the same in both)."""
import re
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(sys.argv[1]).resolve() / "src"))
from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.search_space import Candidate  # noqa: E402
from robodesign.design.solve import warm_up  # noqa: E402
from robodesign.solvers import ik_kernel  # noqa: E402
from robodesign.solvers import planning as PL  # noqa: E402

ik_kernel.warm_up()
warm_up()
old_src = Path("/tmp/base_s7/src/robodesign/solvers/planning.py").read_text()
body = re.search(r"\n(    def first_invalid\(.*?)\n\n\n", old_src, re.S).group(1)
ns = dict(vars(PL))
exec("class _Old:\n" + body, ns)
OLD, NEW = ns["_Old"].first_invalid, PL._Memoized.first_invalid
mode, rounds = sys.argv[2], int(sys.argv[3]) if len(sys.argv) > 3 else 3
print("# src:", PL.__file__, mode, flush=True)


def ptp3():
    shared = Path("/work/shared/cobra")
    p = Problem.build(shared / "tasks" / "simple" / "PTP_3.json", shared / "modules" / "IMPROV", "cyc")
    plans, real = [], PL.plan_path
    PL.plan_path = lambda *a, **k: (plans.append((a, k)), real(*a, **k))[1]
    for s in range(5):
        Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(("1", "21", "4", "22", "5", "23", "12")))
    PL.plan_path = real
    res = {"old": [], "new": []}
    for r in range(rounds):
        for which in (("old", "new") if r % 2 == 0 else ("new", "old")):
            PL._Memoized.first_invalid = OLD if which == "old" else NEW
            t = time.process_time()
            out = [real(*a, **k) for _ in range(4) for a, k in plans]
            res[which].append((time.process_time() - t) / 20 * 1e3)
            res.setdefault(which + "_stats", [(o.success, o.stats["checks"], o.stats["lookups"],
                                              o.stats["distinct_states"]) for o in out])
    assert res["old_stats"] == res["new_stats"]
    o, n = res["old"], res["new"]
    print("plan_path, CPU ms per evaluation: old median %.2f (min %.2f), new median %.2f (min %.2f); ratio of medians"
          " %.2f; per round %s" % (statistics.median(o), min(o), statistics.median(n), min(n),
                                   statistics.median(n) / statistics.median(o),
                                   " ".join("%.2f" % (b / a) for a, b in zip(o, n))))


def ga():
    from robodesign.design.optimize import Budget, SerialExecutor, Study, create_optimizer
    sys.path.append("experiments")
    from profile_evaluator import family_tasks
    files = family_tasks("whitman2020_g5o5", 2, 0)
    res = {}
    for r in range(rounds):
        for which in (("old", "new") if r % 2 == 0 else ("new", "old")):
            PL._Memoized.first_invalid = OLD if which == "old" else NEW
            for f in files:
                problem = Problem.build(f, "robodesign_arm", "cyc")
                ev = Evaluator(EvaluatorSpec(problem, evaluation_settings(), seed=0))
                opt = create_optimizer("genetic", problem, seed=0, options={})
                c0 = time.process_time()
                out = Study(opt, SerialExecutor(ev), Budget.parse("200evals"), batch_size=16).run()
                cpu = time.process_time() - c0
                plan = sum(s["seconds"] for e in out.history for s in e.stages if s["name"] == "plan")
                seen = [(e.stage, repr(e.cost)) for e in out.history]
                res.setdefault((f.name, which), []).append((cpu, plan))
                assert res.setdefault((f.name, "seen"), seen) == seen
                print(f"round {r + 1} {f.name[:34]} {which}: cpu {cpu:.2f} s, plan {plan:.2f} s", flush=True)
    for f in files:
        a, b = res[(f.name, "old")], res[(f.name, "new")]
        print(f"{f.name[:34]}: median cpu {statistics.median(x[0] for x in a):.2f} → "
              f"{statistics.median(x[0] for x in b):.2f} s, plan {statistics.median(x[1] for x in a):.2f} → "
              f"{statistics.median(x[1] for x in b):.2f} s; per round plan ratio "
              + " ".join(f"{y[1] / x[1]:.2f}" for x, y in zip(a, b)))


ptp3() if mode == "ptp3" else ga()
