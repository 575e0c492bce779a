"""The benchmark website (robodesign.web): uploads, checks, leaderboards, queries, withdrawal and the safety rules,
through FastAPI's TestClient and a real uvicorn server; the same flow on a throwaway PostgreSQL cluster.

Solutions are the toy plan of tests/test_checker.py on the toy module set of tests/conftest.py; slower versions
(time scaled by k: t·k, dq/k, ddq/k², goal times ·k) stay valid with cycle time 3.5·k, which gives solutions with
known, distinct costs.
"""
from __future__ import annotations

import contextlib
import glob
import io
import json
import os
import pwd
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request
import zipfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

ROOT = __import__('pathlib').Path(__file__).resolve().parents[1]

pytest.importorskip("fastapi", reason="the website needs fastapi (pip install fastapi uvicorn sqlalchemy "
                                      "python-multipart)")
from fastapi.testclient import TestClient  # noqa: E402

from robodesign import load_module_set  # noqa: E402
from robodesign.judge.checker import check  # noqa: E402
from robodesign.formats.task_io import parse_task  # noqa: E402
from robodesign.web import create_app  # noqa: E402

from conftest import toy_module_set  # noqa: E402
from test_checker import plan, solution  # noqa: E402
from test_checker import task_json as _checker_task_json  # noqa: E402

#: the slowest toy solution the tests upload is k = 2.9 (steps of 0.029 s): the judge allows no step longer than
#: the task's time step, so the site's toy task has a 0.03 s one
WEB_TIME_STEP = 0.03


def task_json(**kw) -> dict:
    """The checker tests' toy task with the site's time step (:data:`WEB_TIME_STEP`)."""
    d = _checker_task_json(**kw)
    d["header"]["timeStepSize"] = WEB_TIME_STEP
    return d

BOARD = "M-toy:cyc:toy/all"
ADMIN = "admin-token-of-the-tests"  # registering tasks and module sets is an admin action
# s: the viewer's build deadline (60 s by default) is not what most tests test; at load 8 a build took longer
# (docs/benchmarks.md, "The test suite beside a CPU hog"); the deadline's own test sets a tiny one
SLOW_MACHINE_VIEWER_TIMEOUT = 600.0
ADMIN_HEADERS = {"X-Admin-Token": ADMIN}


# ------------------------------------------------------------------------------------------------------------
# helpers and fixtures
# ------------------------------------------------------------------------------------------------------------
def toy_solution(k: float = 1.0, broken: bool = False, **kw):
    """The valid toy plan slowed down by k (cyc = 3.5·k); ``broken``: joint 0 crosses its limit 3.2 at sample 40."""
    t, q, dq, ddq, g2t = plan()
    q = q.copy()
    if broken:
        q[40, 0] = 3.3
    return solution(t * k, q, dq / k, ddq / k ** 2, {g: v * k for g, v in g2t.items()}, **kw)


def sol_json(k: float = 1.0, broken: bool = False, **kw) -> dict:
    return toy_solution(k, broken, **kw).to_json()


def make_seed(folder: Path) -> Path:
    """A seed folder as `robodesign serve --seed` expects it: modules/<set>/modules.json, tasks/<ID>.json."""
    toy_module_set(folder / "modules")
    (folder / "tasks" / "toy").mkdir(parents=True, exist_ok=True)
    (folder / "tasks" / "toy" / "all.json").write_text(json.dumps(task_json()))
    return folder


@pytest.fixture(scope="module")
def seed_dir(tmp_path_factory):
    return make_seed(tmp_path_factory.mktemp("seed"))


@pytest.fixture(scope="module")
def judge(seed_dir):
    """The checker run locally on the same task and module set: the costs the site must report."""
    ms = load_module_set(seed_dir / "modules" / "toy")
    task = parse_task(task_json(), seed_dir / "tasks" / "toy" / "all.json")
    return lambda sol: check(task, sol, ms)


@pytest.fixture
def client(tmp_path, seed_dir):
    app = create_app(admin_token=ADMIN, data_dir=tmp_path / "data", seed=[seed_dir], seed_builtin=False,
                     viewer_timeout=SLOW_MACHINE_VIEWER_TIMEOUT)
    with TestClient(app, headers=ADMIN_HEADERS) as c:
        yield c


def upload(c, sol: dict, author="Ada Lovelace", token=None, **extra):
    data = {"author": author, **extra}
    if token:
        data["token"] = token
    return c.post("/api/solutions", files={"file": ("solution.json", json.dumps(sol), "application/json")},
                  data=data)


def listing(root: Path):
    return sorted(str(p.relative_to(root)) for p in Path(root).rglob("*"))


def stl_box() -> bytes:
    import trimesh
    return trimesh.creation.box(extents=(0.2, 0.2, 0.2)).export(file_type="stl")


def mesh_task(tid="toy/mesh", ref="assets/box.stl") -> dict:
    box = {"ID": "box", "collision": {"type": "mesh", "parameters": {"file": ref},
                                      "pose": [[1, 0, 0, 2], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}}
    d = task_json(obstacles=[box])
    d["header"]["ID"] = tid
    return d


def zip_bytes(entries) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        for name, data in entries:  # name: str or ZipInfo
            z.writestr(name, data)
    return buf.getvalue()


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextlib.contextmanager
def running_server(app):
    """uvicorn in a thread on 127.0.0.1:<free port>; yields the base URL."""
    import uvicorn
    port = free_port()
    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning"))
    th = threading.Thread(target=server.run, daemon=True)
    th.start()
    deadline = time.time() + 20
    while not server.started:
        if time.time() > deadline or not th.is_alive():
            raise RuntimeError("uvicorn did not start")
        time.sleep(0.02)
    try:
        yield f"http://127.0.0.1:{port}"
    finally:
        server.should_exit = True
        th.join(15)


def http(method, url, body=None, headers=None, timeout=60):
    data = json.dumps(body).encode() if body is not None else None
    req = urllib.request.Request(url, data=data, method=method,
                                 headers={"Content-Type": "application/json", **(headers or {})})
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            return r.status, json.loads(r.read() or b"null")
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read() or b"null")


# ------------------------------------------------------------------------------------------------------------
# the upload → check → leaderboard flow (shared by SQLite and PostgreSQL)
# ------------------------------------------------------------------------------------------------------------
def exercise_site(c, judge):
    # a valid solution: 201, the checker's cost, a token
    expected = judge(toy_solution(1.0))
    assert expected.valid
    r = upload(c, sol_json(1.0), author="Ada Lovelace", affiliation="Analytical Engines")
    assert r.status_code == 201, r.text
    body = r.json()
    assert body["valid"] is True and body["benchmark_id"] == BOARD
    assert body["cost"] == pytest.approx(expected.cost) and body["cost"] == pytest.approx(3.5)
    assert isinstance(body["token"], str) and len(body["token"]) >= 30
    sid, token = body["id"], body["token"]

    # an invalid one: joint limit crossed → 422 naming joint.q, not stored
    r = c.post("/api/solutions", json={"solution": sol_json(1.0, broken=True), "author": "Bob"})
    assert r.status_code == 422, r.text
    v = r.json()
    assert v["valid"] is False and v["id"] is None and "token" not in v
    jq = [x for x in v["violations"] if x["constraint"] == "joint.q"]
    assert jq and jq[0]["sample"] == 40 and jq[0]["value"] == 3.3 and jq[0]["bound"] == 3.2
    assert "joint.q" in v["detail"]

    # a second valid one, slower: ranked behind the first
    r2 = upload(c, sol_json(1.5), author="Grace Hopper")
    assert r2.status_code == 201, r2.text
    assert r2.json()["cost"] == pytest.approx(judge(toy_solution(1.5)).cost) == pytest.approx(5.25)

    lb = c.get(f"/api/leaderboard/{BOARD}").json()
    assert lb["benchmark_id"] == BOARD and lb["task"] == "toy/all" and lb["module_set"] == "toy"
    assert [(e["id"], e["rank"], e["author"]) for e in lb["entries"]] == \
        [(sid, 1, "Ada Lovelace"), (r2.json()["id"], 2, "Grace Hopper")]
    assert lb["entries"][0]["cost"] == pytest.approx(expected.cost)
    page = c.get(f"/leaderboard/{BOARD}")
    assert page.status_code == 200 and "Ada Lovelace" in page.text and "Grace Hopper" in page.text
    assert page.text.index("Ada Lovelace") < page.text.index("Grace Hopper")
    assert "Bob" not in page.text

    # withdraw: wrong / missing token → 403, right one → 200 and gone from the leaderboard
    assert c.delete(f"/api/solutions/{sid}", headers={"X-Author-Token": "not-the-token"}).status_code == 403
    assert c.delete(f"/api/solutions/{sid}").status_code == 403
    assert len(c.get(f"/api/leaderboard/{BOARD}").json()["entries"]) == 2
    r = c.delete(f"/api/solutions/{sid}", headers={"X-Author-Token": token})
    assert r.status_code == 200 and r.json()["withdrawn"] is True
    lb = c.get(f"/api/leaderboard/{BOARD}").json()
    assert [e["id"] for e in lb["entries"]] == [r2.json()["id"]] and lb["entries"][0]["rank"] == 1
    assert sid not in [s["id"] for s in c.get("/api/solutions").json()]
    assert c.get(f"/api/solutions/{sid}").json()["withdrawn"] is True
    return sid


def test_upload_check_rank_withdraw_sqlite(client, judge, tmp_path):
    exercise_site(client, judge)
    db = tmp_path / "data" / "bench.db"
    assert db.is_file()
    import sqlite3
    with sqlite3.connect(db) as con:
        assert con.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        (th,) = con.execute("SELECT token_hash FROM solutions WHERE id = 1").fetchone()
    assert th.startswith("pbkdf2_sha256$")  # stored hashed, never in clear


def test_solution_api_details_and_raw_json(client, judge):
    r = upload(client, sol_json(1.2), email="ada@example.org")
    sid = r.json()["id"]
    d = client.get(f"/api/solutions/{sid}").json()
    exp = judge(toy_solution(1.2))
    assert d["cost"] == pytest.approx(exp.cost) and d["verdict"]["valid"] is True
    assert d["verdict"]["costs"]["mass"] == pytest.approx(exp.costs["mass"]) and d["email"] is None
    raw = client.get(f"/api/solutions/{sid}/json").json()
    assert raw["taskID"] == "toy/all" and raw["moduleOrder"] == ["B", "J", "J", "E"]
    assert client.get("/api/solutions/999").status_code == 404


def test_chosen_token_and_json_body_with_header_token(client):
    r = client.post("/api/solutions", json=sol_json(1.0, cost="cyc"), params={"author": "Eve"},
                    headers={"X-Author-Token": "my-own-secret-token"})
    assert r.status_code == 201 and r.json()["token"] == "my-own-secret-token"
    sid = r.json()["id"]
    assert client.delete(f"/api/solutions/{sid}", headers={"X-Author-Token": "my-own-secret"}).status_code == 403
    assert client.delete(f"/api/solutions/{sid}", headers={"X-Author-Token": "my-own-secret-token"}).status_code == 200
    # a chosen token must not be trivially short
    r = upload(client, sol_json(), token="short")
    assert r.status_code == 400 and "token" in r.json()["detail"]


def test_other_cost_function_is_another_benchmark(client, judge):
    r = upload(client, sol_json(1.0, cost="Liu2"))
    assert r.status_code == 201 and r.json()["benchmark_id"] == "M-toy:Liu2:toy/all"
    assert r.json()["cost"] == pytest.approx(judge(toy_solution(1.0, cost="Liu2")).cost)
    # the same cost written as a weighted descriptor is the same benchmark
    lb = client.get("/api/leaderboard/M-toy:[(mechEnergy|1),(cyc|0.2)]:toy/all").json()
    assert [e["id"] for e in lb["entries"]] == [r.json()["id"]]
    assert client.get(f"/api/leaderboard/{BOARD}").json()["entries"] == []
    # a bare robot name means M-
    assert client.get("/api/leaderboard/toy:Liu2:toy/all").json()["benchmark_id"] == "M-toy:Liu2:toy/all"
    r2 = upload(client, sol_json(1.2, cost="cyc_0.2,mechEnergy"))
    assert r2.status_code == 201 and r2.json()["benchmark_id"] == "M-toy:cyc_0.2,mechEnergy:toy/all"
    lb = client.get("/api/leaderboard/M-toy:Liu2:toy/all").json()
    # slower is cheaper here: Liu2 = mechEnergy + 0.2·cyc and the mechanical energy falls with the speed
    c1, c2 = judge(toy_solution(1.0, cost="Liu2")).cost, judge(toy_solution(1.2, cost="Liu2")).cost
    assert c2 < c1 and r2.json()["cost"] == pytest.approx(c2)
    assert [(e["id"], e["cost"]) for e in lb["entries"]] == [(r2.json()["id"], pytest.approx(c2)),
                                                             (r.json()["id"], pytest.approx(c1))]
    (b,) = client.get("/api/benchmarks").json()
    assert b["solutions"] == 2 and b["best_cost"] == pytest.approx(c2)
    assert 'href="/leaderboard/M-toy:Liu2:toy/all">Liu2</a> <b>(2)</b>' in client.get("/tasks/toy/all").text


def test_leaderboard_errors(client):
    r = client.get("/api/leaderboard/M-toy:cyc")
    assert r.status_code == 400 and "three parts" in r.json()["detail"]
    r = client.get("/api/leaderboard/M-toy:noSuchCost:toy/all")
    assert r.status_code == 400 and "unknown cost 'noSuchCost'" in r.json()["detail"]
    r = client.get("/api/leaderboard/M-toy:cyc:toy/none")
    assert r.status_code == 404 and "unknown task 'toy/none'" in r.json()["detail"]
    assert client.get("/api/leaderboard/M-nope:cyc:toy/all").status_code == 404


# ------------------------------------------------------------------------------------------------------------
# bad input: 400 naming the problem, 413 beyond the size limit
# ------------------------------------------------------------------------------------------------------------
def test_malformed_json_is_400_naming_the_problem(client):
    r = client.post("/api/solutions", files={"file": ("mine.json", b'{"taskID": "toy/all",, }')},
                    data={"author": "A"})
    assert r.status_code == 400
    assert r.json()["detail"].startswith("mine.json: malformed JSON at line 1, column 22")
    r = client.post("/api/solutions", content=b"\xff\xfe\x00garbage", headers={"content-type": "application/json"})
    assert r.status_code == 400 and "UTF-8" in r.json()["detail"]
    r = client.post("/api/solutions", content=b"[1, NaN]", headers={"content-type": "application/json"})
    assert r.status_code == 400 and "NaN" in r.json()["detail"]


def test_schema_violation_is_400_naming_the_field(client):
    bad = sol_json()
    bad["taskID"] = 5
    r = upload(client, bad)
    assert r.status_code == 400
    assert r.json()["detail"] == "solution.json: taskID: expected a string, got 5"
    bad = sol_json()
    del bad["trajectory"]
    r = upload(client, bad)
    assert r.status_code == 400 and "'trajectory' is required but missing" in r.json()["detail"]
    bad = sol_json()
    bad["trajectory"]["q"][3] = [0.1, "x"]
    r = upload(client, bad)
    assert r.status_code == 400 and "trajectory.q[3][1]" in r.json()["detail"]
    bad = sol_json()
    bad["surprise"] = 1
    r = upload(client, bad)
    assert r.status_code == 400 and "unknown key" in r.json()["detail"] and "surprise" in r.json()["detail"]


def test_unknown_task_module_set_or_missing_author_is_400(client):
    s = sol_json()
    s["taskID"] = "toy/none"
    r = upload(client, s)
    assert r.status_code == 400 and "taskID: unknown task 'toy/none'" in r.json()["detail"]
    s = sol_json()
    s["moduleSet"] = "nope"
    r = upload(client, s)
    assert r.status_code == 400 and "moduleSet: unknown module set 'nope'" in r.json()["detail"]
    s = sol_json()
    s["costFunction"] = "speed"
    r = upload(client, s)
    assert r.status_code == 400 and "unknown cost 'speed'" in r.json()["detail"]
    r = client.post("/api/solutions", files={"file": ("s.json", json.dumps(sol_json()))})
    assert r.status_code == 400 and "author name is required" in r.json()["detail"]
    r = client.post("/api/solutions", data={"author": "A"})
    assert r.status_code == 400 and "form field 'file'" in r.json()["detail"]


def test_oversized_request_is_413(tmp_path, seed_dir):
    app = create_app(admin_token=ADMIN, data_dir=tmp_path / "data", seed=[seed_dir], seed_builtin=False, max_request_bytes=50_000)
    with TestClient(app, headers=ADMIN_HEADERS) as c:
        big = json.dumps(sol_json())  # ~40 kB: fits
        assert len(big) < 50_000
        assert upload(c, sol_json(), author="A").status_code == 201
        padded = sol_json()
        padded["notes"] = "x" * 60_000
        r = upload(c, padded)
        assert r.status_code == 413 and "too large" in r.json()["detail"]
        # without a Content-Length (chunked): counted while streaming
        r = c.post("/api/solutions", content=(b"x" * 10_000 for _ in range(8)),
                   headers={"content-type": "application/json"})
        assert r.status_code == 413
        # the HTML form gets an HTML error page
        r = c.post("/upload", files={"file": ("s.json", json.dumps(padded))}, data={"author": "A"})
        assert r.status_code == 413 and "text/html" in r.headers["content-type"]
        assert c.get("/healthz").json() == {"ok": True}
        assert len(c.get(f"/api/leaderboard/{BOARD}").json()["entries"]) == 1


# ------------------------------------------------------------------------------------------------------------
# tasks and module sets: uploads and the file-system safety rules
# ------------------------------------------------------------------------------------------------------------
def test_task_upload_with_mesh_path_traversal_writes_nothing(client, tmp_path):
    before = listing(tmp_path)
    data = tmp_path / "data"
    stored_before = listing(data / "tasks") + listing(data / "modulesets")
    for ref, expect in (("../../../etc/passwd", "escapes its folder"),
                        ("/etc/passwd", "absolute file paths are not allowed"),
                        ("package://../../../etc/passwd", "escapes its folder")):
        t = mesh_task(tid="evil/one", ref=ref)
        r = client.post("/api/tasks", files={"task": ("one.json", json.dumps(t))})
        assert r.status_code == 400, r.text
        msg = r.json()["detail"]
        assert msg.startswith("one.json: obstacles[0].collision.parameters.file: ") and expect in msg, msg
        assert "root:" not in msg  # nothing of /etc/passwd is echoed
        # also as a JSON body
        r = client.post("/api/tasks", json=t)
        assert r.status_code == 400 and expect in r.json()["detail"]
    # an asset *file name* that climbs out is rejected too
    r = client.post("/api/tasks", files=[("task", ("m.json", json.dumps(mesh_task()))),
                                         ("files", ("../../../etc/passwd", b"solid x\nendsolid x\n"))])
    assert r.status_code == 400 and "contains '..'" in r.json()["detail"]
    assert listing(tmp_path) == before
    assert listing(data / "tasks") + listing(data / "modulesets") == stored_before
    assert listing(client.app.state.bench.tmp) == []  # this server's staging folder is empty again
    assert client.get("/api/tasks").json()[0]["id"] == "toy/all" and len(client.get("/api/tasks").json()) == 1


def test_task_upload_multipart_and_zip(client, tmp_path):
    stl = stl_box()
    r = client.post("/api/tasks", files=[("task", ("mesh.json", json.dumps(mesh_task("toy/mesh")))),
                                         ("files", ("assets/box.stl", stl))])
    assert r.status_code == 201, r.text
    (created,) = r.json()["tasks"]
    assert created["id"] == "toy/mesh" and created["assets"] == ["assets/box.stl"]
    stored = list((tmp_path / "data" / "tasks").rglob("box.stl"))
    assert len(stored) == 1 and stored[0].read_bytes() == stl
    assert all(tmp_path / "data" in p.parents for p in (tmp_path / "data" / "tasks").rglob("*"))
    # the same ID again: 409
    r = client.post("/api/tasks", files=[("task", ("mesh.json", json.dumps(mesh_task("toy/mesh")))),
                                         ("files", ("assets/box.stl", stl))])
    assert r.status_code == 409
    # a zip package: the task at its ID path, meshes relative to the package root; junk entries ignored
    z = zip_bytes([("zipped/one.json", json.dumps(mesh_task("zipped/one"))), ("assets/box.stl", stl),
                   (".DS_Store", b"junk"), ("__MACOSX/._box.stl", b"junk")])
    r = client.post("/api/tasks", files={"file": ("pkg.zip", z, "application/zip")})
    assert r.status_code == 201, r.text
    assert r.json()["tasks"][0]["id"] == "zipped/one"
    # raw zip body
    z2 = zip_bytes([("two.json", json.dumps(mesh_task("zipped/two"))), ("assets/box.stl", stl)])
    r = client.post("/api/tasks", content=z2, headers={"content-type": "application/zip"})
    assert r.status_code == 201, r.text
    ids = [t["id"] for t in client.get("/api/tasks").json()]
    assert ids == ["toy/all", "toy/mesh", "zipped/one", "zipped/two"]
    page = client.get("/tasks/zipped/one")
    assert page.status_code == 200 and "assets/box.stl" in page.text and "M-toy:cyc:zipped/one" in page.text
    # a missing collision mesh: the loader's error
    r = client.post("/api/tasks", files={"task": ("m.json", json.dumps(mesh_task("toy/nomesh")))})
    assert r.status_code == 400 and "mesh file not found: 'assets/box.stl'" in r.json()["detail"]
    assert str(tmp_path) not in r.json()["detail"]  # the server's paths are not shown
    # a schema violation names the field
    bad = mesh_task("toy/bad")
    bad["header"]["timeStepSize"] = "fast"
    r = client.post("/api/tasks", json=bad)
    assert r.status_code == 400 and "header.timeStepSize: expected a number" in r.json()["detail"]
    bad = mesh_task("../escape")
    r = client.post("/api/tasks", json=bad)
    assert r.status_code == 400 and "invalid task ID" in r.json()["detail"]


def test_zip_slip_symlink_and_bomb_rejected(tmp_path, seed_dir):
    app = create_app(admin_token=ADMIN, data_dir=tmp_path / "data", seed=[seed_dir], seed_builtin=False,
                     max_unzipped_bytes=2_000_000)
    stl = stl_box()
    with TestClient(app, headers=ADMIN_HEADERS) as c:
        before = listing(tmp_path)
        # zip slip: an entry that climbs out of the extraction folder
        z = zip_bytes([("t.json", json.dumps(mesh_task("slip/one"))), ("assets/box.stl", stl),
                       ("../../../evil.stl", stl)])
        r = c.post("/api/tasks", files={"file": ("slip.zip", z)})
        assert r.status_code == 400 and "'../../../evil.stl' contains '..'" in r.json()["detail"]
        z = zip_bytes([("t.json", json.dumps(mesh_task("slip/two"))), ("/tmp/evil.stl", stl)])
        r = c.post("/api/tasks", files={"file": ("abs.zip", z)})
        assert r.status_code == 400 and "absolute path" in r.json()["detail"]
        # a symbolic link entry
        link = zipfile.ZipInfo("assets/box.stl")
        link.external_attr = (0o120777 << 16)
        z = zip_bytes([("t.json", json.dumps(mesh_task("slip/three"))), (link, "/etc/passwd")])
        r = c.post("/api/tasks", files={"file": ("link.zip", z)})
        assert r.status_code == 400 and "symbolic link" in r.json()["detail"]
        # a zip bomb: 50 MB of zeros in a few kB
        z = zip_bytes([("t.json", json.dumps(mesh_task("slip/four"))), ("assets/box.stl", b"\0" * 50_000_000)])
        assert len(z) < 200_000
        r = c.post("/api/tasks", files={"file": ("bomb.zip", z)})
        assert r.status_code == 413 and "inflates" in r.json()["detail"]
        # not a zip at all
        r = c.post("/api/tasks", files={"file": ("x.zip", b"PK\x03\x04 broken")})
        assert r.status_code == 400 and "zip" in r.json()["detail"]
        assert listing(tmp_path) == before
        assert not (tmp_path / "evil.stl").exists() and not Path("/tmp/evil.stl").exists()
        assert [t["id"] for t in c.get("/api/tasks").json()] == ["toy/all"]


def test_seed_symlink_leaving_the_folder_is_refused(tmp_path):
    seed = tmp_path / "seed"
    (seed / "tasks" / "toy").mkdir(parents=True)
    (seed / "tasks" / "toy" / "link.json").write_text(json.dumps(mesh_task("toy/link", "assets/box.stl")))
    (tmp_path / "outside.stl").write_bytes(stl_box())
    (seed / "tasks" / "assets").mkdir()
    os.symlink(tmp_path / "outside.stl", seed / "tasks" / "assets" / "box.stl")
    app = create_app(admin_token=ADMIN, data_dir=tmp_path / "data", seed=[seed], seed_builtin=False)
    bench = app.state.bench
    assert not [t.task_id for t in bench.tasks()]
    assert any("skipped" in line and "'assets/box.stl' escapes its folder" in line for line in bench.seed_log), \
        bench.seed_log
    bench.close()


def test_module_set_upload(client, tmp_path):
    from robodesign.formats.module_io import module_set_to_json
    toy = json.loads((toy_module_set(tmp_path / "src") / "modules.json").read_text())
    r = client.post("/api/modulesets", json={"name": "toy2", "modules": toy["modules"],
                                             "ignore_collisions": "rigid_via_joint"})
    assert r.status_code == 201, r.text
    assert r.json()["name"] == "toy2" and r.json()["modules"] == 3
    r = client.post("/api/modulesets", files={"modules": ("modules.json", json.dumps(toy))}, data={"name": "toy2"})
    assert r.status_code == 409
    r = client.post("/api/modulesets", files={"modules": ("modules.json", json.dumps(toy))}, data={"name": "../x"})
    assert r.status_code == 400 and "invalid module set name" in r.json()["detail"]
    # zip with a mesh; the name comes from the folder holding modules.json
    mesh = dict(toy)
    mesh["modules"] = json.loads(json.dumps(toy["modules"]))
    mesh["modules"][2]["bodies"][0]["visual"] = [{"type": "mesh", "parameters": {"file": "meshes/e.stl"}}]
    z = zip_bytes([("withmesh/modules.json", json.dumps(mesh)), ("withmesh/meshes/e.stl", stl_box())])
    r = client.post("/api/modulesets", files={"file": ("set.zip", z)})
    assert r.status_code == 201, r.text
    assert r.json()["name"] == "withmesh" and r.json()["assets"] == ["meshes/e.stl"]
    bad = json.loads(json.dumps(toy))
    bad["modules"][1]["joints"][0]["limits"]["positionLower"] = "low"
    r = client.post("/api/modulesets", files={"modules": ("modules.json", json.dumps(bad))}, data={"name": "bad"})
    assert r.status_code == 400
    assert "bad/modules.json: modules[1].joints[0].limits.positionLower" in r.json()["detail"]
    names = [m["name"] for m in client.get("/api/modulesets").json()]
    assert names == ["toy", "toy2", "withmesh"]
    # a solution for the new set is its own benchmark
    r = upload(client, sol_json(1.0) | {"moduleSet": "toy2"})
    assert r.status_code == 201 and r.json()["benchmark_id"] == "M-toy2:cyc:toy/all"
    assert module_set_to_json  # the writer exists for people who build sets in Python


# ------------------------------------------------------------------------------------------------------------
# queries, pages, concurrency
# ------------------------------------------------------------------------------------------------------------
def test_query_by_cost_range(client, judge):
    ids = {}
    for k in (1.0, 1.2, 1.5, 2.0):
        r = upload(client, sol_json(k), author=f"k{k}")
        assert r.status_code == 201
        ids[k] = r.json()["id"]
    costs = {k: judge(toy_solution(k)).cost for k in ids}
    assert costs[1.2] == pytest.approx(4.2) and costs[1.5] == pytest.approx(5.25)
    r = client.get("/api/solutions", params={"task": "toy/all", "cost": "cyc", "moduleset": "M-toy",
                                             "min_cost": 4, "max_cost": 6})
    assert r.status_code == 200
    assert [s["id"] for s in r.json()] == [ids[1.2], ids[1.5]]
    assert [s["cost"] for s in r.json()] == pytest.approx([costs[1.2], costs[1.5]])
    assert [s["id"] for s in client.get("/api/solutions", params={"max_cost": 3.5}).json()] == [ids[1.0]]
    assert [s["id"] for s in client.get("/api/solutions", params={"min_cost": 7}).json()] == [ids[2.0]]
    assert len(client.get("/api/solutions").json()) == 4
    assert client.get("/api/solutions", params={"cost": "Liu2"}).json() == []
    assert client.get("/api/solutions", params={"moduleset": "other"}).json() == []
    assert client.get("/api/solutions", params={"task": "toy/all", "cost": "cyc_1.0"}).json()[0]["id"] == ids[1.0]
    r = client.get("/api/solutions", params={"min_cost": "cheap"})
    assert r.status_code == 400 and "min_cost" in r.json()["detail"]
    r = client.get("/api/solutions", params={"cost": "cyc_x"})
    assert r.status_code == 400 and "not a number" in r.json()["detail"]
    b = client.get("/api/benchmarks").json()
    assert b == [{"benchmark_id": BOARD, "task": "toy/all", "module_set": "toy", "module_sets": ["toy"], "solutions": 4,
                  "best_cost": pytest.approx(3.5), "collaborative": False}]


def test_pages_and_listings(tmp_path, seed_dir):
    app = create_app(admin_token=ADMIN, data_dir=tmp_path / "data", seed=[seed_dir])  # with the built-in assets/
    with TestClient(app, headers=ADMIN_HEADERS) as c:
        tasks = c.get("/api/tasks").json()
        ids = [t["id"] for t in tasks]
        builtin = sorted(f"{f.parent.name}/{f.stem}" for f in (ROOT / "assets" / "tasks").glob("robodesign*/*.json"))
        assert sorted(ids) == sorted(["toy/all"] + builtin) and len(builtin) >= 5
        assert next(t for t in tasks if t["id"] == "toy/all")["goals"] == 6
        sets = [m["name"] for m in c.get("/api/modulesets").json()]
        assert "robodesign_arm" in sets and "toy" in sets
        costs = {x["name"]: x for x in c.get("/api/costs").json()}
        assert {"cyc", "mechEnergy", "Liu2", "Whit2"} <= set(costs)
        assert costs["Liu2"]["descriptor"] == "cyc_0.2,mechEnergy"
        upload(c, sol_json(1.0), author="<script>alert(1)</script>")
        html = c.get("/").text
        for s in ("toy/all", "robodesign_arm", "Liu2", "cyc_0.2,mechEnergy", BOARD, "M-robodesign_arm:cyc:toy/all"):
            assert s in html, s
        assert "https://" not in html and "http://" not in html  # no external resources
        assert c.get("/").headers["content-security-policy"].startswith("default-src 'self'")
        assert c.get("/static/style.css").headers["content-type"].startswith("text/css")
        page = c.get(f"/leaderboard/{BOARD}").text
        assert "&lt;script&gt;alert(1)&lt;/script&gt;" in page and "<script>alert" not in page
        task_page = c.get("/tasks/toy/all").text
        assert "M-toy:Whit2:toy/all" in task_page and "M-robodesign_arm:Liu2:toy/all" in task_page
        assert "AllGoalsFulfilled" in task_page and "Pause" in task_page
        assert "modules.json" in c.get("/modulesets/toy").text
        assert c.get("/tasks/nope/x").status_code == 404
        form = c.get("/upload").text
        for field in ('name="file"', 'name="author"', 'name="token"', 'enctype="multipart/form-data"'):
            assert field in form
        r = c.get("/leaderboard", params={"moduleset": "toy", "cost": "cyc", "task": "toy/all"},
                  follow_redirects=False)
        assert r.status_code == 303 and r.headers["location"] == f"/leaderboard/{BOARD}"
        assert c.get("/api/openapi.json").status_code == 200


def test_html_form_upload(client):
    r = client.post("/upload", files={"file": ("s.json", json.dumps(sol_json(1.0)))},
                    data={"author": "Form User", "affiliation": "Lab"})
    assert r.status_code == 201 and "Valid" in r.text and 'id="token"' in r.text and "3.5" in r.text
    r = client.post("/upload", files={"file": ("s.json", json.dumps(sol_json(1.0, broken=True)))},
                    data={"author": "Form User"})
    assert r.status_code == 422 and "Invalid" in r.text and "joint.q" in r.text
    r = client.post("/upload", files={"file": ("s.json", b"{")}, data={"author": "Form User"})
    assert r.status_code == 400 and "malformed JSON" in r.text and "text/html" in r.headers["content-type"]
    sid = client.get("/api/solutions").json()[0]["id"]
    assert client.post(f"/solutions/{sid}/withdraw", data={"token": "wrong-token"}).status_code == 403


def test_solution_page_embeds_the_viewer(client):
    sid = upload(client, sol_json()).json()["id"]
    page = client.get(f"/solutions/{sid}")
    assert page.status_code == 200 and f"/leaderboard/{BOARD}" in page.text
    pytest.importorskip("robodesign.viewer", reason="the 3D viewer (robodesign.viewer) is not installed")
    assert f'<iframe class="viewer" title="3D viewer" src="/solutions/{sid}/viewer" sandbox="allow-scripts"' \
        in page.text
    v = client.get(f"/solutions/{sid}/viewer")
    assert v.status_code == 200 and v.text.lstrip().lower().startswith("<!doctype html")
    assert "scene-data" in v.text and "default-src 'none'" in v.headers["content-security-policy"]


def test_concurrent_uploads_on_a_real_server(tmp_path, seed_dir, judge):
    # 24 uploads at once from one address: the per-client limits are lifted here (tested on their own below)
    app = create_app(admin_token=ADMIN, data_dir=tmp_path / "data", seed=[seed_dir], seed_builtin=False,
                     queue_size=24, per_client_queue=24, upload_rate=0)
    ks = [1.0 + 0.1 * i for i in range(20)]
    with running_server(app) as url:
        def one(k):
            return http("POST", f"{url}/api/solutions", {"solution": sol_json(k), "author": f"user{k:.1f}"})

        def garbage(i):
            return http("POST", f"{url}/api/solutions", {"solution": {"taskID": i}})

        with ThreadPoolExecutor(max_workers=24) as ex:
            futs = [ex.submit(one, k) for k in ks] + [ex.submit(garbage, i) for i in range(4)]
            results = [f.result() for f in futs]
        assert [s for s, _ in results[:20]] == [201] * 20, results
        assert [s for s, _ in results[20:]] == [400] * 4
        assert len({b["token"] for _, b in results[:20]}) == 20
        status, lb = http("GET", f"{url}/api/leaderboard/{BOARD}")
        assert status == 200 and len(lb["entries"]) == 20
        assert [e["cost"] for e in lb["entries"]] == pytest.approx([3.5 * k for k in ks])
        assert lb["entries"][7]["cost"] == pytest.approx(judge(toy_solution(ks[7])).cost)
        assert http("GET", f"{url}/healthz") == (200, {"ok": True})


def test_cli_serve(tmp_path, seed_dir):
    """`robodesign serve` as a process: starts, seeds, answers, stops on SIGTERM."""
    port = free_port()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(Path(__file__).parents[1] / "src"),
                                                       os.environ.get("PYTHONPATH", "")]))
    env.pop("ROBODESIGN_ADMIN_TOKEN", None)
    p = subprocess.Popen([sys.executable, "-m", "robodesign.cli", "serve", "--data", str(tmp_path / "d"),
                          "--seed", str(seed_dir), "--port", str(port), "--host", "127.0.0.1"],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env)
    try:
        deadline = time.time() + 90  # the checker processes start first
        while True:
            try:
                status, tasks = http("GET", f"http://127.0.0.1:{port}/api/tasks", timeout=2)
                break
            except (urllib.error.URLError, ConnectionError):
                assert p.poll() is None and time.time() < deadline, p.stdout.read().decode()
                time.sleep(0.1)
        assert status == 200 and "toy/all" in [t["id"] for t in tasks]
        assert (tmp_path / "d" / "bench.db").is_file()
        # checked in a checker process (serve's default)
        status, body = http("POST", f"http://127.0.0.1:{port}/api/solutions", {"solution": sol_json(1.2),
                                                                               "author": "CLI"})
        assert status == 201 and body["cost"] == pytest.approx(4.2), body
        # registration is an admin action and no token was configured
        status, body = http("POST", f"http://127.0.0.1:{port}/api/tasks", task_json())
        assert status == 403 and "disabled on this server" in body["detail"]
    finally:
        p.terminate()
        out = p.communicate(timeout=60)[0].decode()
    assert "seeded task toy/all" in out and "registering tasks and module sets is disabled" in out


@pytest.mark.skipif(not (Path(__file__).parents[2] / "shared" / "cobra" / "tasks").is_dir(),
                    reason="the CoBRA data (shared/cobra) is not next to the checkout")
def test_seed_real_cobra_folders(tmp_path):
    cobra = Path(__file__).parents[2] / "shared" / "cobra"
    app = create_app(admin_token=ADMIN, data_dir=tmp_path / "data", seed=[cobra], seed_builtin=False)
    with TestClient(app, headers=ADMIN_HEADERS) as c:
        ids = [t["id"] for t in c.get("/api/tasks").json()]
        assert {"simple/PTP_1", "simple/PTP_2", "simple/PTP_3"} <= set(ids)
        assert {"IMPROV", "geometric_primitive_modules"} <= {m["name"] for m in c.get("/api/modulesets").json()}
        ptp2 = [t for t in c.get("/api/tasks").json() if t["id"] == "simple/PTP_2"][0]
        assert ptp2["assets"] == ["assets/DMU_125P_compress.stl"]
        stored = list((tmp_path / "data" / "tasks").rglob("DMU_125P_compress.stl"))
        assert len(stored) == 1 and stored[0].stat().st_size == (cobra / "tasks/assets/DMU_125P_compress.stl"
                                                                 ).stat().st_size
        page = c.get("/tasks/simple/PTP_2").text
        assert "M-IMPROV:cyc:simple/PTP_2" in page and "DMU_125P.stl" in page  # missing visual: a warning
        assert "M-IMPROV:Liu2:simple/PTP_1" in c.get("/tasks/simple/PTP_1").text
        assert c.get("/modulesets/IMPROV").status_code == 200


# ------------------------------------------------------------------------------------------------------------
# PostgreSQL: a throwaway cluster on 127.0.0.1
# ------------------------------------------------------------------------------------------------------------
def _pg_bindir():
    cands = []
    if shutil.which("pg_ctl"):
        cands.append(Path(os.path.realpath(shutil.which("pg_ctl"))).parent)
    cands += [Path(p) for p in sorted(glob.glob("/usr/lib/postgresql/*/bin"), reverse=True)]
    for c in cands:
        if (c / "initdb").is_file() and (c / "pg_ctl").is_file():
            return c
    return None


@contextlib.contextmanager
def postgres_cluster():
    """initdb + pg_ctl start in a fresh temp folder, listening on 127.0.0.1:<free port> only.

    PostgreSQL refuses to run as root: as root (CI, this sandbox) the cluster runs as the ``postgres`` user that
    Debian's ``postgresql`` package creates (``runuser -u postgres``); the temp folder is made under /tmp (pytest's
    tmp_path is not traversable by that user) and chowned to it. Trust authentication for the one local user
    ``bench``; the cluster is stopped (``-m immediate``) and deleted afterwards."""
    bindir = _pg_bindir()
    if bindir is None:
        pytest.skip("PostgreSQL server binaries (initdb, pg_ctl) not installed: apt-get install postgresql")
    pytest.importorskip("psycopg", reason="the PostgreSQL driver psycopg (3) is not installed")
    prefix = []
    base = Path(tempfile.mkdtemp(prefix="robodesign-pg-"))
    if os.geteuid() == 0:
        try:
            pw = pwd.getpwnam("postgres")
        except KeyError:
            shutil.rmtree(base, ignore_errors=True)
            pytest.skip("running as root and there is no 'postgres' user to run the server as")
        os.chown(base, pw.pw_uid, pw.pw_gid)
        prefix = ["runuser", "-u", "postgres", "--"]
    os.chmod(base, 0o700)
    data, log = base / "data", base / "log.txt"
    port = free_port()

    def run(*cmd, timeout=90):
        return subprocess.run(prefix + [str(x) for x in cmd], capture_output=True, text=True, timeout=timeout)

    r = run(bindir / "initdb", "-D", data, "-U", "bench", "--auth=trust", "-E", "UTF8", "--no-sync")
    if r.returncode != 0:
        shutil.rmtree(base, ignore_errors=True)
        pytest.fail(f"initdb failed: {r.stdout}\n{r.stderr}")
    r = run(bindir / "pg_ctl", "-D", data, "-l", log, "-w", "-t", "60",
            "-o", f"-k {base} -p {port} -h 127.0.0.1 -c fsync=off", "start")
    try:
        if r.returncode != 0:
            pytest.fail(f"pg_ctl start failed: {r.stdout}\n{r.stderr}\n{log.read_text() if log.exists() else ''}")
        yield f"postgresql://bench@127.0.0.1:{port}/postgres"
    finally:
        run(bindir / "pg_ctl", "-D", data, "-m", "immediate", "-w", "stop")
        shutil.rmtree(base, ignore_errors=True)


def test_postgresql_backend(tmp_path, seed_dir, judge):
    with postgres_cluster() as url:
        app = create_app(admin_token=ADMIN, db_url=url, data_dir=tmp_path / "data", seed=[seed_dir], seed_builtin=False)
        assert app.state.bench.engine.dialect.name == "postgresql"
        with TestClient(app, headers=ADMIN_HEADERS) as c:
            exercise_site(c, judge)
            assert not (tmp_path / "data" / "bench.db").exists()
            # a second server process on the same database and data folder sees the same site
            app2 = create_app(admin_token=ADMIN, db_url=url, data_dir=tmp_path / "data", seed=[seed_dir], seed_builtin=False)
            with TestClient(app2, headers=ADMIN_HEADERS) as c2:
                assert [t["id"] for t in c2.get("/api/tasks").json()] == ["toy/all"]
                assert len(c2.get(f"/api/leaderboard/{BOARD}").json()["entries"]) == 1
                r = upload(c2, sol_json(1.2), author="Second Server")
                assert r.status_code == 201
            assert [e["author"] for e in c.get(f"/api/leaderboard/{BOARD}").json()["entries"]] == \
                ["Second Server", "Grace Hopper"]
