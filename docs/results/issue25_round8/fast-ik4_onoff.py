import sys, time
exec(open(__import__('os').path.join(__import__('os').path.dirname(__file__), 'fast-ik4_replay_ptp3.py')).read().split("mode = sys.argv[2]")[0])
from robodesign.model.collision_cull import culler_of
import numpy as np
robots = {id(r): r for r, *_ in calls}.values()
saved = {}
for r in robots:
    c = culler_of(r)
    if c._one is None: c._one = c._kernel_args()
    saved[id(r)] = c._one[0][15].copy()
def setp(on):
    for r in robots:
        a = culler_of(r)._one[0][15]
        a[:] = saved[id(r)] if on else -np.inf
res = {True: [], False: []}
for i in range(6):
    for on in ((True, False) if len(sys.argv) > 2 and sys.argv[2] == "on-first" else (False, True)):
        setp(on)
        c = time.process_time(); hh = replay(); res[on].append((time.process_time() - c) / 20 * 1e3)
        print('proofs' if on else 'off   ', 'replay cpu ms per eval %.2f' % res[on][-1], hh, flush=True)
print('median off %.2f on %.2f ratio of medians %.3f; per-pair ratios %s' % (np.median(res[False]), np.median(res[True]), np.median(res[True]) / np.median(res[False]), ' '.join('%.3f' % (b / a) for a, b in zip(res[False], res[True]))))
