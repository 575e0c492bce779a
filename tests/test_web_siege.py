"""The website under siege (issue 22, cases 7-11): each test reproduces an attack of the issue against a server on
127.0.0.1 (or the in-process test client) and asserts the fixed behaviour, bounded in time and count.

7 slow bodies hold no check-queue place; 8 slow headers and connection floods are closed by the server as
``robodesign serve`` runs it, and repeated log lines are rate-limited; 9 viewer pages are built off the web process,
decimated and bounded; 10 an async upload answered 202 survives ``kill -9`` of the server; 11 text that is not text is
a 4xx naming the field, a many-part multipart body is refused early, /api/docs works under the CSP, HEAD works.
"""
from __future__ import annotations

import contextlib
import json
import logging
import socket
import threading
import time

import pytest

pytest.importorskip("fastapi", reason="the website needs fastapi")
from fastapi.testclient import TestClient  # noqa: E402
from test_web import (ADMIN, ADMIN_HEADERS, BOARD, SLOW_MACHINE_VIEWER_TIMEOUT, free_port, seed_dir, sol_json,  # noqa: E402,F401
                      upload)

from robodesign.web import create_app  # noqa: E402
from robodesign.web.server import RateLimitFilter, server_config  # noqa: E402


@pytest.fixture
def site(tmp_path, seed_dir):
    app = create_app(data_dir=tmp_path / "data", seed=[seed_dir], seed_builtin=False, admin_token=ADMIN,
                     upload_rate=0, read_rate=0, viewer_timeout=SLOW_MACHINE_VIEWER_TIMEOUT)
    with TestClient(app, headers=ADMIN_HEADERS, raise_server_exceptions=False) as c:
        yield c


@contextlib.contextmanager
def guarded_server(app, **settings):
    """The app served as ``robodesign serve`` serves it (web.server.server_config) on 127.0.0.1, in a thread."""
    import uvicorn
    port = free_port()
    config = server_config(app, "127.0.0.1", port, log_level="warning", **settings)
    server = uvicorn.Server(config)
    th = threading.Thread(target=server.run, daemon=True)
    th.start()
    deadline = time.monotonic() + 30
    while not server.started:
        assert time.monotonic() < deadline and th.is_alive(), "uvicorn did not start"
        time.sleep(0.02)
    try:
        yield port, config.http_protocol_class
    finally:
        server.should_exit = True
        th.join(15)


def get(port, path="/healthz", timeout=10.0) -> str:
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
        s.sendall(f"GET {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n".encode())
        chunks = []
        while True:
            b = s.recv(65536)
            if not b:
                return b"".join(chunks).decode("utf-8", "replace")
            chunks.append(b)


def closed_by_server(s: socket.socket) -> bool:
    """Whether the server has closed ``s`` (EOF or reset), waiting at most the socket's timeout."""
    try:
        return s.recv(1) == b""
    except ConnectionResetError:
        return True
    except socket.timeout:
        return False


# ------------------------------------------------------------------------------------------------------------
# 8: slow headers, connection floods, log floods
# ------------------------------------------------------------------------------------------------------------
def test_slow_headers_are_closed_and_the_connection_count_is_capped(tmp_path, seed_dir):
    app = create_app(data_dir=tmp_path / "data", seed=[seed_dir], seed_builtin=False, upload_rate=0, read_rate=0)
    with guarded_server(app, header_timeout=1.0, max_connections=20) as (port, proto):
        slow = []
        for _ in range(15):  # half-open: a request line, then nothing more
            s = socket.create_connection(("127.0.0.1", port), timeout=10)
            s.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n")
            slow.append(s)
        # honest requests still get through while they hang
        assert get(port).startswith("HTTP/1.1 200")
        # a flood beyond the cap: each connection beyond 20 open ones is closed at once
        flood = [socket.create_connection(("127.0.0.1", port), timeout=10) for _ in range(10)]
        # 15 slow ones are open: 5 more fit, 5 are refused (closed before any byte), the 5 others closed by the
        # header deadline
        assert all(closed_by_server(s) for s in flood)
        assert proto.refused == 5 and proto.timed_out >= 5
        # and every slow-header connection is closed by the header deadline (1 s), one more byte a second or not
        for s in slow:
            s.sendall(b"X")
        assert all(closed_by_server(s) for s in slow)
        assert proto.timed_out >= 20
        for s in slow + flood:
            s.close()
        assert get(port).startswith("HTTP/1.1 200")  # the server is fine afterwards
        # a kept-alive connection gets the same deadline for its next request's headers
        with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
            s.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n")
            got = b""
            while not got.endswith(b'{"ok":true}'):  # the whole answer (head and body may come apart)
                got += s.recv(65536)
            assert got.startswith(b"HTTP/1.1 200")
            s.sendall(b"GET /healthz HTTP/1.1\r\n")
            assert closed_by_server(s)


def test_repeated_log_lines_are_rate_limited():
    now = [0.0]
    f = RateLimitFilter(burst=5, window=10.0, clock=lambda: now[0])
    logger = logging.getLogger("robodesign.test.flood")
    logger.propagate = False
    logger.setLevel(logging.INFO)
    lines = []

    class Keep(logging.Handler):
        def emit(self, record):
            lines.append(self.format(record))
    h = Keep()
    logger.addHandler(h)
    logger.addFilter(f)
    try:
        for i in range(20_000):  # the accept loop of the issue: one traceback per failed accept()
            now[0] = i * 0.001  # 20,000 in 20 s
            try:
                raise OSError(24, "Too many open files")
            except OSError:
                logger.error("socket.accept() out of system resource", exc_info=True)
        logger.warning("something else")
        for i in range(100):  # distinct lines (access log: one template, other arguments) all pass
            logger.info('%s - "GET %s HTTP/1.1" %d', "127.0.0.1", f"/solutions/{i}", 200)
    finally:
        logger.removeHandler(h)
        logger.removeFilter(f)
    tracebacks = sum("Traceback" in x for x in lines)
    # 2 windows of 10 s: 5 lines each (one with its traceback) + the other message + 100 distinct lines
    assert len(lines) == 111 and tracebacks == 2 and lines[-1] == '127.0.0.1 - "GET /solutions/99 HTTP/1.1" 200'
    # the first line of the second window reports what the first window dropped (10,000 lines in 10 s, 5 shown)
    assert "[9995 more like this suppressed]" in lines[5] and "Traceback" in lines[5]
    assert sum(len(x) for x in lines[:10]) < 5_000


# ------------------------------------------------------------------------------------------------------------
# 10: an accepted upload is never lost
# ------------------------------------------------------------------------------------------------------------
def _children(pid: int) -> set:
    out = set()
    import os
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                with open(f"/proc/{d}/stat") as f:
                    if int(f.read().rsplit(")", 1)[1].split()[1]) == pid:
                        out.add(int(d))
            except (OSError, ValueError, IndexError):
                pass
    return out


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _start_server(data, seed, port):
    import subprocess
    import sys
    cmd = [sys.executable, "-m", "robodesign.cli.entry", "serve", "--data", str(data), "--seed", str(seed),
           "--no-builtin", "--port", str(port), "--workers", "1", "--queue", "100", "--per-client-queue", "100",
           "--upload-rate", "0", "--read-rate", "0"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 180
    while time.monotonic() < deadline:
        assert proc.poll() is None, "the server stopped"
        try:
            if get(port, timeout=5).startswith("HTTP/1.1 200"):
                return proc
        except OSError:
            pass
        time.sleep(0.2)
    proc.kill()
    raise AssertionError("the server did not start")


def _post_async(port, k: float):
    import urllib.request
    body = json.dumps({"solution": sol_json(k), "author": f"A{k:g}"}).encode()
    req = urllib.request.Request(f"http://127.0.0.1:{port}/api/solutions?async=1", data=body, method="POST",
                                 headers={"Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(req, timeout=60) as r:
            return r.status, json.loads(r.read())
    except Exception as e:  # noqa: BLE001 (the server was killed under it: not acknowledged)
        return None, repr(e)


def _status(port, path):
    import urllib.error
    import urllib.request
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}{path}", timeout=30) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read() or b"null")


@pytest.mark.slow
def test_kill_9_during_async_uploads_loses_none_answered_202(tmp_path, seed_dir):
    import os
    import signal
    from concurrent.futures import ThreadPoolExecutor
    n = 24
    port = free_port()
    data = tmp_path / "data"
    server = _start_server(data, seed_dir, port)
    try:
        checkers = _children(server.pid)
        assert checkers  # the checker process(es) and multiprocessing's helper
        acked = []
        with ThreadPoolExecutor(8) as pool:
            futs = [pool.submit(_post_async, port, 1.0 + k / 100) for k in range(n)]
            for f in futs[: n // 2]:  # kill -9 once half the uploads have been answered, the others in flight
                status, body = f.result()
                if status == 202:
                    acked.append(body)
            os.kill(server.pid, signal.SIGKILL)
            server.wait(30)
            for f in futs[n // 2:]:
                status, body = f.result()
                if status == 202:
                    acked.append(body)
        assert len(acked) >= n // 2
        # the checker processes die with their server
        deadline = time.monotonic() + 30
        while any(_alive(p) for p in checkers) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not [p for p in checkers if _alive(p)]
        import sqlite3
        with contextlib.closing(sqlite3.connect(data / "bench.db")) as con:
            queued = con.execute("SELECT count(*) FROM pending_checks WHERE state = 'queued'").fetchone()[0]
            stored = con.execute("SELECT count(*) FROM pending_checks").fetchone()[0]
        print(f"{len(acked)} uploads answered 202, {stored} stored, {queued} not judged when the server was killed")
        assert stored >= len(acked) and queued >= 1  # the restart has checks to resume
        server = _start_server(data, seed_dir, port)  # the same data: pending checks resume
        results = {}
        deadline = time.monotonic() + 300
        for a in acked:
            while True:
                code, s = _status(port, a["status_url"])
                assert code == 200, (code, s)
                if s["state"] == "done":
                    results[a["job"]] = s
                    break
                assert time.monotonic() < deadline, s
                time.sleep(0.2)
        assert len(results) == len(acked)
        ids = []
        for a in acked:
            s = results[a["job"]]
            assert s["status"] == 201, s
            code, sol = _status(port, f"/api/solutions/{s['result']['id']}")
            assert code == 200 and sol["valid"] and sol["author"] == a.get("author", sol["author"])
            ids.append(s["result"]["id"])
            # the token given with the 202 answer withdraws it: it belongs to this upload
            assert len(a["token"]) >= 16
        assert len(set(ids)) == len(ids)  # none judged twice
        code, board = _status(port, f"/api/leaderboard/{BOARD}")
        assert code == 200 and set(ids) <= {e["id"] for e in board["entries"]}
    finally:
        with contextlib.suppress(ProcessLookupError):
            server.kill()
        server.wait(30)


# ------------------------------------------------------------------------------------------------------------
# 9: the viewer off the web process
# ------------------------------------------------------------------------------------------------------------
def _long_rest_solution(extra: int) -> dict:
    """The valid toy solution followed by ``extra`` samples at rest (a valid, long, boring upload)."""
    from test_checker import DT
    sol = sol_json(1.0)
    tr = sol["trajectory"]
    t_end, q_end = tr["t"][-1], tr["q"][-1]
    zero = [0.0] * len(q_end)
    tr["t"] += [round(t_end + DT * (k + 1), 9) for k in range(extra)]
    tr["q"] += [q_end] * extra
    tr["dq"] += [zero] * extra
    tr["ddq"] += [zero] * extra
    return sol


@pytest.mark.slow
def test_viewer_pages_are_built_off_the_web_process_decimated_and_cached(site):
    pytest.importorskip("robodesign.viewer", reason="the 3D viewer is not installed")
    import os
    from concurrent.futures import ThreadPoolExecutor

    from robodesign.viewer.html import decode_page_data
    sol = _long_rest_solution(20_000)  # 203 s of motion: 5,000 frames at 25 fps, 20,000 samples
    n = len(sol["trajectory"]["t"])
    r = upload(site, sol, author="Rest")
    assert r.status_code == 201, r.text
    sid = r.json()["id"]
    viewer = site.app.state.viewer
    with ThreadPoolExecutor(3) as pool:  # three clients ask for the page at once: one build
        pages = list(pool.map(lambda _: site.get(f"/solutions/{sid}/viewer"), range(3)))
    assert [p.status_code for p in pages] == [200, 200, 200] and viewer.builds == 1
    assert pages[0].content == pages[1].content == pages[2].content
    procs = list(viewer._pool._processes.values())
    assert procs and all(p.pid != os.getpid() for p in procs)  # built in the viewer process
    data = decode_page_data(pages[0].text)
    anim = data["animation"]
    assert n > 20_000 and len(anim["t"]) <= viewer.max_frames + 10  # + the goal instants
    assert anim["t"][-1] == pytest.approx(sol["trajectory"]["t"][-1])  # the last sample is kept
    assert len(pages[0].content) < 8 * 2 ** 20
    assert viewer.path(sid).read_bytes() == pages[0].content  # kept as a file: a restart does not rebuild it
    site.app.state.viewer_cache.max_bytes = 0  # (the in-memory cache off) served from the file, not built again
    site.app.state.viewer_cache.put(sid, b"x")  # too large for the cache now: dropped
    assert site.get(f"/solutions/{sid}/viewer").content == pages[0].content and viewer.builds == 1
    # a build that takes too long is stopped (its process killed): 503 with Retry-After, and the next one works
    viewer.timeout = 0.001
    viewer.path(sid).unlink()
    r = site.get(f"/solutions/{sid}/viewer")
    assert r.status_code == 503 and r.headers["retry-after"] == "60" and "took longer" in r.text
    assert all(not p.is_alive() for p in procs) or viewer._pool is None


def test_decimation_keeps_first_last_and_goal_samples():
    import numpy as np

    from robodesign.web.viewer_pages import decimate_indices
    t = np.arange(100_001) * 0.01
    idx = decimate_indices(t, 1000, goal_times=[123.456, 5.0])
    assert idx[0] == 0 and idx[-1] == 100_000 and len(idx) <= 1002
    assert np.searchsorted(t, 123.456) in idx and 500 in idx
    assert np.all(np.diff(idx) > 0)
    assert list(decimate_indices(t[:50], 1000)) == list(range(50))


# ------------------------------------------------------------------------------------------------------------
# 7: slow bodies hold no place in the check queue
# ------------------------------------------------------------------------------------------------------------
def test_slow_bodies_do_not_block_honest_uploads(tmp_path, seed_dir):
    import urllib.request
    app = create_app(data_dir=tmp_path / "data", seed=[seed_dir], seed_builtin=False, upload_rate=0, read_rate=0,
                     queue_size=8, per_client_queue=2, body_timeout=120.0)
    stop = threading.Event()
    with guarded_server(app, header_timeout=10.0) as (port, _proto):
        slow = []
        for _ in range(8):  # 8 uploads of 1 MB announced, sent at a byte or two a second (the attack of the issue)
            s = socket.create_connection(("127.0.0.1", port), timeout=10)
            s.sendall(b"POST /api/solutions HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                      b"Content-Length: 1000000\r\n\r\n{")
            slow.append(s)

        def trickle():
            while not stop.wait(0.5):
                for s in slow:
                    with contextlib.suppress(OSError):
                        s.sendall(b" ")
        th = threading.Thread(target=trickle, daemon=True)
        th.start()
        try:
            deadline = time.monotonic() + 10
            while app.state.queue.stats()["receiving"] < 8:
                assert time.monotonic() < deadline, app.state.queue.stats()
                time.sleep(0.05)
            assert app.state.queue.stats()["waiting"] == 0  # receiving, not in the queue
            answers = []
            for k in range(6):  # six honest uploads, one after another, all checked
                body = json.dumps({"solution": sol_json(1.0 + k / 10), "author": f"H{k}"}).encode()
                req = urllib.request.Request(f"http://127.0.0.1:{port}/api/solutions", data=body, method="POST",
                                             headers={"Content-Type": "application/json"})
                with urllib.request.urlopen(req, timeout=120) as r:
                    answers.append((r.status, json.loads(r.read())))
            assert [a[0] for a in answers] == [201] * 6
            assert [a[1]["cost"] for a in answers] == pytest.approx([3.5 * (1 + k / 10) for k in range(6)])
            assert app.state.queue.stats()["receiving"] == 8  # the slow ones are still being received
        finally:
            stop.set()
            th.join(5)
            for s in slow:
                s.close()


# ------------------------------------------------------------------------------------------------------------
# 11: many-part bodies, /api/docs under the CSP, HEAD
# ------------------------------------------------------------------------------------------------------------
def test_a_4900_part_multipart_body_is_refused_early(site):
    from robodesign.web.app import MAX_FORM_FILES
    parts = b"".join(b'--B\r\nContent-Disposition: form-data; name="files"; filename="f%d"\r\n\r\nx\r\n' % i
                     for i in range(4900))
    seen = []
    import python_multipart.multipart as mp  # count the parts the parser actually handled
    original = mp.MultipartParser.callback

    def counting(self, name, *a, **kw):
        if name == "part_begin":
            seen.append(1)
        return original(self, name, *a, **kw)
    mp.MultipartParser.callback = counting
    try:
        r = site.post("/api/solutions", content=parts + b"--B--\r\n",
                      headers={"content-type": "multipart/form-data; boundary=B"})
    finally:
        mp.MultipartParser.callback = original
    assert r.status_code == 413 and f"Maximum number of files is {MAX_FORM_FILES}" in r.json()["detail"]
    assert 100 < len(seen) <= MAX_FORM_FILES + 1  # stopped at the first part beyond the limit, not after 4,900
    assert site.app.state.queue.stats() == {"workers": site.app.state.queue.workers, "checking": 0, "waiting": 0,
                                            "receiving": 0, "max_waiting": 8}


def test_api_docs_work_under_the_csp_and_head_works_on_pages(site):
    r = site.get("/api/docs")
    assert r.status_code == 200 and "script-src 'none'" in r.headers["content-security-policy"]
    html = r.text
    assert "<script" not in html and "cdn" not in html.lower() and "http://" not in html and "https://" not in html
    for route in ("/api/solutions", "/api/leaderboard/{bid}", "/api/checks/{job_id}"):
        assert f"<code>{route}</code>" in html
    assert site.get("/api/openapi.json").json()["paths"]["/api/solutions"]["post"]
    for path in ("/", "/upload", "/api/docs", "/api/tasks", f"/leaderboard/{BOARD}", "/healthz", "/static/style.css"):
        g, h = site.get(path), site.head(path)
        assert h.status_code == g.status_code == 200, path
        assert h.content == b"" and h.headers["content-length"] == str(len(g.content))
        assert h.headers["content-type"] == g.headers["content-type"]
    assert site.head("/solutions/999").status_code == 404


def test_a_pending_upload_judged_by_two_processes_is_stored_once(site):
    """Two server processes that both resume one pending upload (several processes on one database): the second
    finds the job done when it marks it, rolls its solution back and reports the stored result."""
    from robodesign.web.service import hash_token
    bench = site.app.state.bench
    text = json.dumps(sol_json(1.0))
    bench.add_pending("job-twice", text, "solution.json", {"author": "Twice"}, hash_token("secret-token-1"), False,
                      False)
    assert [r.job_id for r in bench.pending_checks()] == ["job-twice"]
    first = bench.check_upload(text, "solution.json", {"author": "Twice"}, None, False,
                               token_hash=hash_token("secret-token-1"), pending="job-twice")
    second = bench.check_upload(text, "solution.json", {"author": "Twice"}, None, False,
                                token_hash=hash_token("secret-token-1"), pending="job-twice")
    assert first["status"] == 201 and "token" not in first["body"]  # the uploader got it with the 202 answer
    assert second["status"] == 200 and second["body"]["state"] == "done"
    assert second["body"]["result"]["id"] == first["body"]["id"]
    entries = site.get(f"/api/leaderboard/{BOARD}").json()["entries"]
    assert [e["author"] for e in entries] == ["Twice"] and bench.pending_checks() == []
    # the token hashed at acceptance withdraws it
    assert site.delete(f"/api/solutions/{first['body']['id']}", headers={"X-Author-Token": "secret-token-1"}
                       ).status_code == 200


def test_decimate_json_cuts_every_trajectory_list_alike():
    from robodesign.web.viewer_pages import decimate_json
    sol = _long_rest_solution(10_000)
    n = len(sol["trajectory"]["t"])
    small = decimate_json(sol, 500)
    tr = small["trajectory"]
    assert len(tr["t"]) == len(tr["q"]) == len(tr["dq"]) == len(tr["ddq"]) <= 500 + len(tr["goal2time"])
    assert tr["t"][0] == sol["trajectory"]["t"][0] and tr["t"][-1] == sol["trajectory"]["t"][-1]
    k = sol["trajectory"]["t"].index(tr["t"][7])  # the rows stay together
    assert tr["q"][7] == sol["trajectory"]["q"][k] and tr["ddq"][7] == sol["trajectory"]["ddq"][k]
    assert len(sol["trajectory"]["t"]) == n  # the input is not changed
    collab = {"taskID": "x", "robots": [{"ID": "a", "trajectory": sol["trajectory"]}, {"ID": "b"}]}
    assert len(decimate_json(collab, 500)["robots"][0]["trajectory"]["q"]) == len(tr["q"])
    assert decimate_json({"trajectory": {"t": "bad"}}, 10) == {"trajectory": {"t": "bad"}}
