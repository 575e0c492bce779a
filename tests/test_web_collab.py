"""Collaborative tasks on the benchmark website (docs/collaborative.md, docs/website.md): uploads judged by the one
collaborative checker (``robodesign check``'s), the ``[M-s1,M-s2]:[C1,C2]:task`` leaderboards ordered by totalCost
then the cost tuple, bad uploads, single-robot and collaborative boards kept apart, and an older database migrated;
every test on SQLite and on a fresh database of a throwaway PostgreSQL cluster.

The solutions are real: the built-in cell ``robodesign-collab/shared_conveyor`` solved by prioritized planning
(``solve_collab``, a few seconds each, once per module) for the default arm design A on both sides, and for A next
to design B (link_L_100 swapped for link_L_200) in both placements. With the cost ``mass`` (a design's mass: the sum
of its modules' body masses, computed here from modules.json) their cost tuples are (mA, mA), (mA, mB) and
(mB, mA): the last two tie on totalCost and differ in the tuple.
"""
from __future__ import annotations

import contextlib
import copy
import io
import json
import re
from pathlib import Path

import pytest

pytest.importorskip("fastapi", reason="the website needs fastapi")
from fastapi.testclient import TestClient  # noqa: E402
from sqlalchemy import inspect, text  # noqa: E402

from robodesign import load_module_set  # noqa: E402
from robodesign.collab.core import RobotSetup, load_collab_task, solve_collab  # noqa: E402
from robodesign.web import create_app  # noqa: E402
from robodesign.web.db import make_engine  # noqa: E402
from robodesign.web.pages import bid_url  # noqa: E402

from test_web import ADMIN, ADMIN_HEADERS, upload  # noqa: E402
from test_web_attacks import db_url, pg_server  # noqa: E402,F401  (SQLite, or a fresh PostgreSQL database)

ROOT = Path(__file__).resolve().parents[1]
import make_tasks as mt  # noqa: E402  (assets/tasks, on the path by conftest)

TID = "robodesign-collab/shared_conveyor"
TASK_FILE = mt.collab_task_path("shared_conveyor")
ARM = "M-robodesign_arm"
CYC = f"[{ARM},{ARM}]:cyc:{TID}"
MASS = f"[{ARM},{ARM}]:mass:{TID}"
ALONE = "robodesign-collab/left_alone"  # a single-robot task: the shared cell with the left arm's goals only
A = tuple(mt.DEFAULT_ORDER)
B = tuple("5" if m == "4" else m for m in A)  # link_L_100 → link_L_200
NEW_COLUMNS = {"tasks": ["robots"], "solutions": ["collaborative", "robots_key", "cost_tuple"]}


# ------------------------------------------------------------------------------------------------------------
# solutions and sites
# ------------------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def solved():
    """``{"AA" | "AB" | "BA": collaborative solution JSON}`` (robot left's design first), cost cyc."""
    ms = load_module_set("robodesign_arm")
    ctask = load_collab_task(TASK_FILE)
    out = {}
    for name, orders in (("AA", (A, A)), ("AB", (A, B)), ("BA", (B, A))):
        res = solve_collab(ctask, [RobotSetup(rid, ms, o) for rid, o in zip(ctask.robot_ids, orders)])
        assert res.feasible, res.message
        out[name] = res.solution.to_json()
    return out


@pytest.fixture
def make_site(tmp_path, db_url):
    """``make_site()`` → a TestClient of a site with the built-in tasks and module sets (the admin header set);
    ``close(c)`` stops one early; the rest are closed at the end of the test."""
    clients = []

    def make(**kw):
        kw = {"admin_token": ADMIN, "upload_rate": 0, "read_rate": 0, **kw}
        app = create_app(db_url=db_url, data_dir=tmp_path / "data", **kw)
        c = TestClient(app, headers=ADMIN_HEADERS, raise_server_exceptions=False)
        c.__enter__()
        clients.append(c)
        return c

    def close(c):
        clients.remove(c)
        c.__exit__(None, None, None)

    make.close = close
    yield make
    for c in clients:
        c.__exit__(None, None, None)


@pytest.fixture
def site(make_site):
    return make_site()


def post(c, sol: dict, author="Ada Lovelace", **kw):
    return upload(c, sol, author=author, **kw)


def with_cost(sol: dict, cost: str) -> dict:
    out = copy.deepcopy(sol)
    for r in out["robots"]:
        r["costFunction"] = cost
    return out


def robot(sol: dict, rid: str) -> dict:
    return next(r for r in sol["robots"] if r["ID"] == rid)


def cli_check(sol: dict, tmp_path: Path, name="sol.json"):
    """``robodesign check <shared_conveyor> <sol> --json`` in this process → (exit code, JSON verdict)."""
    from robodesign.cli.entry import main
    f = tmp_path / name
    f.write_text(json.dumps(sol))
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(["check", str(TASK_FILE), str(f), "--json"])
    return code, json.loads(out.getvalue())


def design_mass(order) -> float:
    """Independent of the checker: the sum of the body masses of the modules in ``order`` (modules.json)."""
    modules = json.loads((ROOT / "assets" / "modules" / "robodesign_arm" / "modules.json").read_text())["modules"]
    mass = {m["header"]["ID"]: sum(b["mass"] for b in m["bodies"]) for m in modules}
    return sum(mass[m] for m in order)


def entries(c, bid):
    r = c.get(f"/api/leaderboard/{bid}")
    assert r.status_code == 200, r.text
    return r.json()["entries"]


# ------------------------------------------------------------------------------------------------------------
# registering a collaborative task (admin)
# ------------------------------------------------------------------------------------------------------------
def test_collaborative_task_registration(site):
    d = json.loads(Path(TASK_FILE).read_text())
    d["header"]["ID"] = "lab/conveyor2"
    r = site.post("/api/tasks", json=d)
    assert r.status_code == 201, r.text
    (t,) = r.json()["tasks"]
    assert t["collaborative"] is True and t["id"] == "lab/conveyor2"
    assert t["robots"] == [{"ID": "left", "name": "arm at y = +0.45 m"}, {"ID": "right", "name": "arm at y = -0.45 m"}]
    assert t["goals"] == {"left_pick": "left", "left_place": "left", "right_pick": "right", "right_place": "right",
                          "inspect": "any", "left_home": "left", "right_home": "right"}
    assert site.get("/api/tasks/lab/conveyor2").json() == d  # stored as uploaded, robots and all
    page = site.get("/tasks/lab/conveyor2").text
    assert "<th>Robot</th>" in page and "any robot" in page and "arm at y = +0.45 m" in page
    assert TestClient(site.app).post("/api/tasks", json=d).status_code == 403  # no admin token

    def refused(status, change, *parts):
        bad = copy.deepcopy(d)
        bad["header"]["ID"] = "lab/bad"
        change(bad)
        r = site.post("/api/tasks", json=bad)
        assert r.status_code == status, r.text
        for p in parts:
            assert p in r.json()["detail"], (p, r.json()["detail"])

    refused(400, lambda x: x["goals"][0].update(robot="middle"), "goals[0].robot: unknown robot 'middle'")
    refused(400, lambda x: x["robots"][1].update(ID="left"), "robots[1].ID: duplicate robot ID 'left'")
    refused(400, lambda x: x["robots"][0].update(ID="r" * 101), "robots[0].ID: at most 100 characters")
    refused(400, lambda x: x["robots"][0].update(ID=int("9" * 101)), "robots[0].ID: at most 100 characters")
    refused(400, lambda x: x["robots"][0].update(ID="a\u0000b"), "NUL character")
    refused(400, lambda x: x.update(robots=[]), "robots: needs at least one robot")
    refused(413, lambda x: x.update(robots=[{"ID": f"r{k}"} for k in range(17)]),
            "robots: at most 16 robots are allowed (got 17)")
    refused(400, lambda x: x["robots"][0].update(basePlacement=[1, 2]), "robots[0].basePlacement")
    refused(400, lambda x: x["goals"][4].update(robot=["left"]), "goals[4].robot: unknown robot ['left']")
    assert "lab/bad" not in [t["id"] for t in site.get("/api/tasks").json()]


# ------------------------------------------------------------------------------------------------------------
# a valid solution: the site's verdict is robodesign check's
# ------------------------------------------------------------------------------------------------------------
def test_valid_collaborative_upload_has_the_cli_cost_tuple(site, solved, tmp_path):
    sol = solved["AA"]
    code, cli = cli_check(sol, tmp_path)
    assert code == 0 and cli["valid"] is True and cli["benchmarkID"] == CYC
    end = sol["robots"][0]["trajectory"]["t"][-1]  # cyc of every robot: the common time base's last stamp
    assert cli["costs"] == [pytest.approx(end), pytest.approx(end)] and cli["totalCost"] == pytest.approx(2 * end)

    r = post(site, sol, affiliation="Analytical Engines")
    assert r.status_code == 201, r.text
    body = r.json()
    assert body["valid"] is True and body["collaborative"] is True and body["benchmark_id"] == CYC
    assert body["costs"] == pytest.approx(cli["costs"], abs=1e-12)
    assert body["totalCost"] == body["cost"] == pytest.approx(cli["totalCost"], abs=1e-12)
    sid = body["id"]

    d = site.get(f"/api/solutions/{sid}").json()
    assert d["collaborative"] is True and d["module_sets"] == ["robodesign_arm", "robodesign_arm"]
    assert d["costs"] == pytest.approx(cli["costs"], abs=1e-12) and d["viewer"] == f"/solutions/{sid}/viewer"
    v = d["verdict"]
    assert v["valid"] is True and v["goals"] == cli["goals"] and v["violations"] == []
    for rid in ("left", "right"):
        assert v["robots"][rid]["costs"] == pytest.approx(cli["robots"][rid]["costs"], abs=1e-12)
    assert site.get(f"/api/solutions/{sid}/json").json() == sol

    (e,) = entries(site, CYC)
    assert e["id"] == sid and e["rank"] == 1 and e["costs"] == pytest.approx(cli["costs"])
    lb = site.get(f"/api/leaderboard/{CYC}").json()
    assert lb["collaborative"] is True and lb["module_sets"] == ["robodesign_arm"] * 2
    assert lb["cost_keys"] == ["cyc", "cyc"] and lb["task"] == TID
    # the same benchmark written with one cost per robot
    assert [x["id"] for x in entries(site, f"[{ARM},{ARM}]:[cyc,cyc]:{TID}")] == [sid]
    (b,) = site.get("/api/benchmarks").json()
    assert b["collaborative"] is True and b["benchmark_id"] == CYC and b["solutions"] == 1
    assert b["module_sets"] == ["robodesign_arm"] * 2 and b["best_cost"] == pytest.approx(cli["totalCost"])

    # pages: the per-robot verdict, the tuple, the viewer with both robots
    page = site.get(f"/solutions/{sid}").text
    tup = f"({end:.6g}, {end:.6g})"
    assert 'id="cost-tuple"' in page and "left" in page and "right" in page
    assert f'<b class="mono" id="cost-tuple">{tup}</b>' in page, page[page.find("cost tuple"):][:200]
    viewer = site.get(f"/solutions/{sid}/viewer")
    assert viewer.status_code == 200 and "default-src 'none'" in viewer.headers["content-security-policy"]
    from robodesign.viewer.html import decode_page_data
    anim = decode_page_data(viewer.text)["animation"]  # both robots animate on the common time base
    assert {"robot/TCP", "right/robot/TCP"} <= set(anim["nodes"]) and anim["t"][-1] == pytest.approx(end)
    task_page = site.get(f"/tasks/{TID}").text
    assert "collaborative: 2 robots" in task_page and f'href="{bid_url(CYC)}"' in task_page
    board_page = site.get(f"/leaderboard/{CYC}").text
    assert "Cost tuple" in board_page and "Ada Lovelace" in board_page
    tasks = {t["id"]: t for t in site.get("/api/tasks").json()}
    assert tasks[TID]["collaborative"] is True and [r["ID"] for r in tasks[TID]["robots"]] == ["left", "right"]
    assert tasks["robodesign/pick_and_place"]["collaborative"] is False


def test_upload_form_shows_every_robot(site, solved):
    r = site.post("/upload", files={"file": ("cell.json", json.dumps(solved["AA"]))}, data={"author": "Form"})
    assert r.status_code == 201 and "Valid" in r.text and 'id="token"' in r.text
    assert 'id="cost-tuple"' in r.text and "watch the robots move together" in r.text
    r = site.post("/upload", files={"file": ("cell.json", json.dumps(no_wait(solved["AA"], "right", 100)))},
                  data={"author": "Form"})
    assert r.status_code == 422 and "Invalid" in r.text and "<th>Robot</th>" in r.text
    assert "robotCollisionFree" in r.text and "robot–robot collision" in r.text


# ------------------------------------------------------------------------------------------------------------
# tampered solutions: rejected (422, not stored) with the violation named, as robodesign check does
# ------------------------------------------------------------------------------------------------------------
def no_wait(sol: dict, rid: str, k0: int) -> dict:
    """Robot ``rid`` starts its motion ``k0`` samples earlier (the prioritized solve made it wait): its samples
    shifted by k0, the last configuration held at rest; the goal times moved with them."""
    out = copy.deepcopy(sol)
    tr = robot(out, rid)["trajectory"]
    n, dt = len(tr["t"]), tr["t"][1] - tr["t"][0]
    for key in ("q", "dq", "ddq"):
        rows = tr[key][k0:] + [tr[key][-1]] * k0
        if key != "q":
            rows = rows[:n - k0] + [[0.0] * len(rows[0])] * k0
        tr[key] = rows
    tr["ddq"][n - k0 - 1] = [0.0] * len(tr["ddq"][0])
    tr["goal2time"] = {g: round(t - k0 * dt, 9) for g, t in tr["goal2time"].items()}
    return out


def test_tampered_collaborative_uploads_are_rejected(site, solved, tmp_path):
    sol = solved["AA"]
    # the right arm no longer waits for the left one: their paths cross over the belt
    right = robot(sol, "right")["trajectory"]
    assert max(abs(x) for x in right["dq"][99]) == 0.0  # it was still waiting at sample 99
    tampered = no_wait(sol, "right", 100)
    code, cli = cli_check(tampered, tmp_path)
    assert code == 1 and cli["violations"]
    r = post(site, tampered)
    assert r.status_code == 422, r.text
    v = r.json()
    assert v["valid"] is False and v["id"] is None and "token" not in v and v["collaborative"] is True
    assert v["violations"] == cli["violations"]  # one judge
    assert {x["constraint"] for x in v["violations"]} == {"robotCollisionFree"}
    first = min(v["violations"], key=lambda x: x["time"])
    assert first["robot"] is None and "left:" in first["message"] and "right:" in first["message"]
    # the instant lies between the two samples the message names (the task's time step apart)
    k = [int(x) for x in re.search(r"between samples (\d+) and (\d+)", first["message"]).groups()]
    dt = right["t"][1] - right["t"][0]
    assert k[1] == k[0] + 1 and k[0] * dt <= first["time"] <= k[1] * dt + 1e-9
    assert "robotCollisionFree" in v["detail"] and "robot–robot collision" in v["detail"]
    assert entries(site, CYC) == []

    # time-stretched: every robot's times doubled, q / dq / ddq kept (q is no longer the integral of dq)
    stretched = copy.deepcopy(sol)
    for rb in stretched["robots"]:
        tr = rb["trajectory"]
        tr["t"] = [2 * t for t in tr["t"]]
        tr["goal2time"] = {g: 2 * t for g, t in tr["goal2time"].items()}
    r = post(site, stretched)
    assert r.status_code == 422, r.text
    v = r.json()
    # the judge's motion model: each robot's steps are now twice the task's time step (trajectory.t)
    bad = [x for x in v["violations"] if x["constraint"] == "trajectory.t"]
    assert {x["robot"] for x in bad} == {"left", "right"} and "longer than the task's time step" in bad[0]["message"]
    assert v["violations"] == cli_check(stretched, tmp_path, "stretched.json")[1]["violations"]

    # teleporting: the left arm's first joint jumps by 0.3 rad at sample 50 and back
    jump = copy.deepcopy(sol)
    robot(jump, "left")["trajectory"]["q"][50][0] += 0.3
    r = post(site, jump)
    assert r.status_code == 422, r.text
    v = r.json()
    dq = [(x["robot"], x["sample"]) for x in v["violations"] if x["constraint"] == "joint.dq"]
    assert dq == [("left", 49), ("left", 50)]
    motion = {(x["robot"], x["sample"]) for x in v["violations"] if x["constraint"] == "trajectory.motion"}
    assert motion and motion <= {("left", 49), ("left", 50)}, v["violations"]   # the judge's motion model
    assert entries(site, CYC) == []

    # one robot off the common time base: bad input (400), not a verdict
    skew = copy.deepcopy(sol)
    robot(skew, "right")["trajectory"]["t"] = [2 * t for t in right["t"]]
    r = post(site, skew)
    assert r.status_code == 400 and "robots[1].trajectory.t" in r.json()["detail"]
    assert "common time base" in r.json()["detail"]


# ------------------------------------------------------------------------------------------------------------
# the leaderboard: totalCost, ties broken by the cost tuple
# ------------------------------------------------------------------------------------------------------------
def test_leaderboard_orders_by_total_cost_then_the_tuple(site, solved):
    m_a, m_b = design_mass(A), design_mass(B)
    assert m_b - m_a == pytest.approx(0.986297 - 0.660576)  # link_L_200 vs link_L_100
    ids = {}
    for name, who in (("BA", "Barbara"), ("AB", "Alan"), ("AA", "Ada")):  # the tie's loser is uploaded first
        r = post(site, with_cost(solved[name], "mass"), author=who)
        assert r.status_code == 201, r.text
        ids[name] = r.json()["id"]
        assert r.json()["benchmark_id"] == MASS
        expect = {"AA": [m_a, m_a], "AB": [m_a, m_b], "BA": [m_b, m_a]}[name]
        assert r.json()["costs"] == pytest.approx(expect, abs=1e-9)
        assert r.json()["totalCost"] == pytest.approx(sum(expect), abs=1e-9)
    r = post(site, solved["AA"], author="Cyc")  # another benchmark: cyc
    assert r.status_code == 201

    lb = entries(site, MASS)
    assert [(e["id"], e["rank"]) for e in lb] == [(ids["AA"], 1), (ids["AB"], 2), (ids["BA"], 3)]
    assert lb[1]["cost"] == lb[2]["cost"] and lb[0]["cost"] < lb[1]["cost"]  # the tie is exact
    assert [e["costs"] for e in lb] == [pytest.approx([m_a, m_a]), pytest.approx([m_a, m_b]),
                                        pytest.approx([m_b, m_a])]
    assert [e["author"] for e in entries(site, f"[{ARM},{ARM}]:[mass,mass]:{TID}")] == ["Ada", "Alan", "Barbara"]
    assert [e["author"] for e in entries(site, CYC)] == ["Cyc"]
    page = site.get(f"/leaderboard/{MASS}").text
    assert page.index("Ada") < page.index("Alan") < page.index("Barbara") and "Cyc" not in page
    assert "ties broken by the cost tuple" in page


# ------------------------------------------------------------------------------------------------------------
# bad uploads: 4xx naming the field, nothing stored
# ------------------------------------------------------------------------------------------------------------
def test_bad_collaborative_uploads_are_4xx_naming_the_field(site, solved):
    sol = solved["AA"]

    def expect(status, bad, *parts, raw=None):
        r = (site.post("/api/solutions", content=raw, params={"author": "A"},
                       headers={"content-type": "application/json"}) if raw is not None else post(site, bad))
        assert r.status_code == status, r.text
        for p in parts:
            assert p in r.json()["detail"], (p, r.json()["detail"])

    one = copy.deepcopy(sol)
    one["robots"] = one["robots"][:1]
    expect(400, one, "robots: the task has 2 robots (left, right), the solution gives 1")
    three = copy.deepcopy(sol)
    three["robots"].append({**copy.deepcopy(three["robots"][1]), "ID": "third"})
    expect(400, three, "robots: the task has 2 robots (left, right), the solution gives 3")
    unknown = copy.deepcopy(sol)
    robot(unknown, "right")["ID"] = "middle"
    expect(400, unknown, "robots[1].ID: the task has no robot 'middle' (robots: left, right)")
    dup = copy.deepcopy(sol)
    dup["robots"][1]["ID"] = "left"
    expect(400, dup, "robots[1].ID: duplicate robot ID 'left'")
    text = json.dumps(sol)
    q0 = json.dumps(sol["robots"][0]["trajectory"]["q"][0][0])
    nan = text.replace(f'"q": [[{q0}', '"q": [[NaN', 1)
    assert nan != text
    expect(400, None, "NaN", "robots[0].trajectory.q[0][0]", raw=nan.encode())
    ms = copy.deepcopy(sol)
    ms["robots"][1]["moduleSet"] = "nope"
    expect(400, ms, "robots[1].moduleSet: unknown module set 'nope'")
    cost = copy.deepcopy(sol)
    cost["robots"][0]["costFunction"] = "speed"
    expect(400, cost, "robots[0].costFunction", "unknown cost 'speed'")
    schema = copy.deepcopy(sol)
    schema["robots"][0]["trajectory"]["q"][3] = [0.1, "x"]
    expect(400, schema, "robots[0].trajectory.q[3]")
    extra = {**copy.deepcopy(sol), "surprise": 1}
    expect(400, extra, "surprise: unknown key(s): 'surprise'")
    flag = {**copy.deepcopy(sol), "collaborative": False}
    expect(400, flag, "collaborative: expected true")
    nul = copy.deepcopy(sol)
    nul["robots"][0]["ID"] = "le\u0000ft"
    expect(400, nul, "NUL character")
    other = copy.deepcopy(sol)
    other["taskID"] = "robodesign/pick_and_place"
    expect(400, other, "taskID: task 'robodesign/pick_and_place' is a single-robot task")
    unknown_task = copy.deepcopy(sol)
    unknown_task["taskID"] = "robodesign-collab/none"
    expect(400, unknown_task, "taskID: unknown task 'robodesign-collab/none'")
    single = {**copy.deepcopy(robot(sol, "left")), "taskID": TID}
    del single["ID"]
    expect(400, single, "taskID: task 'robodesign-collab/shared_conveyor' is collaborative (robots left, right)")
    # the size caps apply to every robot and to the robots together
    notes = copy.deepcopy(sol)
    notes["robots"][1]["notes"] = "x" * 20_000
    expect(413, notes, "robots[1].notes: at most 16384 characters")
    many = copy.deepcopy(sol)
    many["robots"] = [{**copy.deepcopy(sol["robots"][0]), "ID": f"r{k}"} for k in range(17)]
    expect(413, many, "robots: at most 16 robots are allowed (got 17)")
    long_set = copy.deepcopy(sol)
    long_set["robots"][0]["moduleSet"] = "s" * 101
    expect(400, long_set, "robots[0].moduleSet: at most 100 characters")
    assert site.get("/api/solutions").json() == []


def test_collaborative_size_caps_count_every_robot(make_site, solved):
    from robodesign.web.service import Limits
    sol = solved["AA"]
    n = len(sol["robots"][0]["trajectory"]["q"]) * len(sol["robots"][0]["trajectory"]["q"][0])  # one robot's
    c = make_site(limits=Limits(trajectory_values=n + 1))  # one robot fits, both together do not
    r = post(c, sol)
    assert r.status_code == 413, r.text
    assert r.json()["detail"] == (f"solution.json: robots: {2 * n} trajectory values (samples × joints of all "
                                  f"robots); at most {n + 1} are allowed")
    c2 = make_site(limits=Limits(trajectory_values=2 * n))
    assert post(c2, sol).status_code == 201


def test_collaborative_uploads_share_the_workers_the_rate_limit_and_the_error_rules(make_site, solved, monkeypatch):
    import os
    import robodesign.web.judging as judging
    sol = solved["AA"]
    end = sol["robots"][0]["trajectory"]["t"][-1]
    # judged in a separate checker process at a lower priority (robodesign serve's default)
    c = make_site(check_processes=True, check_workers=1)
    r = post(c, sol, author="Proc")
    assert r.status_code == 201, r.text
    assert r.json()["costs"] == pytest.approx([end, end]) and r.json()["benchmark_id"] == CYC
    (pid,) = list(c.app.state.checker._get_pool()._processes)
    assert os.getpriority(os.PRIO_PROCESS, pid) == min(19, os.getpriority(os.PRIO_PROCESS, 0) + 10)
    r = post(c, no_wait(sol, "right", 100), author="Proc")
    assert r.status_code == 422 and r.json()["violations"][0]["constraint"] == "robotCollisionFree"
    make_site.close(c)

    # an internal error of the judge is a 500, never a verdict, and nothing is stored
    def broken(*a, **k):
        raise RuntimeError("a bug in the judge")
    monkeypatch.setattr(judging, "check_collab", broken)
    c = make_site()
    r = post(c, sol, author="Bug")
    assert r.status_code == 500 and "internal error (RuntimeError)" in r.json()["detail"]
    assert "valid" not in r.json() and [e["author"] for e in entries(c, CYC)] == ["Proc"]
    monkeypatch.undo()
    make_site.close(c)

    # the per-client upload rate counts collaborative uploads like any other (bursts of rate/3)
    c = make_site(upload_rate=3)
    assert post(c, sol, author="First").status_code == 201
    r = post(c, sol, author="Second")
    assert r.status_code == 429 and int(r.headers["retry-after"]) >= 1
    assert [e["author"] for e in entries(c, CYC)] == ["Proc", "First"]


# ------------------------------------------------------------------------------------------------------------
# single-robot and collaborative benchmarks never mix
# ------------------------------------------------------------------------------------------------------------
def left_alone_task() -> dict:
    """The shared cell as a single-robot task for the left arm: its goals and the "any robot" one, its base."""
    d = json.loads(Path(TASK_FILE).read_text())
    left = next(r for r in d.pop("robots") if r["ID"] == "left")
    d["header"] = {**d["header"], "ID": ALONE, "taskName": "the left arm alone"}
    d["goals"] = [{k: v for k, v in g.items() if k != "robot"} for g in d["goals"] if g.get("robot") in ("left", None)]
    d["constraints"] = d["constraints"] + [{"type": "basePlacement", "pose": left["basePlacement"]}]
    return d


def left_alone_solution(sol: dict) -> dict:
    single = {**copy.deepcopy(robot(sol, "left")), "taskID": ALONE}
    del single["ID"]
    return single


def test_single_robot_and_collaborative_boards_never_mix(site, solved):
    r = site.post("/api/tasks", json=left_alone_task())
    assert r.status_code == 201, r.text
    assert r.json()["tasks"][0]["collaborative"] is False
    sol = solved["AA"]
    single = post(site, left_alone_solution(sol), author="Solo")
    assert single.status_code == 201, single.text
    # the left arm's trajectory judged alone: the same cyc as in the cell
    assert single.json()["cost"] == pytest.approx(sol["robots"][0]["trajectory"]["t"][-1])
    collab = post(site, sol, author="Duo")
    assert collab.status_code == 201, collab.text
    s_id, c_id = single.json()["id"], collab.json()["id"]

    assert [e["id"] for e in entries(site, f"{ARM}:cyc:{ALONE}")] == [s_id]
    assert [e["id"] for e in entries(site, CYC)] == [c_id]
    ids = lambda **q: [x["id"] for x in site.get("/api/solutions", params=q).json()]  # noqa: E731
    assert ids(collaborative="1") == [c_id] and ids(collaborative="0") == [s_id]
    assert ids(moduleset="robodesign_arm") == [s_id] and ids(task=TID) == [c_id]
    assert sorted(ids()) == sorted([s_id, c_id])
    r = site.get("/api/solutions", params={"collaborative": "maybe"})
    assert r.status_code == 400 and "collaborative" in r.json()["detail"]
    # an ID that does not fit its task is refused, never an empty or mixed board
    r = site.get(f"/api/leaderboard/{ARM}:cyc:{TID}")
    assert r.status_code == 400 and "is collaborative (2 robots: left, right)" in r.json()["detail"]
    assert f"[{ARM},{ARM}]:cyc:{TID}" in r.json()["detail"]
    r = site.get(f"/api/leaderboard/[{ARM},{ARM}]:cyc:{ALONE}")
    assert r.status_code == 400 and "one robot (it is not collaborative)" in r.json()["detail"]
    r = site.get(f"/api/leaderboard/[{ARM}]:cyc:{TID}")
    assert r.status_code == 400 and "has 2 robots (left, right), the ID lists 1" in r.json()["detail"]
    r = site.get(f"/api/leaderboard/[{ARM},M-nope]:cyc:{TID}")
    assert r.status_code == 404 and "unknown module set 'nope'" in r.json()["detail"]
    # the form opens the board of the task's kind
    r = site.get("/leaderboard", params={"moduleset": "robodesign_arm", "cost": "cyc", "task": TID},
                 follow_redirects=False)
    assert r.status_code == 303 and r.headers["location"] == bid_url(CYC)
    bench = {b["benchmark_id"]: b["collaborative"] for b in site.get("/api/benchmarks").json()}
    assert bench == {CYC: True, f"{ARM}:cyc:{ALONE}": False}
    assert site.get(f"/tasks/{ALONE}").status_code == 200


# ------------------------------------------------------------------------------------------------------------
# an older database (before collaborative tasks) opens and is migrated
# ------------------------------------------------------------------------------------------------------------
def test_older_database_is_migrated(make_site, db_url, solved, tmp_path):
    url = db_url or f"sqlite:///{tmp_path / 'data' / 'bench.db'}"
    c = make_site()
    assert c.post("/api/tasks", json=left_alone_task()).status_code == 201
    old = post(c, left_alone_solution(solved["AA"]), author="Before")
    assert old.status_code == 201, old.text
    make_site.close(c)
    # what an older version's database looks like: the same tables without the new columns
    engine = make_engine(url)
    try:
        with engine.begin() as con:
            for table, cols in NEW_COLUMNS.items():
                for col in cols:
                    con.execute(text(f"ALTER TABLE {table} DROP COLUMN {col}"))
        for table, cols in NEW_COLUMNS.items():
            assert not set(cols) & {x["name"] for x in inspect(engine).get_columns(table)}
    finally:
        engine.dispose()

    c = make_site()  # opens it: the columns are added, the old rows get their defaults
    engine = make_engine(url)
    try:
        for table, cols in NEW_COLUMNS.items():
            assert set(cols) <= {x["name"] for x in inspect(engine).get_columns(table)}
        with engine.connect() as con:
            rows = con.execute(text("SELECT collaborative, robots_key, cost_tuple FROM solutions")).all()
            robots = dict(con.execute(text("SELECT task_id, robots FROM tasks")).all())
    finally:
        engine.dispose()
    assert [(bool(a), b, t) for a, b, t in rows] == [(False, "", "[]")]
    assert json.loads(robots[ALONE]) == [] and [r["ID"] for r in json.loads(robots[TID])] == ["left", "right"]
    (e,) = entries(c, f"{ARM}:cyc:{ALONE}")
    assert e["id"] == old.json()["id"] and e["collaborative"] is False
    assert e["cost"] == pytest.approx(old.json()["cost"])
    tasks = {t["id"]: t for t in c.get("/api/tasks").json()}
    assert tasks[TID]["collaborative"] is True and tasks[ALONE]["collaborative"] is False
    r = post(c, solved["AA"])
    assert r.status_code == 201, r.text
    assert [x["id"] for x in entries(c, CYC)] == [r.json()["id"]]
    make_site.close(c)
    c = make_site()  # a second start on the migrated database changes nothing
    assert [x["id"] for x in entries(c, CYC)] == [r.json()["id"]]
