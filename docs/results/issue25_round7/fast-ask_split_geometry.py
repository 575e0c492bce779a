"""Ask CPU of replayed searches: fresh space (builds included) vs a space whose per-order geometry is pre-filled."""

import statistics
import sys
import time

sys.path.insert(0, "/work/main/experiments")
from robodesign.solvers import ik_kernel

ik_kernel.warm_up()
from robodesign.design.solve import warm_up

warm_up()
from profile_evaluator import family_tasks

from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
from robodesign.design.optimize import Budget, SerialExecutor, Study, create_optimizer
from robodesign.design.problem import Problem


def search(problem, evaluator):
    opt = create_optimizer("genetic", problem, seed=0, options={})
    spent = [0.0]
    ask = opt.ask

    def timed():
        t = time.process_time()
        try:
            return ask()
        finally:
            spent[0] += time.process_time() - t

    opt.ask = timed
    Study(opt, SerialExecutor(evaluator), Budget.parse("200evals"), batch_size=16).run()
    return spent[0]


for fam, task in (("bpo2024", "oven_hard"), ("bpo2024", "middle_oven"), ("whitman2020_g5o5", "0000")):
    f = next(f for f in family_tasks(fam, 2, 0) if task in f.name)
    problem = Problem.build(f, "robodesign_arm", "cyc")
    ev = Evaluator(EvaluatorSpec(problem, evaluation_settings(), seed=0))
    seen = {}

    def rec(c):
        seen[c.key()] = e = ev(c)
        return e

    search(problem, rec)
    geo = dict(problem.space._cache("_memo_reach"))
    memos = {k: dict(v) for k, v in problem.space.__dict__.items() if k.startswith("_memo")}
    full, pre, allm = [], [], []
    for r in range(int(sys.argv[1])):
        full.append(search(Problem.build(f, "robodesign_arm", "cyc"), lambda c: seen[c.key()]))
        p = Problem.build(f, "robodesign_arm", "cyc")
        p.space._cache("_memo_reach").update(geo)
        pre.append(search(p, lambda c: seen[c.key()]))
        p = Problem.build(f, "robodesign_arm", "cyc")
        for k, v in memos.items():
            p.space._cache(k).update(v)
        allm.append(search(p, lambda c: seen[c.key()]))
    print(
        task,
        "fresh %.3f  geometry pre-filled %.3f  all memos %.3f"
        % (statistics.median(full), statistics.median(pre), statistics.median(allm)),
        [round(x, 3) for x in full],
        [round(x, 3) for x in pre],
        [round(x, 3) for x in allm],
    )
