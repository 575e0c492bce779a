import sys, time
exec(open(__import__('os').path.join(__import__('os').path.dirname(__file__), 'fast-ik4_replay_ptp3.py')).read().split("mode = sys.argv[2]")[0])
from robodesign.model.collision_cull import culler_of
import numpy as np
qs = []
import robodesign.model.collision_cull as cc
orig_ic = cc.CollisionCuller.in_collision
def spy(self, q):
    qs.append((self, np.array(q, dtype=float))); return orig_ic(self, q)
cc.CollisionCuller.in_collision = spy
replay()
cc.CollisionCuller.in_collision = orig_ic
cullers = {id(c): c for c, _ in qs}.values()
saved = {id(c): c._one[0][15].copy() for c in cullers}
def setp(on):
    for c in cullers:
        c._one[0][15][:] = saved[id(c)] if on else -np.inf
def run():
    return [c.in_collision(q) for c, q in qs]
setp(True); ref = run(); setp(False); assert run() == ref
res = {True: [], False: []}
for i in range(10):
    for on in ((True, False) if i % 2 else (False, True)):
        setp(on)
        t = time.process_time(); run(); res[on].append((time.process_time() - t) / 20 * 1e3)
print(len(qs), 'culler queries of 20 evaluations;', sum(ref), 'colliding')
print('ms per evaluation, proofs off:', ' '.join('%.2f' % x for x in res[False]))
print('ms per evaluation, proofs on: ', ' '.join('%.2f' % x for x in res[True]))
print('median off %.2f on %.2f; per-pair ratios median %.3f' % (np.median(res[False]), np.median(res[True]), np.median([b / a for a, b in zip(res[False], res[True])])))
