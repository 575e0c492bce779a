"""first_invalid and the certificates' parts, ms per good-arm evaluation (wrapped with perf_counter; argv[1]: checkout)."""
import sys, time, statistics
exec(open(__import__("pathlib").Path(__file__).with_name("fast-feasible2_bench_plan.py")).read().split("tp, tc = [], []")[0])
from robodesign.model import collision_cull as C
from robodesign.solvers import pair_certificates as PC, planning as PL
acc = {}
cnt = {}
def wrap(cls, name):
    o = getattr(cls, name)
    def w(*a, **k):
        t = time.perf_counter(); r = o(*a, **k); acc[name] = acc.get(name, 0) + time.perf_counter() - t; cnt[name] = cnt.get(name, 0) + 1; return r
    setattr(cls, name, w)
for cls, n in [(C.CollisionCuller, "collides"), (C.CollisionCuller, "survivors"), (PC.PairCertificates, "pending"),
               (PC.PairCertificates, "ask"), (PC.PairCertificates, "_certify"), (PL._Memoized, "first_invalid")]:
    wrap(cls, n)
res = []
for r in range(8):
    acc.clear(); cnt.clear()
    t = time.perf_counter()
    for a, k in plans: o_plan(*a, **k)
    res.append(((time.perf_counter() - t) / 5 * 1e3, {k: round(v / 5 * 1e3, 2) for k, v in acc.items()}, {k: v // 5 for k, v in cnt.items()}))
res.sort(key=lambda x: x[0])
print(res[len(res) // 2])
