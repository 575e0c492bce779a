"""Paired A/B in one process: the old package (robodesign_old, /tmp/hb_old) and the new (robodesign on PYTHONPATH),
alternating batches; ratio per pair, medians. Wall and CPU time."""
import pickle, sys, time, gc
sys.path.insert(0, "/tmp/hb_old/src")
import numpy as np
import robodesign, robodesign_old
from robodesign.design.problem import Problem as PN
from robodesign.formats.assembly import Assembly as AN
from robodesign.model.robot import Robot as RN
from robodesign.model.cell import RobotPool as PoolN
from robodesign_old.design.problem import Problem as PO
from robodesign_old.formats.assembly import Assembly as AO
from robodesign_old.model.robot import Robot as RO
from robodesign_old.model.cell import RobotPool as PoolO
print("new:", robodesign.__file__, " old:", robodesign_old.__file__)
orders = [o for o in pickle.load(open(sys.argv[1], "rb")) if o[1] == "robodesign_arm" and o[3] is not None]
rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 30
def prep(P, A):
    probs, items = {}, []
    for task, mods, order, T in orders:
        if task not in probs: probs[task] = P.build(task, mods, "cyc")
        ms = probs[task].module_set
        items.append((probs[task], ms, A.from_order(ms, order), order, T))
    return items
IN, IO = prep(PN, AN), prep(PO, AO)
def robot(R, items):
    for p, ms, asm, order, T in items: R(ms, asm, base_pose=T)
def from_order(A, items):
    for p, ms, asm, order, T in items: A._from_order(ms, order)
def take(Pool, items):   # a new pool per pass: every take builds (the solve pipeline's path for a new assembly)
    pools = {}
    for p, ms, asm, order, T in items:
        pl = pools.get(id(p)) or pools.setdefault(id(p), Pool(p.task))
        pl.give_back(pl.take(ms, asm, T))
def retake(Pool, items):   # taken back: set_base_pose only
    pools = {}
    for p, ms, asm, order, T in items:
        pl = pools.get(id(p)) or pools.setdefault(id(p), Pool(p.task, size=10**6))
        pl.give_back(pl.take(ms, asm, T))
    t0 = time.perf_counter()
    for p, ms, asm, order, T in items:
        pl = pools[id(p)]
        pl.give_back(pl.take(ms, asm, T))
    return time.perf_counter() - t0
cases = [("Robot(ms, asm, base_pose)", lambda it, o: robot(RO if o else RN, it)),
         ("RobotPool.take (new robot)", lambda it, o: take(PoolO if o else PoolN, it)),
         ("Assembly._from_order", lambda it, o: from_order(AO if o else AN, it))]
n = 64
for name, f in cases:
    f(IN[:n], False); f(IO[:n], True)
    ratios, wo, wn, co, cn = [], [], [], [], []
    for r in range(rounds):
        k = (r * n) % (len(IN) - n)
        res = {}
        for old in ((False, True) if r % 2 else (True, False)):
            it = (IO if old else IN)[k:k + n]
            gc.collect(); gc.disable()
            c0, t0 = time.process_time(), time.perf_counter()
            f(it, old)
            res[old] = (time.perf_counter() - t0, time.process_time() - c0)
            gc.enable()
        wo.append(res[True][0] / n); wn.append(res[False][0] / n); co.append(res[True][1] / n); cn.append(res[False][1] / n)
        ratios.append(res[True][0] / res[False][0])
    print(f"{name:28s} old {np.median(wo)*1e6:7.1f} us  new {np.median(wn)*1e6:7.1f} us  (cpu {np.median(co)*1e6:7.1f} / "
          f"{np.median(cn)*1e6:7.1f})  median of paired ratios old/new {np.median(ratios):.2f}x "
          f"[q25 {np.percentile(ratios, 25):.2f}, q75 {np.percentile(ratios, 75):.2f}]  ({rounds} rounds of {n})")
    sys.stdout.flush()
