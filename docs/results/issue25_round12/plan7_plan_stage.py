"""The plan stage of PTP_3's feasible fresh arms, in one process (issue 25, round 12, plan7).

Usage: ``python plan7_plan_stage.py CHECKOUT FEAS_PKL [--serve | --only I]`` (FEAS_PKL: a pickle of the fresh stream's feasible
candidates, /tmp/s11/feas.pkl). Evaluates the first candidate (warm-up), then the others once each with one
Evaluator, and prints one JSON line: per candidate the CPU seconds of its ``plan_path`` calls, their sum, and a hash
of every planned path (the same on every checkout that plans the same paths). ``--serve``: a worker of
plan7_paired_plan.py, evaluating candidate i (a line of stdin) when asked and answering its plan CPU seconds.
``--only I``: candidate I alone (after the warm-up).
"""
import hashlib
import json
import pickle
import sys
import time
from pathlib import Path

src, feas_pkl, serve = sys.argv[1], sys.argv[2], sys.argv[3:] == ["--serve"]
only = int(sys.argv[4]) if sys.argv[3:4] == ["--only"] else None
sys.path.insert(0, src + "/src")
sys.path.insert(0, "/work/main/experiments")
sys.argv[1:] = ["--src", src]
from profile_evaluator import SHARED  # noqa: E402

from robodesign.design.evaluator import Evaluator, EvaluatorSpec  # noqa: E402
from robodesign.design.problem import Problem  # noqa: E402
from robodesign.design.solve import warm_up  # noqa: E402
from robodesign.solvers import ik_kernel, planning  # noqa: E402

ik_kernel.warm_up()
warm_up()
problem = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
feasible = pickle.loads(Path(feas_pkl).read_bytes())
evaluator = Evaluator(EvaluatorSpec(problem, seed=1))
evaluator.evaluate(feasible[0])
plan_path, spent, paths = planning.plan_path, [0.0], hashlib.sha1()


def timed(*args, **kwargs):
    t = time.process_time()
    r = plan_path(*args, **kwargs)
    spent[0] += time.process_time() - t
    paths.update(r.path.tobytes())
    return r


planning.plan_path = timed
if serve:
    print("ready", flush=True)
    for line in sys.stdin:
        spent[0] = 0.0
        evaluator.evaluate(feasible[int(line)])
        print(json.dumps([spent[0], paths.hexdigest()[:12]]), flush=True)
    sys.exit(0)
per = []
for c in feasible[1:] if only is None else [feasible[only]]:
    spent[0] = 0.0
    evaluator.evaluate(c)
    per.append(round(spent[0], 5))
print(json.dumps({"src": src, "plan_cpu": per, "sum": round(sum(per), 4), "paths": paths.hexdigest()[:12]}))
