"""The website under attack (issue 13, section 3), on SQLite and on a throwaway PostgreSQL cluster: every bad request
is a 4xx (never a 500) and leaves nothing behind; size caps; listings never read the stored files; per-client rate
limits and the bounded check queue (429 + Retry-After, queue position); slow bodies; stale staging folders; the
byte-bounded viewer cache; registration as an admin action.

Uses the toy task / module set / solutions of tests/test_web.py (a valid toy solution costs cyc = 3.5·k).
"""
from __future__ import annotations

import fcntl
import json
import socket
import threading
import time
import uuid
from concurrent.futures import ThreadPoolExecutor

import pytest

pytest.importorskip("fastapi", reason="the website needs fastapi")
from fastapi.testclient import TestClient  # noqa: E402
from sqlalchemy import event  # noqa: E402

from robodesign.web import create_app  # noqa: E402
from robodesign.web.cache import ByteLRU  # noqa: E402
from robodesign.web.service import Limits  # noqa: E402
from robodesign.web.throttle import RateLimiter  # noqa: E402

from test_web import SLOW_MACHINE_VIEWER_TIMEOUT, task_json  # noqa: E402
from test_web import (ADMIN, ADMIN_HEADERS, BOARD, listing, postgres_cluster, running_server, seed_dir,  # noqa: E402,F401
                      sol_json, upload)

BIG = 2 ** 63


# ------------------------------------------------------------------------------------------------------------
# fixtures: one app per test on SQLite or on a fresh database of a PostgreSQL cluster shared by the module
# ------------------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def pg_server():
    with postgres_cluster() as url:
        yield url


@pytest.fixture(params=["sqlite", "postgresql"])
def db_url(request):
    if request.param == "sqlite":
        return None
    base = request.getfixturevalue("pg_server")
    import psycopg
    name = "t" + uuid.uuid4().hex[:12]
    with psycopg.connect(base, autocommit=True) as con:
        con.execute(f"CREATE DATABASE {name}")
    return base.rsplit("/", 1)[0] + "/" + name


@pytest.fixture
def make_site(tmp_path, seed_dir, db_url):
    """``make_site(**create_app options)`` → a TestClient (admin header set); closed at the end of the test."""
    clients = []

    def make(**kw):
        kw.setdefault("admin_token", ADMIN)
        kw.setdefault("viewer_timeout", SLOW_MACHINE_VIEWER_TIMEOUT)
        app = create_app(db_url=db_url, data_dir=tmp_path / "data", seed=[seed_dir], seed_builtin=False, **kw)
        c = TestClient(app, headers=ADMIN_HEADERS, raise_server_exceptions=False)
        c.__enter__()
        clients.append(c)
        return c

    yield make
    for c in clients:
        c.__exit__(None, None, None)


@pytest.fixture
def site(make_site):
    """A site without rate limits (they are tested on their own)."""
    return make_site(upload_rate=0, read_rate=0)


def raw_post(c, body, **kw):
    return c.post("/api/solutions", content=body, headers={"content-type": "application/json"}, **kw)


def board(c, bid=BOARD):
    return c.get(f"/api/leaderboard/{bid}")


# ------------------------------------------------------------------------------------------------------------
# every bad request is a 4xx
# ------------------------------------------------------------------------------------------------------------
def test_hostile_json_is_400(site):
    for body, expect in ((b"[" * 100_000 + b"]" * 100_000, "nested deeper than 100 levels"),
                         (b'{"taskID": ' + b"1" * 5000 + b"}", "taskID: number 1111111111"),
                         (b'{"a": ' + b"[" * 3000 + b"]" * 3000 + b"}", "nested deeper than 100 levels")):
        r = raw_post(site, body, params={"author": "A"})
        assert r.status_code == 400, r.text
        assert expect in r.json()["detail"], r.json()
        r = site.post("/api/solutions", files={"file": ("s.json", body)}, data={"author": "A"})
        assert r.status_code == 400 and expect in r.json()["detail"]
        r = site.post("/upload", files={"file": ("s.json", body)}, data={"author": "A"})
        assert r.status_code == 400 and "text/html" in r.headers["content-type"]
        r = site.post("/api/tasks", content=body, headers={"content-type": "application/json"})
        assert r.status_code == 400 and expect in r.json()["detail"]
        r = site.post("/api/modulesets", content=body, headers={"content-type": "application/json"},
                      params={"name": "deep"})
        assert r.status_code == 400 and expect in r.json()["detail"]
    assert board(site).json()["entries"] == []


def test_out_of_range_numbers_are_400(site):
    for field in ("computationTime", "cost"):
        text = json.dumps(sol_json() | {field: 12345.5}).replace("12345.5", "1e400")
        r = raw_post(site, text.encode(), params={"author": "A"})
        assert r.status_code == 400, r.text
        assert r.json()["detail"] == f"solution.json: {field}: number 1e400 is out of range (beyond 1.8e308)"
    s = sol_json()
    s["trajectory"]["t"][1] = 12345.5
    text = json.dumps(s).replace("12345.5", "1e400")
    r = raw_post(site, text.encode(), params={"author": "A"})
    assert r.status_code == 400 and "trajectory.t" in r.json()["detail"]
    for v in ("1e400", "-1e999", "inf", "nan"):
        r = site.get("/api/solutions", params={"min_cost": v})
        assert r.status_code == 400 and "min_cost" in r.json()["detail"], (v, r.text)
    assert board(site).json()["entries"] == []


def test_nul_bytes_anywhere_are_400(site, tmp_path):
    # in a form field, in the solution's own author list, in the token
    r = upload(site, sol_json(), author="Ada\x00Lovelace")
    assert r.status_code == 400 and "author: contains a NUL character" in r.json()["detail"]
    r = upload(site, sol_json(), affiliation="Lab\x00")
    assert r.status_code == 400 and "affiliation" in r.json()["detail"]
    r = site.post("/api/solutions", json=sol_json() | {"author": ["Ada\u0000"]})
    assert r.status_code == 400 and "NUL" in r.json()["detail"]
    r = upload(site, sol_json(), token="secret-token\x00-x")
    assert r.status_code == 400 and "NUL" in r.json()["detail"]
    # in paths and queries
    for url in ("/tasks/toy%00all", "/api/tasks/toy/al%00l", "/modulesets/to%00y", "/api/modulesets/to%00y",
                "/leaderboard/M-toy:cyc:toy/all%00", "/api/leaderboard/M-toy%00:cyc:toy/all",
                "/api/solutions?task=toy%00", "/api/solutions?moduleset=%00", "/api/solutions?cost=cyc%00",
                "/solutions/1%00", "/api/checks/%00", "/leaderboard?moduleset=toy&cost=cyc&task=%00"):
        r = site.get(url)
        assert r.status_code == 400, (url, r.status_code, r.text[:200])
        assert "NUL" in r.text
    # in a task file (its name) and a module set name: refused before anything is stored
    t = task_json()
    t["header"]["ID"], t["header"]["taskName"] = "toy/nul", "bad\u0000name"
    before = listing(tmp_path / "data" / "tasks")
    r = site.post("/api/tasks", json=t)
    assert r.status_code == 400 and "NUL" in r.json()["detail"]
    r = site.post("/api/modulesets", content=b"{}", headers={"content-type": "application/json"},
                  params={"name": "a\x00b"})
    assert r.status_code == 400
    assert listing(tmp_path / "data" / "tasks") == before
    assert [t["id"] for t in site.get("/api/tasks").json()] == ["toy/all"]
    assert board(site).json()["entries"] == []


@pytest.mark.parametrize("sid", [str(2 ** 31), str(BIG), str(2 ** 64), "9" * 40, "-1", "1.5", "abc", "0x10"])
def test_ids_out_of_range_are_404_on_every_id_route(site, sid):
    ok = upload(site, sol_json(), author="Ada")
    assert ok.status_code == 201
    for method, url in (("GET", f"/solutions/{sid}"), ("GET", f"/solutions/{sid}/viewer"),
                        ("POST", f"/solutions/{sid}/withdraw"), ("GET", f"/api/solutions/{sid}"),
                        ("GET", f"/api/solutions/{sid}/json"), ("DELETE", f"/api/solutions/{sid}")):
        r = site.request(method, url, data={"token": "x" * 10} if method == "POST" else None,
                         headers={"X-Author-Token": ok.json()["token"]})
        assert r.status_code == 404, (method, url, r.status_code, r.text[:200])
    assert [e["id"] for e in board(site).json()["entries"]] == [ok.json()["id"]]  # nothing withdrawn


def test_largest_id_is_a_plain_404(site):
    r = site.get(f"/api/solutions/{2 ** 31 - 1}")  # the largest ID an Integer column holds on PostgreSQL
    assert r.status_code == 404 and r.json()["detail"] == f"unknown solution {2 ** 31 - 1}"


def test_long_identifiers_are_400_before_the_check(site, tmp_path):
    long_cost = ",".join(["cyc_0.1"] * 43)  # 343 characters, a valid descriptor (= cyc_4.3)
    r = upload(site, sol_json(cost=long_cost))
    assert r.status_code == 400
    assert r.json()["detail"] == "solution.json: costFunction: at most 300 characters are allowed (got 343)"
    s = sol_json()
    s["taskID"] = "toy/" + "a" * 220
    r = upload(site, s)
    assert r.status_code == 400 and "taskID: at most 200 characters" in r.json()["detail"]
    r = upload(site, sol_json(), author="A" * 201)
    assert r.status_code == 400 and r.json()["detail"] == "author: at most 200 characters are allowed (got 201)"
    r = upload(site, sol_json(), email="e" * 250)
    assert r.status_code == 400 and "email: at most 200" in r.json()["detail"]
    assert site.get("/api/benchmarks").json() == [] and site.get("/api/solutions").json() == []
    # a task name beyond its column: 400, and no task folder is left behind
    before = listing(tmp_path / "data" / "tasks")
    t = task_json()
    t["header"]["ID"], t["header"]["taskName"] = "toy/longname", "n" * 201
    r = site.post("/api/tasks", json=t)
    assert r.status_code == 400
    assert r.json()["detail"] == "task.json: header.taskName: at most 200 characters are allowed (got 201)"
    assert listing(tmp_path / "data" / "tasks") == before
    assert listing(site.app.state.bench.tmp) == []
    t["header"]["taskName"] = "n" * 200  # at the limit: fine
    assert site.post("/api/tasks", json=t).status_code == 201
    assert len(listing(tmp_path / "data" / "tasks")) > len(before)


def test_negative_or_non_finite_cost_weights_are_400(site):
    for cost in ("cyc_-1", "cyc_-0.5,mechEnergy", "[(cyc|-1)]", "cyc_inf", "cyc_1e400"):
        r = upload(site, sol_json(cost=cost))
        assert r.status_code == 400, (cost, r.text)
        assert "costFunction" in r.json()["detail"]
    assert site.get("/api/benchmarks").json() == []
    assert board(site, "M-toy:cyc_-1:toy/all").status_code == 400


# ------------------------------------------------------------------------------------------------------------
# size caps (413) and listings that never read the stored files
# ------------------------------------------------------------------------------------------------------------
def test_size_caps_are_413_naming_the_field(make_site):
    c = make_site(limits=Limits(notes_chars=1000, text_chars=50, list_items=3, trajectory_values=600))
    r = upload(c, sol_json() | {"notes": "n" * 1001})
    assert r.status_code == 413
    assert r.json()["detail"] == "solution.json: notes: at most 1000 characters are allowed (got 1001)"
    r = upload(c, sol_json() | {"publication": "p" * 51})
    assert r.status_code == 413 and "publication: at most 50 characters" in r.json()["detail"]
    r = upload(c, sol_json() | {"tags": ["a", "b", "c", "d"]})
    assert r.status_code == 413 and "tags: at most 3 entries" in r.json()["detail"]
    r = upload(c, sol_json() | {"author": ["Ada", "B" * 51]})
    assert r.status_code == 413 and "author[1]: at most 50 characters" in r.json()["detail"]
    # the toy trajectory has 351 samples × 2 joints = 702 values
    r = upload(c, sol_json())
    assert r.status_code == 413
    assert r.json()["detail"] == ("solution.json: trajectory: 351 samples × 2 joints = 702 values; at most 600 are "
                                  "allowed")
    assert c.get("/api/solutions").json() == []
    c2 = make_site(limits=Limits(notes_chars=1000, trajectory_values=702))
    r = upload(c2, sol_json() | {"notes": "n" * 1000})
    assert r.status_code == 201, r.text


def test_listings_read_only_the_columns_they_show(site):
    for k in (1.0, 1.5):
        assert upload(site, sol_json(k) | {"notes": "N" * 10_000}, author=f"k{k}").status_code == 201
    statements = []
    engine = site.app.state.bench.engine

    def log(_conn, _cursor, statement, *_a):
        statements.append(statement)

    event.listen(engine, "before_cursor_execute", log)
    try:
        for url in ("/", f"/leaderboard/{BOARD}", f"/api/leaderboard/{BOARD}", "/api/solutions", "/api/tasks",
                    "/api/modulesets", "/api/benchmarks", "/tasks/toy/all", "/solutions/1", "/api/solutions/1"):
            r = site.get(url)
            assert r.status_code == 200, url
            assert "NNNNNNNNNN" not in r.text
    finally:
        event.remove(engine, "before_cursor_execute", log)
    sql = "\n".join(statements)
    assert "solutions.id" in sql and "solutions.author_name" in sql
    for column in ("solution_json", "costs_json", "token_hash", "tasks.json", "module_sets.json"):
        assert column not in sql, column
    # the file itself is still there on its own route
    assert site.get("/api/solutions/1/json").json()["notes"] == "N" * 10_000


# ------------------------------------------------------------------------------------------------------------
# rate limits and the check queue
# ------------------------------------------------------------------------------------------------------------
def test_rate_limiter_token_bucket():
    now = [0.0]
    rl = RateLimiter(rate=2.0, burst=3, max_clients=2, clock=lambda: now[0])
    assert [rl.wait_time("a") for _ in range(3)] == [0, 0, 0]
    assert rl.wait_time("a") == pytest.approx(0.5)  # empty: one token comes back after 1/2 s
    assert rl.wait_time("b") == 0  # another client has its own bucket
    now[0] = 0.5
    assert rl.wait_time("a") == 0 and rl.wait_time("a") == pytest.approx(0.5)
    rl.wait_time("c")  # a third client evicts the least recently used bucket ("b")
    assert set(rl._buckets) == {"a", "c"}
    assert RateLimiter(0, 0).wait_time("x") == 0  # rate 0: no limit


def test_per_client_rate_limits_are_429_with_retry_after(make_site):
    c = make_site(upload_rate=6, read_rate=1)  # uploads: 6/min, bursts of 2; reads: 1/s, bursts of 5
    assert [upload(c, sol_json(1 + k / 10)).status_code for k in range(2)] == [201, 201]
    r = upload(c, sol_json(1.3))
    # one upload per 10 s: the wait left, rounded up (a second may pass on a loaded machine before the 429)
    assert r.status_code == 429 and 1 <= int(r.headers["retry-after"]) <= 10
    assert "too many uploads" in r.json()["detail"]
    statuses = [c.get("/api/tasks").status_code for _ in range(6)]
    assert statuses == [200] * 5 + [429]
    r = c.get("/")
    assert r.status_code == 429 and int(r.headers["retry-after"]) == 1 and "text/html" in r.headers["content-type"]
    assert c.get("/healthz").status_code == 200  # never limited
    # another client is not affected
    other = TestClient(c.app, client=("203.0.113.7", 4000))
    assert other.get("/api/tasks").status_code == 200
    assert upload(other, sol_json(1.4)).status_code == 201


def _gate(app):
    """Make every check wait until the returned event is set (to hold jobs in the queue)."""
    gate = threading.Event()
    bench = app.state.bench
    original = bench.judge

    def judge(sub, **kw):
        assert gate.wait(60)
        return original(sub, **kw)

    bench.judge = judge
    return gate


def _wait_state(c, job, state, timeout=30):
    deadline = time.time() + timeout
    while time.time() < deadline:
        s = c.get(f"/api/checks/{job}").json()
        if s["state"] == state:
            return s
        time.sleep(0.05)
    raise AssertionError(f"job {job} never reached {state}: {s}")


def test_check_queue_full_is_429_and_reports_the_position(make_site):
    c = make_site(check_workers=1, queue_size=2, per_client_queue=2, upload_rate=0, read_rate=0)
    gate = _gate(c.app)
    clients = [TestClient(c.app, client=(f"198.51.100.{i}", 1000)) for i in range(5)]
    first = clients[0].post("/api/solutions?async=1", json={"solution": sol_json(1.0), "author": "A"})
    assert first.status_code == 202, first.text
    j0 = first.json()
    assert j0["status_url"] == f"/api/checks/{j0['job']}" and first.headers["location"] == j0["status_url"]
    _wait_state(c, j0["job"], "checking")
    jobs = []
    for i in (1, 2):
        r = clients[i].post("/api/solutions", json={"solution": sol_json(1 + i / 10), "author": f"U{i}"},
                            headers={"Prefer": "respond-async"})
        assert r.status_code == 202 and r.json()["state"] == "queued"
        assert r.json()["position"] == i - 1  # jobs ahead of it in the line
        jobs.append(r.json()["job"])
    # the line is full: 429 (once the body has arrived: a slow sender holds no place), with a Retry-After
    r = clients[3].post("/api/solutions", json={"solution": sol_json(1.5), "author": "late"})
    assert r.status_code == 429 and int(r.headers["retry-after"]) >= 1
    assert "queue is full (2 uploads waiting)" in r.json()["detail"]
    assert c.get("/api/queue").json() == {"workers": 1, "checking": 1, "waiting": 2, "receiving": 0,
                                          "max_waiting": 2}
    s = c.get(f"/api/checks/{jobs[1]}").json()
    assert s["state"] == "queued" and s["position"] == 1 and s["waiting"] == 2 and "result" not in s
    gate.set()
    done = [_wait_state(c, j, "done") for j in [j0["job"]] + jobs]
    assert [d["status"] for d in done] == [201, 201, 201]
    assert [d["result"]["cost"] for d in done] == pytest.approx([3.5, 3.85, 4.2])
    assert [e["author"] for e in board(c).json()["entries"]] == ["A", "U1", "U2"]
    # a synchronous upload reports where it joined the line
    r = clients[4].post("/api/solutions", json={"solution": sol_json(2.0), "author": "sync"})
    assert r.status_code == 201 and r.json()["queue_position"] == 0 and r.json()["cost"] == pytest.approx(7.0)
    assert c.get("/api/checks/unknown").status_code == 404


def test_one_client_holds_at_most_per_client_places(make_site):
    c = make_site(check_workers=1, queue_size=10, per_client_queue=2, upload_rate=0)
    gate = _gate(c.app)
    rs = [c.post("/api/solutions?async=1", json={"solution": sol_json(1 + k / 10), "author": "A"}) for k in range(3)]
    assert [r.status_code for r in rs] == [202, 202, 429]
    assert "already have 2 upload(s) being checked" in rs[2].json()["detail"] and rs[2].headers["retry-after"]
    gate.set()
    for r in rs[:2]:
        _wait_state(c, r.json()["job"], "done")
    assert c.post("/api/solutions?async=1", json={"solution": sol_json(2.0), "author": "A"}).status_code == 202


def test_bodies_one_client_may_be_sending_at_once():
    # by default as many as its places in the line, at least 16; the 17th (25th) at once is refused (Busy = 429)
    from robodesign.web.throttle import Busy, CheckQueue
    for per_client, allowed in ((2, 16), (24, 24)):
        q = CheckQueue(1, 8, per_client)
        try:
            for _ in range(allowed):
                q.start_receiving("10.0.0.1")
            with pytest.raises(Busy, match=f"already sending {allowed} uploads"):
                q.start_receiving("10.0.0.1")
            q.start_receiving("10.0.0.2")  # another client is not affected
            q.done_receiving("10.0.0.1")
            q.start_receiving("10.0.0.1")  # a body has arrived: room for one more
        finally:
            q.close()
    q = CheckQueue(1, 8, 24, per_client_receiving=3)
    try:
        for _ in range(3):
            q.start_receiving("10.0.0.1")
        with pytest.raises(Busy):
            q.start_receiving("10.0.0.1")
    finally:
        q.close()


def test_small_upload_is_not_stuck_behind_big_checks(make_site):
    small_sol = sol_json(3.0)
    for key in ("q", "dq", "ddq"):  # one joint only: smaller (and invalid for the 2-joint robot)
        small_sol["trajectory"][key] = [row[:1] for row in small_sol["trajectory"][key]]
    small, big = len(json.dumps(small_sol)), len(json.dumps(sol_json(1.0)))
    assert small < 0.8 * big
    # 2 checker threads; uploads larger than the threshold are "big" and use at most one of them
    c = make_site(check_workers=2, queue_size=4, upload_rate=0, big_upload_bytes=(small + big) // 2)
    gate = _gate(c.app)
    big_jobs = [TestClient(c.app, client=(f"192.0.2.{i}", 1)).post(
        "/api/solutions", content=json.dumps(sol_json(1 + i / 10)), params={"author": f"big{i}", "async": 1},
        headers={"content-type": "application/json"}).json()["job"] for i in range(2)]
    _wait_state(c, big_jobs[0], "checking")
    time.sleep(0.2)
    assert c.get(f"/api/checks/{big_jobs[1]}").json()["state"] == "queued"  # waits for the big slot
    # the small upload takes the free thread at once, ahead of the big one that arrived earlier
    r = TestClient(c.app, client=("192.0.2.99", 1)).post(
        "/api/solutions", content=json.dumps(small_sol), params={"author": "small", "async": 1},
        headers={"content-type": "application/json"})
    assert r.status_code == 202 and r.json()["position"] == 0
    _wait_state(c, r.json()["job"], "checking")
    assert c.get(f"/api/checks/{big_jobs[1]}").json()["state"] == "queued"
    gate.set()
    assert _wait_state(c, r.json()["job"], "done")["status"] == 422
    assert [_wait_state(c, j, "done")["status"] for j in big_jobs] == [201, 201]


# ------------------------------------------------------------------------------------------------------------
# slow bodies, stale staging folders, the viewer cache
# ------------------------------------------------------------------------------------------------------------
def _read_all(s: socket.socket) -> str:
    """Everything the server sends until it closes the connection (the head and the body may come apart)."""
    chunks = []
    while True:
        b = s.recv(65536)
        if not b:
            return b"".join(chunks).decode()
        chunks.append(b)


def test_slow_body_is_408_and_the_server_stays_up(tmp_path, seed_dir):
    app = create_app(data_dir=tmp_path / "data", seed=[seed_dir], seed_builtin=False, body_timeout=1.0)
    with running_server(app) as url:
        host, port = url.rsplit("//", 1)[1].split(":")
        with socket.create_connection((host, int(port)), timeout=10) as s:
            s.sendall(b"POST /api/solutions HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                      b"Content-Length: 100000\r\n\r\n" + b"[" * 100)
            reply = _read_all(s)
        assert reply.startswith("HTTP/1.1 408"), reply
        assert "did not arrive within 1 s" in reply
        assert app.state.queue.stats()["receiving"] == 0  # its place in the queue was given back
        import urllib.request
        with urllib.request.urlopen(f"{url}/healthz", timeout=10) as r:
            assert r.status == 200


def test_startup_removes_stale_staging_folders(tmp_path, seed_dir):
    tmp = tmp_path / "data" / "tmp"
    (tmp / "0123abcd" / "pkg").mkdir(parents=True)  # an old-style staging folder (no lock)
    (tmp / "0123abcd" / "pkg" / "half.stl").write_bytes(b"solid half")
    (tmp / "srv-99999-dead").mkdir()  # a killed server's folder: its lock file is not held
    (tmp / "srv-99999-dead" / "x.json").write_text("{}")
    (tmp / "srv-99999-dead.lock").write_text("")
    (tmp / "srv-1-alive").mkdir()  # a server still running on the same data folder holds its lock
    (tmp / "srv-1-alive" / "y.json").write_text("{}")
    held = open(tmp / "srv-1-alive.lock", "w")
    fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
    try:
        app = create_app(data_dir=tmp_path / "data", seed=[seed_dir], seed_builtin=False)
        bench = app.state.bench
        assert bench.removed_staging == ["0123abcd", "srv-99999-dead"]
        assert sorted(p.name for p in tmp.iterdir()) == sorted(
            ["srv-1-alive", "srv-1-alive.lock", bench.tmp.name, bench.tmp.name + ".lock"])
        assert (tmp / "srv-1-alive" / "y.json").is_file()
        assert any("removed the staging folder tmp/srv-99999-dead" in x for x in bench.seed_log)
        # a second server on the same folder leaves the first one's staging folder alone
        app2 = create_app(data_dir=tmp_path / "data", seed=[seed_dir], seed_builtin=False)
        assert app2.state.bench.removed_staging == [] and bench.tmp.is_dir()
        for a in (app, app2):
            a.state.queue.close()
            a.state.bench.close()
        assert sorted(p.name for p in tmp.iterdir()) == ["srv-1-alive", "srv-1-alive.lock"]
    finally:
        held.close()


def test_byte_lru_is_bounded_by_bytes():
    c = ByteLRU(1000)
    c.put(1, "a" * 400)
    c.put(2, "é" * 200)  # 400 bytes in UTF-8
    assert c.bytes == 800 and len(c) == 2
    assert c.get(1) == "a" * 400  # 1 is now the most recently used
    c.put(3, b"b" * 400)  # 1200 > 1000: the least recently used (2) goes
    assert 2 not in c and 1 in c and 3 in c and c.bytes == 800
    c.put(4, "x" * 1001)  # larger than the whole cache: not kept, nothing else evicted
    assert 4 not in c and c.bytes == 800
    c.put(1, "z" * 10)  # replacing a value updates the size
    assert c.bytes == 410 and c.get(1) == "z" * 10


def test_viewer_cache_is_bounded_by_bytes(make_site):
    pytest.importorskip("robodesign.viewer", reason="the 3D viewer is not installed")
    c = make_site(upload_rate=0)
    cache = c.app.state.viewer_cache
    assert cache.max_bytes == 64 * 2 ** 20  # the default
    ids = [upload(c, sol_json(1 + k / 10), author=f"v{k}").json()["id"] for k in range(3)]
    sizes = []
    for sid in ids:
        r = c.get(f"/solutions/{sid}/viewer")
        assert r.status_code == 200
        sizes.append(len(r.content))
        if len(sizes) == 1:
            cache.max_bytes = int(2.5 * sizes[0])  # room for two pages, not three
    assert cache.bytes == sizes[1] + sizes[2] <= cache.max_bytes, sizes
    assert ids[0] not in cache and ids[1] in cache and ids[2] in cache


# ------------------------------------------------------------------------------------------------------------
# registration: an admin action by default
# ------------------------------------------------------------------------------------------------------------
def _new_task(tid):
    t = task_json()
    t["header"]["ID"] = tid
    return t


def test_registration_needs_the_admin_token(make_site, monkeypatch):
    monkeypatch.delenv("ROBODESIGN_ADMIN_TOKEN", raising=False)
    closed = make_site(admin_token=None)
    r = closed.post("/api/tasks", json=_new_task("toy/a"))
    assert r.status_code == 403 and "disabled on this server" in r.json()["detail"]
    c = make_site()
    anon = TestClient(c.app)
    r = anon.post("/api/tasks", json=_new_task("toy/b"))
    assert r.status_code == 403 and "admin action" in r.json()["detail"]
    r = anon.post("/api/tasks", json=_new_task("toy/b"), headers={"X-Admin-Token": "wrong-token-0123456789"})
    assert r.status_code == 403 and "the one given is wrong" in r.json()["detail"]
    r = anon.post("/api/modulesets", content=b"{}", params={"name": "x"}, headers={"content-type": "application/json"})
    assert r.status_code == 403
    assert anon.post("/api/tasks", json=_new_task("toy/b"), headers={"Authorization": f"Bearer {ADMIN}"}).status_code \
        == 201
    assert anon.post("/api/tasks", json=_new_task("toy/c"), headers=ADMIN_HEADERS).status_code == 201
    assert [t["id"] for t in anon.get("/api/tasks").json()] == ["toy/all", "toy/b", "toy/c"]
    # solutions stay open to everyone
    assert upload(anon, sol_json()).status_code == 201


def test_admin_token_from_the_environment_and_open_registration(make_site, monkeypatch):
    monkeypatch.setenv("ROBODESIGN_ADMIN_TOKEN", "token-from-the-environment")
    c = make_site(admin_token=None)
    anon = TestClient(c.app)
    assert anon.post("/api/tasks", json=_new_task("toy/d")).status_code == 403
    assert anon.post("/api/tasks", json=_new_task("toy/d"),
                     headers={"X-Admin-Token": "token-from-the-environment"}).status_code == 201
    monkeypatch.delenv("ROBODESIGN_ADMIN_TOKEN")
    opened = TestClient(make_site(admin_token=None, open_registration=True).app)
    assert opened.post("/api/tasks", json=_new_task("toy/e")).status_code == 201
    with pytest.raises(Exception, match="at least 16 characters"):
        make_site(admin_token="short")


# ------------------------------------------------------------------------------------------------------------
# checks in separate processes (robodesign serve's default)
# ------------------------------------------------------------------------------------------------------------
def test_checks_in_processes(make_site):
    c = make_site(check_processes=True, check_workers=1, upload_rate=0)
    r = upload(c, sol_json(1.2), author="Proc")
    assert r.status_code == 201 and r.json()["cost"] == pytest.approx(4.2)
    r = upload(c, sol_json(broken=True))
    assert r.status_code == 422 and r.json()["violations"][0]["constraint"] == "joint.q"
    r = raw_post(c, b"[" * 5000 + b"]" * 5000)
    assert r.status_code == 400 and "nested deeper than 100 levels" in r.json()["detail"]
    r = c.post("/api/solutions?async=1", json={"solution": sol_json(1.5), "author": "Async"})
    assert r.status_code == 202
    assert _wait_state(c, r.json()["job"], "done")["result"]["cost"] == pytest.approx(5.25)
    assert [(e["author"], e["cost"]) for e in board(c).json()["entries"]] == [("Proc", pytest.approx(4.2)),
                                                                            ("Async", pytest.approx(5.25))]
    # a checker process that dies: that upload is a 500, the next one gets a new process
    import os
    import signal
    pool = c.app.state.checker._get_pool()
    for pid in list(pool._processes):
        os.kill(pid, signal.SIGKILL)
    time.sleep(0.5)
    r = upload(c, sol_json(1.1), author="After")
    if r.status_code == 500:  # the broken pool noticed on this upload
        r = upload(c, sol_json(1.1), author="After")
    assert r.status_code == 201 and r.json()["cost"] == pytest.approx(3.85)


# ------------------------------------------------------------------------------------------------------------
# issue 22 case 11: text that is not text (lone surrogates), on both databases
# ------------------------------------------------------------------------------------------------------------
LONE = "\ud800"  # json.dumps writes it as the escape \ud800


@pytest.mark.parametrize("field", ["key", "author", "email", "affiliation", "token", "goal2time"])
def test_lone_surrogates_are_400_naming_the_field(site, field):
    sol = sol_json(1.0)
    body = {"solution": sol, "author": "A"}
    if field == "key":
        sol["x" + LONE] = 1
        where, in_file = "solution.json: solution.x\\ud800", "solution.json: x\\ud800"
    elif field == "goal2time":
        g = next(iter(sol["trajectory"]["goal2time"]))
        sol["trajectory"]["goal2time"][g + LONE] = sol["trajectory"]["goal2time"].pop(g)
        in_file = f"solution.json: trajectory.goal2time.{g}\\ud800"
        where = in_file.replace(": ", ": solution.")
    else:
        body[field] = "x" * 8 + LONE
        where = f"solution.json: {field}"
    text = json.dumps(body)
    assert "\\ud800" in text
    r = raw_post(site, text)
    assert r.status_code == 400 and r.json()["detail"].startswith(where), r.text
    assert "lone UTF-16 surrogate" in r.json()["detail"]
    # the same as an async upload: accepted (stored), then judged 400, and its job page answers
    r = raw_post(site, text, params={"async": 1})
    assert r.status_code == 202, r.text
    done = _wait_state(site, r.json()["job"], "done")
    assert done["status"] == 400 and done["result"]["detail"].startswith(where)
    # and through the form: the solution file holds it
    if field in ("key", "goal2time"):
        r = upload(site, sol)
        assert r.status_code == 400 and r.json()["detail"].startswith(in_file), r.text
    assert board(site).json()["entries"] == []
    assert site.get("/api/solutions").json() == []


def test_invalid_utf8_in_form_fields_is_not_a_500(site):
    body = (b"--B\r\nContent-Disposition: form-data; name=\"author\"\r\n\r\n\xed\xa0\x80\r\n"
            b"--B\r\nContent-Disposition: form-data; name=\"file\"; filename=\"s.json\"\r\n"
            b"Content-Type: application/json\r\n\r\n" + json.dumps(sol_json(1.0)).encode() + b"\r\n--B--\r\n")
    r = site.post("/api/solutions", content=body, headers={"content-type": "multipart/form-data; boundary=B"})
    assert r.status_code in (201, 400), r.text
    if r.status_code == 201:  # the parser falls back to Latin-1 for a field that is not UTF-8: text all the same
        sid = r.json()["id"]
        assert site.get(f"/api/solutions/{sid}").json()["author"] == b"\xed\xa0\x80".decode("latin-1")
        assert site.get(f"/solutions/{sid}").status_code == 200
