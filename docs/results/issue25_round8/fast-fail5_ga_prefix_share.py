"""How deep the builds of the genetic search could start from a kept cut (longest prefix of module ids shared with an
earlier build, serial orders)."""
import sys, runpy, atexit
sys.path.insert(0, "/work/main/experiments")
sys.path.insert(0, "/work/h-fast-fail5/src")
from robodesign.model import robot_build as rb
orders = []
orig = rb.walk
def walk(ms, asm, flag):
    orders.append(tuple(asm.module_ids)); return orig(ms, asm, flag)
rb.walk = walk
import robodesign.model.robot as rm
rm.walk = walk
def report():
    seen = set(); depths = []
    for o in orders:
        d = 0
        for k in range(1, len(o)):
            if o[:k + 1] in seen: d = k
            else: break
        depths.append(d)
        for k in range(1, len(o)): seen.add(o[:k + 1])
    import statistics
    n = sum(len(o) for o in orders)
    print("builds", len(orders), "mean modules", n / len(orders), "mean resumable depth", statistics.mean(depths),
          "share of modules", sum(depths) / n, "capped at 8:", sum(min(d, 8) for d in depths) / n)
atexit.register(report)
sys.argv = ["bench_front_ga.py", "--src", "/work/h-fast-fail5", "--budget", "200evals", "--tasks", "1", "--only", sys.argv[1]]
runpy.run_path("experiments/bench_front_ga.py", run_name="__main__")
