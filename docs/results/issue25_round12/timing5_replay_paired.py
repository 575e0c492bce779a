"""Paired replay A/B: two workers (checkouts A and B) pinned to one core replay the recorded time_parameterize calls
in turn; per round CPU ms per evaluation and the ratio B/A.  usage: t5_paired.py A B [rounds] [group]"""
import os, subprocess, sys, statistics, json
if sys.argv[1] == "--worker":
    src, group = sys.argv[2], sys.argv[3]
    sys.argv = [sys.argv[0], src]
    import io, contextlib
    with contextlib.redirect_stdout(io.StringIO()):
        exec(open('' + __import__('os').path.join(__import__('os').path.dirname(__import__('os').path.abspath(__file__)), 'timing5_record.py') + '').read().split("from collections import defaultdict")[0])
    from robodesign.solvers import timing
    import time, hashlib
    nev = 23 if group == "fresh" else 20
    d = hashlib.sha256()
    for robot, path, kw in calls[group]:
        tr = timing.time_parameterize(robot, path, **kw)
        for x in (tr.t, tr.q, tr.dq, tr.ddq): d.update(x.tobytes())
    print(json.dumps({"hash": d.hexdigest()[:16]}), flush=True)
    for line in sys.stdin:
        t = time.process_time()
        for _ in range(3):
            for robot, path, kw in calls[group]:
                timing.time_parameterize(robot, path, **kw)
        print(json.dumps({"ms": (time.process_time() - t) / 3 / nev * 1e3}), flush=True)
    sys.exit(0)
A, B = sys.argv[1], sys.argv[2]
rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 15
group = sys.argv[4] if len(sys.argv) > 4 else "fresh"
core = str(os.sched_getaffinity(0).pop())
procs = {}
for name, src in (("A", A), ("B", B)):
    env = {**os.environ, "PYTHONPATH": src + "/src", "OPENBLAS_NUM_THREADS": "1"}
    procs[name] = subprocess.Popen(["taskset", "-c", core, sys.executable, "-W", "ignore", __file__, "--worker", src, group],
                                   stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
hashes = {n: json.loads(p.stdout.readline())["hash"] for n, p in procs.items()}
print(group, "hashes", hashes)
ratios, ms = [], {"A": [], "B": []}
for r in range(rounds):
    order = ("A", "B") if r % 2 == 0 else ("B", "A")
    got = {}
    for n in order:
        procs[n].stdin.write("go\n"); procs[n].stdin.flush()
        got[n] = json.loads(procs[n].stdout.readline())["ms"]
    ms["A"].append(got["A"]); ms["B"].append(got["B"]); ratios.append(got["B"] / got["A"])
for p in procs.values():
    p.stdin.close(); p.wait()
print(f"{group}: A median {statistics.median(ms['A']):.3f} ms/eval, B median {statistics.median(ms['B']):.3f}; "
      f"ratio B/A median {statistics.median(ratios):.3f} (per round: {' '.join(f'{x:.3f}' for x in ratios)})")
