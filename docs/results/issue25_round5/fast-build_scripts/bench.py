"""Time Robot(ms, asm, base_pose=T) over random robodesign_arm orders (src from PYTHONPATH)."""
import pickle, sys, time, gc
import numpy as np
from robodesign.design.problem import Problem
from robodesign.formats.assembly import Assembly
from robodesign.model.robot import Robot
from robodesign.model.cell import RobotPool

orders = [o for o in pickle.load(open(sys.argv[1], "rb")) if o[1] == "robodesign_arm" and o[3] is not None]
reps = int(sys.argv[2]) if len(sys.argv) > 2 else 5
probs = {}
items = []
for task, mods, order, T in orders:
    if task not in probs:
        probs[task] = Problem.build(task, mods, "cyc")
    p = probs[task]
    items.append((p, p.module_set, Assembly.from_order(p.module_set, order), order, T))
for p, ms, asm, order, T in items:
    Robot(ms, asm, base_pose=T)   # warm
res = {"robot": [], "robot_nobase": [], "from_order": [], "pool_take": []}
gc.disable()
for rep in range(reps):
    t0 = time.perf_counter()
    for p, ms, asm, order, T in items:
        Robot(ms, asm, base_pose=T)
    res["robot"].append((time.perf_counter() - t0) / len(items))
    t0 = time.perf_counter()
    for p, ms, asm, order, T in items:
        Robot(ms, asm)
    res["robot_nobase"].append((time.perf_counter() - t0) / len(items))
    t0 = time.perf_counter()
    for p, ms, asm, order, T in items:
        Assembly._from_order(ms, order)
    res["from_order"].append((time.perf_counter() - t0) / len(items))
    pools = {task: RobotPool(p.task) for task, p in probs.items()}
    t0 = time.perf_counter()
    for p, ms, asm, order, T in items:
        pools[p.task_ref if False else id(p)] if False else None
        pl = pools[next(k for k, v in probs.items() if v is p)]
        pl.take(ms, asm, T)
    res["pool_take"].append((time.perf_counter() - t0) / len(items))
    gc.collect()
print(" ".join(f"{k}={np.median(v)*1e6:.1f}us" for k, v in res.items()), f"n={len(items)} reps={reps}")
