"""Load test of the benchmark website (issue 13, section 3): page latency and upload acknowledgement while two
~20 MiB uploads are being checked.

What it does (everything on 127.0.0.1, bounded in count and time):

1. starts ``robodesign serve`` as its own process (default settings: checker processes, rate limits, queue; only
   ``--max-upload-mb`` is raised a little so that a 20 MiB solution plus the form overhead fits) on the toy task and
   module set of the tests, and fills the leaderboard with ``--rows`` valid solutions;
2. runs ``--clients`` page clients (each its own address via ``X-Forwarded-For``, which uvicorn trusts from
   127.0.0.1 as behind a reverse proxy) that load the home page, the leaderboard (HTML and JSON), the solution list,
   the task page and a solution page in turn, with a think time drawn uniformly from ``--think`` seconds;
3. after a warm-up, sends two dense ~``--big-mib`` MiB solutions (the toy motion sampled ~150,000 times: parsing and
   checking each takes tens of seconds of CPU) from two addresses, and while they are being checked sends a small
   valid upload every ``--small-every`` seconds, alternately synchronous (time until the verdict, 201) and
   asynchronous (time until 202 Accepted with its place in the queue), each from a new address;
4. one client sends three asynchronous uploads at once: the third must be 429 (at most 2 per client) — the
   intended 429;
5. stops when both big uploads are answered (or after ``--max-seconds``) and prints the page latency percentiles
   over the time the big uploads were in the server, the small uploads' times, and every status seen.

    flock /tmp/robodesign-bench.lock nice -n 5 python experiments/load_test_web.py

Targets: page p99 ≤ 500 ms, small upload acknowledged in ≤ 2 s, no error other than the intended 4xx/429.
"""
from __future__ import annotations

import argparse
import http.client
import json
import os
import random
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the toy task, module set and solutions of the test suite

import test_checker  # noqa: E402
from test_web import BOARD, make_seed, sol_json, toy_solution  # noqa: E402


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def request(port, method, path, body=None, headers=None, timeout=300):
    """One request on a new connection → (status, seconds, JSON or text)."""
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
    t0 = time.perf_counter()
    try:
        conn.request(method, path, body=body, headers=headers or {})
        r = conn.getresponse()
        data = r.read()
        dt = time.perf_counter() - t0
        try:
            payload = json.loads(data)
        except ValueError:
            payload = data[:200].decode("utf-8", "replace")
        return r.status, dt, payload
    finally:
        conn.close()


def big_solution_text(target_mib: float, k: float) -> str:
    """The toy motion sampled so densely that the compact JSON is about ``target_mib`` MiB (numbers only)."""
    dt0 = test_checker.DT
    n = 20_000
    try:
        for _ in range(3):  # the bytes per sample grow a little with the sample count: calibrate twice
            test_checker.DT = 3.5 / n
            text = json.dumps(toy_solution(k).to_json())
            n = int(n * target_mib * 2 ** 20 * 0.98 / len(text))
        return text
    finally:
        test_checker.DT = dt0


def rss_mib(pid: int) -> float:
    """Resident memory of a process and its children (MiB)."""
    total = 0
    todo = [pid]
    while todo:
        p = todo.pop()
        try:
            for line in open(f"/proc/{p}/status"):
                if line.startswith("VmRSS:"):
                    total += int(line.split()[1])
            for task in os.listdir(f"/proc/{p}/task"):
                todo += [int(c) for c in open(f"/proc/{p}/task/{task}/children").read().split()]
        except (OSError, ValueError):
            pass
    return total / 1024


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--clients", type=int, default=50)
    ap.add_argument("--think", type=float, nargs=2, default=(0.25, 0.75), metavar=("MIN", "MAX"),
                    help="think time of a page client between two pages [s] (default 0.25 0.75)")
    ap.add_argument("--big-mib", type=float, default=20.0)
    ap.add_argument("--rows", type=int, default=40, help="valid solutions on the leaderboard before the test")
    ap.add_argument("--small-every", type=float, default=2.0)
    ap.add_argument("--warmup", type=float, default=5.0)
    ap.add_argument("--max-seconds", type=float, default=240.0)
    ap.add_argument("--workers", type=int, default=2, help="checker processes of the server (default 2)")
    ap.add_argument("--json", help="also write the figures to this file")
    args = ap.parse_args(argv)

    tmp = Path(tempfile.mkdtemp(prefix="robodesign-load-"))
    seed = make_seed(tmp / "seed")
    port = free_port()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]))
    env.pop("ROBODESIGN_ADMIN_TOKEN", None)
    server = subprocess.Popen([sys.executable, "-m", "robodesign.cli", "serve", "--data", str(tmp / "data"),
                               "--seed", str(seed), "--no-builtin", "--port", str(port), "--host", "127.0.0.1",
                               "--max-upload-mb", str(args.big_mib + 1), "--workers", str(args.workers)],
                              stdout=subprocess.DEVNULL, stderr=open(tmp / "server.log", "w"), env=env)
    try:
        deadline = time.time() + 90
        while True:
            try:
                if request(port, "GET", "/healthz", timeout=2)[0] == 200:
                    break
            except OSError:
                pass
            if server.poll() is not None or time.time() > deadline:
                raise SystemExit(f"the server did not start: {(tmp / 'server.log').read_text()[-2000:]}")
            time.sleep(0.2)

        def upload(sol_text: str, client: str, author: str, asynchronous=False):
            q = f"/api/solutions?author={author}" + ("&async=1" if asynchronous else "")
            return request(port, "POST", q, body=sol_text.encode(),
                           headers={"Content-Type": "application/json", "X-Forwarded-For": client})

        for i in range(args.rows):
            st, _, body = upload(json.dumps(sol_json(1 + 0.01 * i)), f"10.0.{i // 250}.{i % 250 + 1}", f"row{i}")
            assert st == 201, (st, body)
        sid = body["id"]
        print(f"server on 127.0.0.1:{port}, leaderboard with {args.rows} solutions; building the big uploads ...",
              flush=True)
        bigs = [big_solution_text(args.big_mib, k) for k in (1.0, 1.5)]
        print("big uploads: " + ", ".join(f"{len(b) / 2 ** 20:.1f} MiB" for b in bigs), flush=True)

        # ---------------------------------------------------------------- page clients
        pages = ["/", f"/leaderboard/{BOARD}", f"/api/leaderboard/{BOARD}", "/api/solutions", "/tasks/toy/all",
                 f"/solutions/{sid}"]
        stop = threading.Event()
        samples = []  # (start time, seconds, status, path)
        lock = threading.Lock()

        def page_client(i):
            rng = random.Random(i)
            headers = {"X-Forwarded-For": f"10.1.{i // 250}.{i % 250 + 1}"}
            conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
            k = i
            while not stop.is_set():
                path = pages[k % len(pages)]
                k += 1
                t0 = time.perf_counter()
                try:
                    conn.request("GET", path, headers=headers)
                    r = conn.getresponse()
                    r.read()
                    status = r.status
                except (OSError, http.client.HTTPException):
                    status = -1
                    conn.close()
                    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
                with lock:
                    samples.append((t0, time.perf_counter() - t0, status, path))
                stop.wait(rng.uniform(*args.think))
            conn.close()

        clients = [threading.Thread(target=page_client, args=(i,), daemon=True) for i in range(args.clients)]
        for t in clients:
            t.start()
        time.sleep(args.warmup)

        # ---------------------------------------------------------------- the two big uploads
        big_results = [None, None]
        peak_rss = [rss_mib(server.pid)]

        def big(i):
            try:
                st, dt, body = upload(bigs[i], f"10.2.0.{i + 1}", f"big{i}")
            except OSError as e:  # e.g. refused while being sent
                st, dt, body = -1, 0.0, str(e)
            big_results[i] = (st, dt, body.get("detail", "")[:120] if isinstance(body, dict) else body)

        t_big = time.perf_counter()
        big_threads = [threading.Thread(target=big, args=(i,), daemon=True) for i in range(2)]
        for t in big_threads:
            t.start()
        while request(port, "GET", "/api/queue", headers={"X-Forwarded-For": "10.9.9.9"})[2].get("checking", 0) < 1:
            time.sleep(0.1)
            if time.perf_counter() - t_big > 60 or not any(t.is_alive() for t in big_threads):
                raise SystemExit(f"the big uploads never reached a checker: {big_results}")

        # ---------------------------------------------------------------- small uploads while they are checked
        smalls = []  # (mode, status, seconds, queue position)
        n = 0
        limit_probe = None
        while any(t.is_alive() for t in big_threads) and time.perf_counter() - t_big < args.max_seconds:
            n += 1
            asynchronous = n % 2 == 0
            st, dt, body = upload(json.dumps(sol_json(2 + 0.01 * n)), f"10.3.{n // 250}.{n % 250 + 1}", f"small{n}",
                                  asynchronous)
            smalls.append(("async" if asynchronous else "sync", st, dt, body.get("position", body.get("queue_position"))
                           if isinstance(body, dict) else None))
            peak_rss.append(rss_mib(server.pid))
            if limit_probe is None:  # one client, three uploads at once: the third is the intended 429
                limit_probe = [upload(json.dumps(sol_json(3 + 0.01 * j)), "10.4.0.1", f"burst{j}", True)[0]
                               for j in range(3)]
            time.sleep(args.small_every)
        for t in big_threads:
            t.join(max(1.0, args.max_seconds - (time.perf_counter() - t_big)))
        t_end = time.perf_counter()
        stop.set()
        for t in clients:
            t.join(10)
    finally:
        server.send_signal(signal.SIGTERM)
        try:
            server.wait(30)
        except subprocess.TimeoutExpired:
            server.kill()

    # -------------------------------------------------------------------- figures
    window = [s for s in samples if t_big <= s[0] <= t_end]
    lat = np.array([s[1] for s in window]) * 1000
    statuses = {}
    for s in samples:
        statuses[s[2]] = statuses.get(s[2], 0) + 1
    per_path = {p: np.percentile([s[1] * 1000 for s in window if s[3] == p], 99) for p in pages}
    small_sync = [s[2] for s in smalls if s[0] == "sync"]
    small_async = [s[2] for s in smalls if s[0] == "async"]
    out = {
        "clients": args.clients, "think_s": list(args.think), "rows": args.rows, "workers": args.workers,
        "big_upload_mib": [round(len(b) / 2 ** 20, 2) for b in bigs],
        "big_results": [{"status": r[0], "seconds": round(r[1], 1), "detail": r[2]} if r else None
                        for r in big_results],
        "window_s": round(t_end - t_big, 1), "page_requests": int(len(lat)),
        "page_rate_per_s": round(len(lat) / max(1e-9, t_end - t_big), 1),
        "page_ms": {"p50": round(float(np.percentile(lat, 50)), 1), "p95": round(float(np.percentile(lat, 95)), 1),
                    "p99": round(float(np.percentile(lat, 99)), 1), "max": round(float(lat.max()), 1)},
        "page_p99_ms_by_path": {p: round(float(v), 1) for p, v in per_path.items()},
        "page_statuses": statuses,
        "small_sync_s": [round(x, 3) for x in small_sync], "small_async_s": [round(x, 3) for x in small_async],
        "small_statuses": sorted({s[1] for s in smalls}), "small_positions": [s[3] for s in smalls],
        "per_client_limit_probe": limit_probe, "server_peak_rss_mib": round(max(peak_rss), 0),
    }
    print(json.dumps(out, indent=2))
    ok_pages = set(statuses) <= {200}
    print(f"page p99 {out['page_ms']['p99']:.0f} ms over {len(lat)} requests ({out['page_rate_per_s']}/s) while the "
          f"big uploads were in the server ({out['window_s']} s); statuses {statuses}")
    print(f"small upload: synchronous (verdict) max {max(small_sync, default=float('nan')):.2f} s, "
          f"asynchronous (202) max {max(small_async, default=float('nan')):.3f} s over {len(smalls)} uploads")
    print(f"big uploads: {[(r[0], round(r[1], 1)) for r in big_results if r]}; burst probe {limit_probe}")
    targets = (out["page_ms"]["p99"] <= 500 and ok_pages and max(small_sync + small_async, default=9) <= 2
               and set(out["small_statuses"]) <= {201, 202} and limit_probe == [202, 202, 429]
               and all(r and r[0] in (201, 422) for r in big_results))
    print("targets met" if targets else "TARGETS MISSED")
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=2))
    return 0 if targets else 1


if __name__ == "__main__":
    sys.exit(main())
