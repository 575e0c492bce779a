"""In one process: plan_path of the good arm's captured calls with and without the pair certificates, alternating
(the same code otherwise): CPU ms per evaluation, per round."""
import sys, time, statistics
from pathlib import Path
exec(open(str(Path(__file__).with_name("fast-feasible2_bench_plan.py"))).read().split("tp, tc = [], []")[0])
from robodesign.solvers import planning as PL
real = PL.PairCertificates.of
def run(on):
    PL.PairCertificates.of = real if on else (lambda *a: None)
    t = time.process_time()
    for _ in range(4):
        for a, k in plans: o_plan(*a, **k)
    return (time.process_time() - t) / 20 * 1e3
res = {True: [], False: []}
for r in range(12):
    for on in (False, True):
        res[on].append(run(on))
print("without: median %.2f min %.2f | with: median %.2f min %.2f | ratio of medians %.2f, per round %s" % (
    statistics.median(res[False]), min(res[False]), statistics.median(res[True]), min(res[True]),
    statistics.median(res[True]) / statistics.median(res[False]),
    " ".join("%.2f" % (b / a) for a, b in zip(res[False], res[True]))))
