import sys, time, copy, hashlib
sys.path.insert(0, sys.argv[1] + '/src')
exec(open(__import__('os').path.join(__import__('os').path.dirname(__file__), 'fast-ik4_micro_head.py')).read())
calls = []
orig2 = ik.solve_ik
def rec(robot, goal, rng=None, **k):
    calls.append((robot, goal, copy.deepcopy(rng), k)); return orig2(robot, goal, rng, **k)
ik.solve_ik = rec
import robodesign.design.goal_planner as gp
gp_orig = getattr(gp, 'solve_ik', None)
if gp_orig is not None: gp.solve_ik = rec
for s in range(20):
    Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD))
ik.solve_ik = orig2
if gp_orig is not None: gp.solve_ik = gp_orig
print(len(calls), 'calls')
def replay():
    h = hashlib.sha256()
    for robot, goal, rng, k in calls:
        r = orig2(robot, goal, copy.deepcopy(rng), **k)
        for q in r.solutions: h.update(q.tobytes())
        h.update(repr({a: b for a, b in r.stats.items() if a != 'time'}).encode())
    return h.hexdigest()[:12]
mode = sys.argv[2] if len(sys.argv) > 2 else 'time'
if mode == 'time':
    for i in range(int(sys.argv[3]) if len(sys.argv) > 3 else 5):
        c = time.process_time(); hh = replay(); print('replay cpu ms per eval %.2f' % ((time.process_time() - c) / 20 * 1e3), hh)
else:
    import cProfile, pstats
    replay()
    pr = cProfile.Profile(); pr.enable(); hh = replay(); pr.disable(); print(hh)
    pstats.Stats(pr).sort_stats(mode).print_stats(int(sys.argv[3]) if len(sys.argv) > 3 else 40)
