"""Property-based fuzzing of everything robodesign reads (issue 13 §2).

Structural mutations (delete/rename keys, change types, huge/NaN/Inf numbers, deep nesting, unicode,
NUL, truncated text) of real tasks, solutions and module sets — the CoBRA reference files in
../shared/cobra and the built-in assets, read at test time — go through the CLI's ``main()`` in-process
(``check`` and ``robot``, with ``--json``). Every result must be exit 0, 1 or 2, stdout must be JSON, a
2 must be one ``robodesign: error:`` line and the JSON error object, and there is never a traceback or an
internal error (exit 3). A few mutated files also go through a real ``robodesign`` subprocess.

Hypothesis runs derandomized (the same inputs in every CI run); the example counts below add up to
more than 2,000 mutated inputs.
"""
import contextlib
import io
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robodesign.cli.entry import main
from robodesign.core.defaults import DEFAULT_ORDER
from robodesign.formats.module_io import load_module_set
from robodesign.core.paths import builtin_tasks_dir
from robodesign.design.solve import SolveSettings, solve
from robodesign.formats.task_io import load_task

from conftest import COBRA, IMPROV, PRIMITIVES, ROOT, TASKS

IMPROV_ORDER = ("1", "21", "4", "22", "5", "23", "12")
# ROBODESIGN_FUZZ_SCALE=10 runs ten times as many examples (a longer local fuzzing session)
SCALE = float(os.environ.get("ROBODESIGN_FUZZ_SCALE", "1"))
FUZZ = dict(deadline=None, derandomize=True, database=None, print_blob=True,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                   HealthCheck.function_scoped_fixture])

# raw JSON literals json.dumps cannot write; a mutation inserts a marker string that is replaced by one
RAW = ["1e400", "-1e400", "NaN", "Infinity", "-Infinity", "9" * 400, "-" + "9" * 5000, "1e-400", "1e308",
       "123456789012345678901234567890", "-0.0",
       "[" * 1200 + "0" + "]" * 1200, '{"a":' * 1200 + "0" + "}" * 1200]  # deeper than json.dumps can write
_MARK = "@@raw{}@@"

VALUES = st.one_of(
    st.none(), st.booleans(), st.integers(-2**70, 2**70), st.sampled_from([0, -1, 1, 2**63, -2**63 - 1]),
    st.floats(allow_nan=False, allow_infinity=False), st.sampled_from([1e308, -1e308, 5e-324, 0.0]),
    st.sampled_from([_MARK.format(i) for i in range(len(RAW))]),
    st.text(max_size=12), st.sampled_from(["", "\0", "a\0b", "../../etc/passwd", "/abs/path.stl", "é✓😀",
                                           "package://x.stl", "1,21", "cyc_-1", "Liu2", " ", "\u202e"]),
    st.just([]), st.just({}), st.lists(st.integers(-3, 3), max_size=4),
    st.dictionaries(st.text(max_size=4), st.integers(-2, 2), max_size=2),
)


def _children(node):
    if isinstance(node, dict):
        return list(node.keys())
    if isinstance(node, list):
        return list(range(len(node)))
    return []


def _pick_path(data, doc):
    """A path into ``doc``: below the root (almost always), descending while a coin says so (4/5), so every
    level is hit, not only the top-level keys or only the leaves."""
    path, node = [], doc
    while _children(node) and data.draw(st.integers(0, 19 if not path else 4), label="descend") != 0:
        keys = _children(node)
        k = keys[data.draw(st.integers(0, len(keys) - 1), label="child")]
        path.append(k)
        node = node[k]
    return path


def _get(doc, path):
    for k in path:
        doc = doc[k]
    return doc


def _mutate_once(data, doc):
    """One structural mutation of ``doc`` (in place when possible); returns the new root."""
    path = _pick_path(data, doc)
    op = data.draw(st.sampled_from(["delete", "rename", "replace", "replace", "perturb", "nest", "copy", "resize",
                                    "wrap"]), label="op")
    if not path:  # the root itself
        if op in ("replace", "perturb", "nest", "wrap"):
            return data.draw(VALUES) if op == "replace" else [doc] if op == "wrap" else {"x": doc}
        path_parent, key = None, None
    else:
        path_parent, key = _get(doc, path[:-1]), path[-1]
    if path_parent is None:
        return doc
    value = path_parent[key]
    if op == "delete":
        del path_parent[key]
    elif op == "rename" and isinstance(path_parent, dict):
        new = data.draw(st.one_of(st.sampled_from([key.upper(), key.lower(), key + "_", key[:-1], "ID", "type",
                                                   "\0" + key, key + "é"]), st.text(max_size=6)), label="key")
        path_parent[new] = path_parent.pop(key)
    elif op == "perturb" and isinstance(value, (int, float)) and not isinstance(value, bool):
        f = data.draw(st.sampled_from([-1, 0, 1e6, 1e-6, 1e300, 0.5]), label="factor")
        path_parent[key] = value * f if f != 0.5 else value + 0.5
    elif op == "nest":
        depth = data.draw(st.sampled_from([2, 20, 99, 150]), label="depth")  # deeper: the RAW markers
        nested = value
        for _ in range(depth):
            nested = [nested]
        path_parent[key] = nested
    elif op == "copy":  # a realistic value in the wrong place: another node of the same document
        path_parent[key] = json.loads(json.dumps(_get(doc, _pick_path(data, doc))))
    elif op == "resize" and isinstance(value, list):
        n = data.draw(st.sampled_from([0, 1, 2, len(value) // 2, len(value) + 1, 3 * len(value) + 1]), label="len")
        path_parent[key] = (value * (n // max(len(value), 1) + 1))[:n] if value else [None] * min(n, 3)
    elif op == "wrap":
        path_parent[key] = [value] if data.draw(st.booleans(), label="as list") else {"value": value}
    else:
        path_parent[key] = data.draw(VALUES, label="value")
    return doc


def mutated_text(data, doc) -> str:
    """1-3 structural mutations, sometimes followed by a text-level one (truncation, a byte inserted)."""
    doc = json.loads(json.dumps(doc))  # a deep copy, 5x faster than copy.deepcopy for these documents
    for _ in range(data.draw(st.integers(1, 3), label="n mutations")):
        doc = _mutate_once(data, doc)
    text = json.dumps(doc, ensure_ascii=data.draw(st.booleans(), label="ascii"))
    for i, raw in enumerate(RAW):
        text = text.replace(f'"{_MARK.format(i)}"', raw)
    text_op = data.draw(st.sampled_from(["none"] * 8 + ["truncate", "insert"]), label="text op")
    if text_op != "none" and text:
        pos = data.draw(st.integers(0, len(text) - 1), label="pos")
        text = text[:pos] if text_op == "truncate" else \
            text[:pos] + data.draw(st.sampled_from(["\0", "\ufeff", "\\", '"', "}", "\ud800", "é"])) + text[pos:]
    return text


def run_cli(*args):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in args])
    return code, out.getvalue(), err.getvalue()


def assert_contract(code, out, err, where=""):
    """Exit 0/1/2, JSON on stdout, a bad-input error as one line plus the JSON error object."""
    assert code in (0, 1, 2), f"{where}: exit {code}: {err}"
    assert "Traceback" not in err and "internal error" not in err, f"{where}: {err}"
    payload = json.loads(out)
    if code == 2:
        assert set(payload) == {"error", "file", "path"} and payload["error"], payload
        lines = [ln for ln in err.splitlines() if not ln.startswith(("robodesign: warning", "robodesign: note"))]
        assert len(lines) == 1 and lines[0].startswith("robodesign: error: "), err


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", encoding="utf-8", errors="surrogatepass") as f:
        f.write(text)
    return path


# ----------------------------------------------------------------------------------------- seed inputs
@pytest.fixture(scope="module")
def seeds(tmp_path_factory):
    """Seed documents (read from ../shared/cobra and assets/ now, not copied into the project) and a
    workspace whose folders link to the meshes the documents reference."""
    ws = tmp_path_factory.mktemp("fuzz")
    (ws / "tasks").mkdir()
    os.symlink(TASKS / "assets", ws / "tasks" / "assets")  # PTP_2/PTP_3 reference the CNC meshes there
    for name, src in (("IMPROV", IMPROV), ("robodesign_arm", ROOT / "assets" / "modules" / "robodesign_arm")):
        (ws / name).mkdir()
        for child in src.iterdir():
            if child.is_dir():
                os.symlink(child, ws / name / child.name)
    # real solutions written by the solver, plus a hand-made short one
    ptp3 = solve(load_task(TASKS / "simple" / "PTP_3.json"), load_module_set(IMPROV), list(IMPROV_ORDER),
                 settings=SolveSettings(seed=0))
    pnp_task = load_task("robodesign/pick_and_place")
    pnp = solve(pnp_task, load_module_set("robodesign_arm"), list(DEFAULT_ORDER), pnp_task.nominal_base_pose,
                settings=SolveSettings(seed=0))
    assert ptp3.feasible and pnp.feasible
    t = np.arange(4) * 0.01
    z = np.zeros((4, 6))
    short = ptp3.solution.with_(trajectory=type(ptp3.solution.trajectory)(t, z, z.copy(), z.copy(), {"1": 0.02}))
    sols = {}
    for name, sol in (("ptp3", ptp3.solution), ("pnp", pnp.solution), ("short", short)):
        sols[name] = json.loads(sol.write(ws / f"{name}_seed.json").read_text())
    tasks = {p.stem: json.loads(p.read_text()) for p in sorted((TASKS / "simple").glob("*.json"))}
    tasks.update({p.stem: json.loads(p.read_text()) for p in sorted((builtin_tasks_dir() / "robodesign").glob("*.json"))})
    modules = {}
    for name, folder in (("IMPROV", IMPROV), ("geometric_primitive_modules", PRIMITIVES),
                         ("robodesign_arm", ROOT / "assets" / "modules" / "robodesign_arm")):
        doc = json.loads((folder / "modules.json").read_text())
        used = set(MODULE_CASES[name].split(","))  # only the modules of the order: half the schema work
        modules[name] = dict(doc, modules=[m for m in doc["modules"] if str(m["header"]["ID"]) in used])
    return {"ws": ws, "solutions": sols, "tasks": tasks, "modules": modules}


SOLUTION_CASES = {  # seed solution → (task file or built-in ID, module set)
    "ptp3": (TASKS / "simple" / "PTP_3.json", IMPROV),
    "short": (TASKS / "simple" / "PTP_3.json", IMPROV),
    "pnp": ("robodesign/pick_and_place", "robodesign_arm"),
}
TASK_CASES = {  # seed task → the solution checked against its mutations
    "PTP_1": "short", "PTP_2": "short", "PTP_3": "ptp3", "Empty": "short",
    "pick_and_place": "pnp", "base_placement": "pnp", "machine_tending": "pnp", "timed_follow": "pnp",
    "welding_seam": "pnp",
}
MODULE_CASES = {"IMPROV": ",".join(IMPROV_ORDER), "robodesign_arm": ",".join(DEFAULT_ORDER),
                "geometric_primitive_modules": "base,J2,i_30,J1,l_15,J2,eef"}


def _check_solution(seeds, data):
    name = data.draw(st.sampled_from(sorted(SOLUTION_CASES)), label="solution")
    task, modules = SOLUTION_CASES[name]
    f = write(seeds["ws"] / "sol.json", mutated_text(data, seeds["solutions"][name]))
    return (f, task, modules), run_cli("check", task, f, "--modules", modules, "--json")


def _check_task(seeds, data):
    name = data.draw(st.sampled_from(sorted(TASK_CASES)), label="task")
    sol = seeds["ws"] / f"{TASK_CASES[name]}_seed.json"
    # <package>/<task ID>.json, so the ID-to-path rule and the mesh links hold for unmutated IDs
    f = write(seeds["ws"] / "tasks" / f"{seeds['tasks'][name]['header']['ID']}.json",
              mutated_text(data, seeds["tasks"][name]))
    modules = IMPROV if TASK_CASES[name] != "pnp" else "robodesign_arm"
    return (f, sol), run_cli("check", f, sol, "--modules", modules, "--json")


def _robot(seeds, data):
    name = data.draw(st.sampled_from(sorted(MODULE_CASES)), label="module set")
    f = write(seeds["ws"] / name / "modules.json", mutated_text(data, seeds["modules"][name]))
    return (f, MODULE_CASES[name]), run_cli("robot", f.parent, "--order", MODULE_CASES[name], "--json")


def _fuzz(seeds, target, n):
    n = max(1, int(n * SCALE))
    runs = []

    @settings(max_examples=n, **FUZZ)
    @given(st.data())
    def one(data):
        where, (code, out, err) = target(seeds, data)
        assert_contract(code, out, err, str(where))
        runs.append(code)

    one()
    assert len(runs) >= n, f"hypothesis ran {len(runs)} of {n} examples"
    return runs


@pytest.mark.slow
def test_fuzz_solutions(seeds):
    codes = _fuzz(seeds, _check_solution, 900)
    assert {1, 2} <= set(codes)  # mutations hit both verdicts and bad input, not one path only


@pytest.mark.slow
def test_fuzz_tasks(seeds):
    codes = _fuzz(seeds, _check_task, 700)
    assert {1, 2} <= set(codes)


@pytest.mark.slow
def test_fuzz_module_sets(seeds):
    codes = _fuzz(seeds, _robot, 500)
    assert {0, 2} <= set(codes)


def test_fuzz_seeds_are_valid(seeds):
    """The unmutated seeds pass: a mutation, not the workspace, is what makes an input bad."""
    for name, (task, modules) in SOLUTION_CASES.items():
        f = write(seeds["ws"] / "sol.json", json.dumps(seeds["solutions"][name]))
        code, out, err = run_cli("check", task, f, "--modules", modules, "--json")
        assert code == (1 if name == "short" else 0), (name, err)  # "short" misses PTP_3's goals
    for name, order in MODULE_CASES.items():
        f = write(seeds["ws"] / name / "modules.json", json.dumps(seeds["modules"][name]))
        code, out, err = run_cli("robot", f.parent, "--order", order, "--json")
        assert code == 0, (name, err)


def test_fuzz_through_real_subprocesses(seeds, tmp_path):
    """A few mutated inputs through the installed command: the process exit code and streams."""
    cases = [
        ("check", TASKS / "simple" / "PTP_3.json", "{sol}", "--modules", IMPROV, "--json"),
        ("robot", "{ms}", "--order", ",".join(IMPROV_ORDER), "--json"),
    ]
    texts = {
        "sol": json.dumps(dict(seeds["solutions"]["ptp3"], basePose=[[[[1]]]] * 3)),
        "ms": json.dumps(seeds["modules"]["IMPROV"]).replace('"mass": ', '"mass": "heavy", "x": ', 1),
    }
    sol = write(tmp_path / "sol.json", texts["sol"])
    ms = tmp_path / "IMPROV"
    write(ms / "modules.json", texts["ms"])
    os.symlink(IMPROV / "STLfiles", ms / "STLfiles")
    for case in cases:
        args = [str(a).format(sol=sol, ms=ms) for a in case]
        p = subprocess.run([sys.executable, "-m", "robodesign.cli", *args], capture_output=True, text=True,
                           timeout=300, env=dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path)))
        assert p.returncode == 2, p.stderr
        assert_contract(p.returncode, p.stdout, p.stderr, " ".join(args))


# ----------------------------------------------------------------------------------------- issue 22: check + upload
N_TOY = int(os.environ.get("ROBODESIGN_FUZZ_TOY", "2500"))  # per path: 2 × 2,500 ≥ 5,000 inputs
def short_toy_seed(folder: Path):
    """A seed folder with the toy module set and task ``toy/short`` (the toy task with goals A and a 0.03 s pause
    only) and a valid 6-sample solution of it, resting at A: checked in ~0.1 s, so thousands fit in a test."""
    from conftest import toy_module_set
    from test_checker import DT, QA, hold, solution, task_json
    toy_module_set(folder / "modules")
    t = task_json(extra_goals=False)
    t["header"]["ID"] = "toy/short"
    t["goals"] = [dict(g, duration=0.03) if g["ID"] == "P" else g for g in t["goals"] if g["ID"] in ("A", "P")]
    t["constraints"] = [c for c in t["constraints"] if c["type"] != "allGoalsFulfilledInOrder"]
    write(folder / "tasks" / "toy" / "short.json", json.dumps(t))
    q, dq, ddq = hold(QA, 0.05)
    sol = solution(np.arange(len(q)) * DT, q, dq, ddq, {"A": 0.0, "P": 0.05}).to_json()
    sol["taskID"] = "toy/short"
    return folder, sol


@pytest.fixture(scope="module")
def toy_site(tmp_path_factory):
    """The short toy task and its module set as files (for ``check``) and as a website (in process)."""
    pytest.importorskip("fastapi", reason="the website needs fastapi")
    from fastapi.testclient import TestClient

    from robodesign.web import create_app
    d = tmp_path_factory.mktemp("toyfuzz")
    seed, sol = short_toy_seed(d / "seed")
    app = create_app(data_dir=d / "data", seed=[seed], seed_builtin=False, upload_rate=0, read_rate=0,
                     queue_size=64, per_client_queue=64)
    with TestClient(app, raise_server_exceptions=False) as c:
        yield {"ws": d, "task": seed / "tasks" / "toy" / "short.json", "modules": seed / "modules" / "toy",
               "solution": sol, "client": c}


def _check_toy(site, data):
    f = write(site["ws"] / "sol.json", mutated_text(data, site["solution"]))
    return f, run_cli("check", site["task"], f, "--modules", site["modules"], "--json")


def _upload_toy(site, data):
    """A mutated solution through POST /api/solutions: raw JSON (sometimes wrapped, sometimes async) or a form."""
    c = site["client"]
    text = mutated_text(data, site["solution"])
    body = text.encode("utf-8", "surrogatepass")
    how = data.draw(st.sampled_from(["raw", "raw", "wrapped", "form", "async"]), label="how")
    if how == "form":
        r = c.post("/api/solutions", files={"file": ("s.json", body, "application/json")}, data={"author": "F"})
    elif how == "wrapped":
        r = c.post("/api/solutions", content=b'{"author": "W", "solution": ' + body + b"}",
                   headers={"content-type": "application/json"})
    else:
        r = c.post("/api/solutions", content=body, headers={"content-type": "application/json"},
                   params={"author": "R", **({"async": 1} if how == "async" else {})})
    if r.status_code == 202:  # stored, then judged: its result must be a verdict or a 4xx too
        url = r.json()["status_url"]
        for _ in range(2000):
            s = c.get(url).json()
            if s["state"] in ("done", "failed"):
                break
            import time
            time.sleep(0.005)
        return (how, text[:200]), s["status"], s["result"]
    return (how, text[:200]), r.status_code, r.json()


# Issue 22: ≥ 5,000 mutated solutions, half through ``check`` in process, half through the upload route: 0
# tracebacks, 0 exit 3, 0 HTTP 500. Two tests of N_TOY inputs each (the same inputs as one test of both), so that
# ``pytest -n 2`` (README) runs the halves side by side.
@pytest.mark.slow
def test_fuzz_2500_inputs_through_check(toy_site):
    """The first half of issue 22's 5,000 inputs: mutated solutions through ``check`` in process."""
    f = write(toy_site["ws"] / "sol.json", json.dumps(toy_site["solution"]))  # the unmutated seed is valid
    assert run_cli("check", toy_site["task"], f, "--modules", toy_site["modules"], "--json")[0] == 0
    codes = _fuzz(toy_site, lambda s, d: _check_toy(s, d), N_TOY)
    assert {0, 1, 2} <= set(codes) and len(codes) >= N_TOY * SCALE


@pytest.mark.slow
def test_fuzz_2500_inputs_through_the_upload_route(toy_site):
    """The second half of issue 22's 5,000 inputs: mutated solutions through POST /api/solutions."""
    statuses = []

    @settings(max_examples=max(1, int(N_TOY * SCALE)), **FUZZ)
    @given(st.data())
    def one(data):
        where, status, body = _upload_toy(toy_site, data)
        assert status in (201, 400, 413, 422), (where, status, body)
        assert isinstance(body, dict) and (body.get("detail") or status == 201), (where, body)
        statuses.append(status)

    one()
    assert len(statuses) >= N_TOY * SCALE and {201, 400, 422} <= set(statuses)
