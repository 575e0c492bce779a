"""Replay the 60 solve_ik calls of 20 PTP_3 evaluations (the known-good arm); CPU ms per evaluation + hash.
usage: replay.py CHECKOUT [time ROUNDS | prof SORT N]"""
import sys, time, copy, hashlib
sys.path.insert(0, sys.argv[1] + '/src')
from robodesign.solvers import ik_kernel; ik_kernel.warm_up()
from robodesign.design.solve import warm_up; warm_up()
from robodesign.design.problem import Problem
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.search_space import Candidate
from pathlib import Path
import robodesign.solvers.ik as ik
S = Path('/work/shared/cobra')
GOOD = ("1", "21", "4", "22", "5", "23", "12")
p = Problem.build(S/"tasks/simple/PTP_3.json", S/"modules/IMPROV", "cyc")
Evaluator(EvaluatorSpec(p)).evaluate(Candidate(GOOD))
calls = []
orig = ik.solve_ik
def rec(robot, goal, rng=None, **k):
    calls.append((robot, goal, copy.deepcopy(rng), k)); return orig(robot, goal, rng, **k)
import robodesign.design.goal_planner as gp
ik.solve_ik = rec; gp.solve_ik = rec
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
ik.solve_ik = orig; gp.solve_ik = orig
def replay():
    h = hashlib.sha256()
    for robot, goal, rng, k in calls:
        r = orig(robot, goal, copy.deepcopy(rng), **k)
        for q in r.solutions: h.update(q.tobytes())
        h.update(repr({a: b for a, b in r.stats.items() if a != 'time'}).encode())
        g = rng.generator if hasattr(rng, 'generator') else rng
    return h.hexdigest()[:12]
mode = sys.argv[2] if len(sys.argv) > 2 else 'time'
if mode == 'time':
    replay()
    out = []
    for i in range(int(sys.argv[3]) if len(sys.argv) > 3 else 5):
        c = time.process_time(); hh = replay(); out.append((time.process_time() - c) / 20 * 1e3)
    print(len(calls), 'calls; cpu ms per eval', ' '.join('%.2f' % x for x in out), 'min %.2f' % min(out), hh)
else:
    import cProfile, pstats
    replay()
    pr = cProfile.Profile(); pr.enable(); hh = replay(); pr.disable(); print(hh)
    pstats.Stats(pr).sort_stats(sys.argv[3]).print_stats(int(sys.argv[4]) if len(sys.argv) > 4 else 40)
