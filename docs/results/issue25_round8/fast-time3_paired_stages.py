"""bench_paired.py's paired A/B (both checkouts in workers pinned to one core, the same jobs in turn), reporting also
the median of the per-job ratios B ÷ A of each stage's seconds (the evaluator's own stage records), and each
side's stage medians per round. Run from /work/main:

    OPENBLAS_NUM_THREADS=1 flock /tmp/robodesign-bench.lock .venv/bin/python \
        <this file> --a /tmp/base_s8 --b <checkout> [--feasible 20] [--rounds 3]
"""
import argparse
import json
import statistics
import subprocess
import sys
from pathlib import Path

BENCH = Path("/work/main/experiments/bench_paired.py")


def paired(a: str, b: str, feasible: int):
    cmd = [sys.executable, str(BENCH), "--a", a, "--b", b, "--only", "good", "--feasible", str(feasible),
           "--candidates", "0", "--worker"]
    procs = [subprocess.Popen(cmd + [src], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True) for src in (a, b)]
    try:
        n = [json.loads(p.stdout.readline())["jobs"] for p in procs]
        pairs = []
        for i in range(n[0]):
            out = [None, None]
            for k in ((0, 1) if i % 2 == 0 else (1, 0)):
                procs[k].stdin.write(f"{i}\n")
                procs[k].stdin.flush()
                out[k] = json.loads(procs[k].stdout.readline())
            assert (out[0]["stage"], out[0]["feasible"]) == (out[1]["stage"], out[1]["feasible"]), (i, out)
            pairs.append(out)
        return pairs
    finally:
        for p in procs:
            p.kill()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--a", required=True)
    ap.add_argument("--b", required=True)
    ap.add_argument("--feasible", type=int, default=20)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    print(f"# A: {args.a}\n# B: {args.b}")
    for r in range(args.rounds):
        pairs = paired(args.a, args.b, args.feasible)
        cpu = statistics.median([y["cpu"] / x["cpu"] for x, y in pairs])
        line = [f"round {r + 1}: n {len(pairs)}, CPU ms A {1e3 * statistics.median([x['cpu'] for x, _ in pairs]):.2f} "
                f"B {1e3 * statistics.median([y['cpu'] for _, y in pairs]):.2f}, B/A per job {cpu:.3f}"]
        for st in ("ik", "plan", "timing", "check"):
            ra = [1e3 * x["stages"][st] for x, _ in pairs]
            rb = [1e3 * y["stages"][st] for _, y in pairs]
            ratio = statistics.median([q / p for p, q in zip(ra, rb)])
            line.append(f"{st} {statistics.median(ra):.2f} -> {statistics.median(rb):.2f} ms (per job {ratio:.3f})")
        print("; ".join(line), flush=True)


if __name__ == "__main__":
    main()
