"""check8 variant of fast-check7_check_paired.py: every check at a new base pose (the solution's moved by n·0.1 mm
along x and turned by n·0.1 mrad about z, n counting the jobs), as in a search that meets the same assembly at
other base poses: the judge's robot is taken back at a new pose every time (no base-pose-keyed set-up repeats).
Paired A/B of judge.check between two checkouts (as experiments/bench_paired.py does for whole evaluations): each
checkout in a worker process of its own (its src/ first on the path, kernels warmed up), both pinned to one core;
the parent hands them the same check in turn (A then B, B then A on the next), each times it with its own CPU
clock. Jobs: the good IMPROV arm's 20 PTP_3 solutions (study seeds 0-19), checked `--reps` times each per round.
The verdicts must be equal. Prints per round the median CPU ms of A and B and the median per-job ratio B / A.
usage (from /work/main): OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock .venv/bin/python
       fast-check7_check_paired.py A_CHECKOUT B_CHECKOUT [rounds]"""
import json
import os
import statistics
import subprocess
import sys


def worker(src: str) -> None:
    """Read job numbers from stdin, check that solution, print (CPU ms, verdict key) as one JSON line."""
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    sys.path.insert(0, src + "/src")
    import gc
    import time
    from robodesign.solvers import ik_kernel
    ik_kernel.warm_up()
    from robodesign.design.solve import warm_up
    warm_up()
    import robodesign.design.solve as sv
    from robodesign.design.evaluator import Evaluator, EvaluatorSpec
    from robodesign.design.problem import Problem
    from robodesign.design.search_space import Candidate
    from robodesign.judge import checker as ck
    S = "/work/shared/cobra"
    p = Problem.build(f"{S}/tasks/simple/PTP_3.json", f"{S}/modules/IMPROV", "cyc")
    sols = []
    orig = sv.check
    sv.check = lambda task, sol, ms, **kw: (sols.append((task, sol, ms, kw)), orig(task, sol, ms, **kw))[1]
    for s in range(20):
        Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(("1", "21", "4", "22", "5", "23", "12")))
    sv.check = orig
    gc.freeze()
    print("ready", flush=True)
    import numpy as np
    for line in sys.stdin:
        i, n = (int(x) for x in line.split())
        a = sols[i]
        T = np.eye(4)
        c, s = np.cos(1e-4 * n), np.sin(1e-4 * n)
        T[:2, :2] = [[c, -s], [s, c]]
        T[0, 3] = 1e-4 * n
        sol = a[1].with_(base_pose=T @ np.asarray(a[1].base_pose, dtype=float))
        t = time.process_time()
        v = ck.check(a[0], sol, a[2], **a[3])
        d = time.process_time() - t
        key = repr((v.valid, [x.to_json() for x in v.violations], v.costs, v.cost, v.goals))
        print(json.dumps([d * 1e3, key]), flush=True)


def main() -> None:
    a_src, b_src = sys.argv[1], sys.argv[2]
    rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 5
    procs = {}
    for side, src in (("A", a_src), ("B", b_src)):
        procs[side] = subprocess.Popen([sys.executable, __file__, "--worker", src], stdin=subprocess.PIPE,
                                       stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    for p in procs.values():
        while p.stdout.readline().strip() != "ready":
            pass
    print(f"# A: {a_src}\n# B: {b_src}")
    all_r = []
    job = 0
    for r in range(rounds):
        ta, tb, ratios = [], [], []
        for rep in range(3):
            for i in range(20):
                got = {}
                job += 1
                for side in (("A", "B") if (i + r + rep) % 2 == 0 else ("B", "A")):
                    procs[side].stdin.write(f"{i} {job}\n")
                    procs[side].stdin.flush()
                    got[side] = json.loads(procs[side].stdout.readline())
                assert got["A"][1] == got["B"][1], f"verdicts differ on solution {i}"
                ta.append(got["A"][0])
                tb.append(got["B"][0])
                ratios.append(got["B"][0] / got["A"][0])
        all_r += ratios
        print(f"round {r + 1}: A median {statistics.median(ta):.2f} ms, B median {statistics.median(tb):.2f} ms, "
              f"per-check ratio B/A median {statistics.median(ratios):.3f}", flush=True)
    print(f"all {len(all_r)} checks: per-check ratio B/A median {statistics.median(all_r):.3f}; verdicts equal")
    for p in procs.values():
        p.stdin.close()
        p.wait()


if __name__ == "__main__":
    if len(sys.argv) > 2 and sys.argv[1] == "--worker":
        worker(sys.argv[2])
    else:
        main()
