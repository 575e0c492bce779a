"""A/B benchmark of the house redesign (issue 23: "behaviour unchanged", no slowdown over 5 %): each commit of the
redesign against its parent, on the hot paths it touched, the same measurement code run against both checkouts.

    flock /tmp/robodesign-bench.lock .venv/bin/python experiments/bench_house_ab.py [--rounds 4] \
        [--pair A:B[:group,group...]] ... [--quick] [--out docs/results/house_ab/ab.json]

Without ``--pair`` the four pairs of the redesign are measured (parent : commit : groups):

* ``7312ff5:ca91683`` the package move (alias finder for the old flat names): models, checker, solve, cold;
* ``8204881:9caa54a`` merge of 'house-sizes' (judge, urdf, viewer, cli, experiment splits): checker, urdf,
  viewer, cold;
* ``f22c8fc:837abec`` web: Bench split by job, create_app split into route modules: web;
* ``da28b26:d29a2b8`` design/solve.py split into stages.py and goal_planner.py: solve, screen.

Each commit is checked out once as a detached worktree ``<worktrees>/ab_<sha>`` (created when missing; ``git
worktree remove`` them afterwards). Every measurement is a fresh process of this file (``--measure GROUP``) with
``PYTHONPATH=<worktree>/src`` (and ``<worktree>/tests`` for the web group), so nothing but the checkout differs;
robodesign is imported by its packaged module names, falling back to the old flat names on a checkout before the
package move. The numba IK kernels are compiled into each worktree's cache before the first round. Rounds
alternate the order of A and B (A first in even rounds) group by group. A round's figure is the median of that
process's repeats; the table gives, per figure, the median over rounds of A and of B, B/A, the slowdown of B in
percent (for rates: A/B - 1) and the range of the per-round paired ratios.

Groups (PTP_3 and IMPROV from ../shared/cobra; GOOD = the known-good arm 1,21,4,22,5,23,12):

* models: random valid 6-DoF IMPROV assemblies -> Robot models per second; Robot.fk and Robot.rnea per call and as
  ratios to raw pinocchio (experiments/bench_models.py);
* checker: GOOD's solution (seed 1) stretched to 1,500 samples, checked with the between-sample certification,
  samples only, and its gradient-filled copy (witness search) (experiments/bench_checker.py);
* solve: solve() of GOOD with the default settings and with the evaluator's settings (cost cyc), seeds 0..k-1;
  the costs are recorded too (they must agree between A and B);
* screen: random candidates of the default search space solved up to the IK stage (experiments/bench_evaluator.py);
* urdf: export_urdf of GOOD's Robot;
* viewer: build_scene of PTP_3 with GOOD and its solved trajectory;
* cold: wall time of fresh processes ``python -m robodesign.cli --help`` and ``... solve PTP_3 --order GOOD --json``
  (warm numba cache);
* web: ``robodesign serve`` on the toy task of the tests with a leaderboard of ``rows`` solutions; sequential GETs
  of six pages (each from a new client address), median and p90 milliseconds.
"""
from __future__ import annotations

import argparse
import datetime as dt
import importlib
import json
import os
import platform
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
SHARED = ROOT.parent / "shared" / "cobra"
GOOD = ("1", "21", "4", "22", "5", "23", "12")
DEFAULT_PAIRS = ["7312ff5:ca91683:models,checker,solve,cold", "8204881:9caa54a:checker,urdf,viewer,cold",
                 "f22c8fc:837abec:web", "da28b26:d29a2b8:solve,screen"]
LIMIT = 0.05  # issue 23: no slowdown over 5 %


# ------------------------------------------------------------------------------------------------------------
# worker side: one group of figures in this process, against the robodesign on PYTHONPATH
# ------------------------------------------------------------------------------------------------------------
def rd(new: str, old: str | None = None):
    """robodesign.<new>, or robodesign.<old> on a checkout before the package move."""
    try:
        return importlib.import_module("robodesign." + new)
    except ModuleNotFoundError as e:
        if old is None or not (e.name or "").startswith("robodesign"):
            raise
        return importlib.import_module("robodesign." + old)


def fig(value: float, better: str, unit: str) -> dict:
    return {"value": float(value), "better": better, "unit": unit}


def _problem(shared: Path):
    import robodesign
    task_io = rd("formats.task_io", "task_io")
    return (task_io.load_task(shared / "tasks" / "simple" / "PTP_3.json"),
            robodesign.load_module_set(shared / "modules" / "IMPROV"))


def _warm_ik() -> None:
    rd("solvers.ik_kernel").warm_up()


def _good_solution(task, ms, seed: int = 1):
    sv = rd("design.solve", "solve")
    res = sv.solve(task, ms, list(GOOD), settings=sv.SolveSettings(seed=seed))
    assert res.feasible, res.message
    return res.solution


def g_models(a, shared) -> tuple:
    import numpy as np
    import pinocchio as pin

    import robodesign
    assembly = rd("formats.assembly", "assembly")
    ms = robodesign.load_module_set(shared / "modules" / "IMPROV")
    rng = np.random.default_rng(0)
    n = 20 if a.quick else 300
    orders = [assembly.random_serial_order(ms, rng, dof=6) for _ in range(n)]
    robodesign.Robot.from_order(ms, orders[0])  # the mesh cache
    rates = []
    for _ in range(1 if a.quick else 3):
        t0 = time.perf_counter()
        robots = [robodesign.Robot.from_order(ms, o) for o in orders]
        rates.append(n / (time.perf_counter() - t0))
    r = robots[0]
    m, d = r.model, r.model.createData()
    k = 200 if a.quick else 2000
    Q, V, A = (rng.uniform(-1, 1, (k, 6)) for _ in range(3))
    loops = {
        "raw_fk": lambda: [(pin.framesForwardKinematics(m, d, q), d.oMf[r.tcp_frame]) for q in Q],
        "fk": lambda: [r.fk(q) for q in Q],
        "raw_rnea": lambda: [pin.rnea(m, d, q, v, ac) for q, v, ac in zip(Q, V, A)],
        "rnea": lambda: [r.rnea(q, v, ac) for q, v, ac in zip(Q, V, A)],
    }
    t = {name: [] for name in loops}
    for f in loops.values():  # warm-up pass
        f()
    for _ in range(1 if a.quick else 5):
        for name, f in loops.items():
            t0 = time.perf_counter()
            f()
            t[name].append((time.perf_counter() - t0) / k * 1e6)
    med = {name: statistics.median(v) for name, v in t.items()}
    figs = {"models/s": fig(statistics.median(rates), "higher", "1/s"),
            "Robot.fk us": fig(med["fk"], "lower", "us"),
            "Robot.fk / raw pinocchio": fig(med["fk"] / med["raw_fk"], "lower", "x"),
            "Robot.rnea us": fig(med["rnea"], "lower", "us"),
            "Robot.rnea / raw pinocchio": fig(med["rnea"] / med["raw_rnea"], "lower", "x")}
    return figs, {"raw_fk_us": med["raw_fk"], "raw_rnea_us": med["raw_rnea"], "n_models": n}


def g_checker(a, shared) -> tuple:
    import numpy as np
    checker = rd("judge.checker", "checker")
    solution = rd("formats.solution", "solution")
    timing = rd("solvers.timing")
    task, ms = _problem(shared)
    _warm_ik()
    sol = _good_solution(task, ms)
    tr = sol.trajectory  # stretched to ~1,500 samples as in experiments/bench_checker.py (one motion)
    n_target = 200 if a.quick else 1500
    m = max(1, int(round((n_target - 1) / (tr.n - 1))))
    t_new = np.arange(m * (tr.n - 1) + 1) * task.dt
    q, dq, ddq = timing.JointTrajectory(tr.t, tr.q, tr.dq, tr.ddq).interpolate(t_new / m)
    index = {g: int(np.argmin(np.abs(tr.t - v))) for g, v in tr.goal2time.items()}
    g2t = {g: float(t_new[m * i]) for g, i in index.items()}
    sol = sol.with_(trajectory=solution.SolutionTrajectory(t_new, q, dq / m, ddq / m ** 2, g2t))
    tr = sol.trajectory
    dqg = np.gradient(tr.q, tr.t, axis=0)
    grad = sol.with_(trajectory=solution.SolutionTrajectory(tr.t, tr.q, dqg, np.gradient(dqg, tr.t, axis=0),
                                                            dict(tr.goal2time)))
    v0 = checker.check(task, sol, ms)  # warm-up
    cases = {"check 1,500 samples ms": (sol, checker.CheckSettings()),
             "check samples only ms": (sol, checker.CheckSettings(between_samples=False)),
             "check gradient copy (witness) ms": (grad, checker.CheckSettings())}
    t = {k: [] for k in cases}
    verdicts = {}
    for _ in range(1 if a.quick else 5):
        for k, (s, st) in cases.items():
            t0 = time.perf_counter()
            v = checker.check(task, s, ms, st)
            t[k].append((time.perf_counter() - t0) * 1e3)
            verdicts[k] = [v.valid, sorted({x.constraint for x in v.violations})]
    figs = {k: fig(statistics.median(v), "lower", "ms") for k, v in t.items()}
    return figs, {"samples": tr.n, "valid": v0.valid, "verdicts": verdicts}


def g_solve(a, shared) -> tuple:
    from dataclasses import replace
    sv = rd("design.solve", "solve")
    ev = rd("design.evaluator", "evaluator")
    sp = rd("design.search_space", "search_space")
    task, ms = _problem(shared)
    _warm_ik()
    sv.solve(task, ms, list(GOOD))  # warm-up
    k = 1 if a.quick else 6
    key = sp.Candidate(GOOD, ()).key()
    t = {"solve GOOD (default settings) ms": [], "evaluation of GOOD (evaluator settings, cyc) ms": []}
    costs = {name: [] for name in t}
    for s in range(k):
        for name in t:
            if name.startswith("solve"):
                settings = sv.SolveSettings(seed=s)
            else:
                settings = replace(ev.evaluation_settings(), seed=ev.candidate_seed(s, key))
            t0 = time.perf_counter()
            res = sv.solve(task, ms, list(GOOD), cost="cyc", settings=settings)
            t[name].append((time.perf_counter() - t0) * 1e3)
            costs[name].append(round(res.cost, 9) if res.feasible else res.stage)
    return {name: fig(statistics.median(v), "lower", "ms") for name, v in t.items()}, {"costs": costs}


def g_screen(a, shared) -> tuple:
    from collections import Counter

    import numpy as np
    sv = rd("design.solve", "solve")
    sp = rd("design.search_space", "search_space")
    task, ms = _problem(shared)
    space = sp.SearchSpace(ms)
    rng = np.random.default_rng(1)
    n = 10 if a.quick else 150
    cands = [space.random_order(rng) for _ in range(n)]
    _warm_ik()
    sv.solve(task, ms, cands[0], settings=sv.SolveSettings(stop_after="ik"))
    rates, stages = [], Counter()
    for _ in range(1 if a.quick else 2):
        stages = Counter()
        t0 = time.perf_counter()
        for i, order in enumerate(cands):
            stages[sv.solve(task, ms, order, settings=sv.SolveSettings(seed=i, stop_after="ik")).stage] += 1
        rates.append(n / (time.perf_counter() - t0))
    return ({"screen to IK: candidates/s": fig(statistics.median(rates), "higher", "1/s")},
            {"stages": dict(sorted(stages.items()))})


def g_urdf(a, shared) -> tuple:
    import robodesign
    urdf = rd("formats.urdf", "urdf")
    ms = robodesign.load_module_set(shared / "modules" / "IMPROV")
    robot = robodesign.Robot.from_order(ms, GOOD)
    tmp = Path(tempfile.mkdtemp(prefix="rd-ab-urdf-"))
    try:
        urdf.export_urdf(robot, tmp / "warm.urdf")
        t = []
        for i in range(3 if a.quick else 30):
            t0 = time.perf_counter()
            urdf.export_urdf(robot, tmp / f"r{i}.urdf")
            t.append((time.perf_counter() - t0) * 1e3)
        size = (tmp / "r0.urdf").stat().st_size
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return {"export_urdf GOOD ms": fig(statistics.median(t), "lower", "ms")}, {"bytes": size}


def g_viewer(a, shared) -> tuple:
    cell = rd("model.cell", "cell")
    scene = importlib.import_module("robodesign.viewer.scene")
    task, ms = _problem(shared)
    _warm_ik()
    sol = _good_solution(task, ms)
    robot = cell.build_robot(task, ms, sol.assembly(ms), sol.base_pose)
    s = scene.build_scene(task, robot, sol.trajectory)
    t = []
    for _ in range(2 if a.quick else 10):
        t0 = time.perf_counter()
        s = scene.build_scene(task, robot, sol.trajectory)
        t.append((time.perf_counter() - t0) * 1e3)
    return ({"build_scene PTP_3 + GOOD ms": fig(statistics.median(t), "lower", "ms")},
            {"scene_json_bytes": len(json.dumps(s, default=str))})


def g_cold(a, shared) -> tuple:
    rdcli = [sys.executable, "-m", "robodesign.cli"]
    cmds = {"cold start: robodesign --help s": rdcli + ["--help"],
            "cold start: robodesign solve PTP_3 GOOD s": rdcli + [
                "solve", str(shared / "tasks" / "simple" / "PTP_3.json"), "--modules", str(shared / "modules" / "IMPROV"),
                "--order", ",".join(GOOD), "--json"]}
    t = {k: [] for k in cmds}
    for _ in range(1 if a.quick else 4):
        for k, cmd in cmds.items():
            t0 = time.perf_counter()
            p = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            t[k].append(time.perf_counter() - t0)
            if p.returncode not in (0, 1):
                raise RuntimeError(f"{cmd[3:5]} exited {p.returncode}: {p.stderr[-500:]}")
    return {k: fig(statistics.median(v), "lower", "s") for k, v in t.items()}, {}


def _request(port: int, method: str, path: str, body: bytes | None = None, headers=None, timeout: float = 60):
    import http.client
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
    try:
        conn.request(method, path, body=body, headers=headers or {})
        r = conn.getresponse()
        data = r.read()
        return r.status, data
    finally:
        conn.close()


def g_web(a, shared) -> tuple:
    import signal

    from test_web import BOARD, make_seed, sol_json  # the toy task of the checkout's own tests
    tmp = Path(tempfile.mkdtemp(prefix="rd-ab-web-"))
    seed = make_seed(tmp / "seed")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = {k: v for k, v in os.environ.items() if k != "ROBODESIGN_ADMIN_TOKEN"}
    log = open(tmp / "server.log", "w")
    server = subprocess.Popen([sys.executable, "-m", "robodesign.cli", "serve", "--data", str(tmp / "data"), "--seed",
                               str(seed), "--no-builtin", "--port", str(port), "--host", "127.0.0.1"],
                              stdout=subprocess.DEVNULL, stderr=log, env=env)
    try:
        deadline = time.time() + 180
        while True:
            try:
                if _request(port, "GET", "/healthz", timeout=2)[0] == 200:
                    break
            except OSError:
                pass
            if server.poll() is not None or time.time() > deadline:
                raise RuntimeError(f"the server did not start: {(tmp / 'server.log').read_text()[-2000:]}")
            time.sleep(0.2)
        rows = 3 if a.quick else 20
        sid = None
        for i in range(rows):
            st, body = _request(port, "POST", f"/api/solutions?author=row{i}", json.dumps(sol_json(1 + 0.01 * i)).encode(),
                                {"Content-Type": "application/json", "X-Forwarded-For": f"10.0.0.{i + 1}"})
            assert st == 201, (st, body[:300])
            sid = json.loads(body)["id"]
        pages = ["/", f"/leaderboard/{BOARD}", f"/api/leaderboard/{BOARD}", "/api/solutions", "/tasks/toy/all",
                 f"/solutions/{sid}"]
        n = 0
        samples = {p: [] for p in pages}
        for rep in range(-3, 2 if a.quick else 40):  # 3 warm-up passes
            for p in pages:
                n += 1
                t0 = time.perf_counter()
                st, _ = _request(port, "GET", p, headers={"X-Forwarded-For": f"10.{1 + n // 62500}.{n // 250 % 250}."
                                                                            f"{n % 250 + 1}"})
                ms = (time.perf_counter() - t0) * 1e3
                if st != 200:
                    raise RuntimeError(f"GET {p}: {st}")
                if rep >= 0:
                    samples[p].append(ms)
    finally:
        server.send_signal(signal.SIGTERM)
        try:
            server.wait(30)
        except subprocess.TimeoutExpired:
            server.kill()
            server.wait(30)
        log.close()
        shutil.rmtree(tmp, ignore_errors=True)
    allv = sorted(x for v in samples.values() for x in v)
    p90 = allv[min(len(allv) - 1, int(0.9 * len(allv)))]
    figs = {"web: page median ms": fig(statistics.median(allv), "lower", "ms"),
            "web: page p90 ms": fig(p90, "lower", "ms")}
    for p, v in samples.items():
        name = p.replace(BOARD, "<board>").replace(f"/{sid}", "/<id>")
        figs[f"web: GET {name} ms"] = fig(statistics.median(v), "lower", "ms")
    return figs, {"requests": len(allv), "rows": rows}


GROUPS = {"models": g_models, "checker": g_checker, "solve": g_solve, "screen": g_screen, "urdf": g_urdf,
          "viewer": g_viewer, "cold": g_cold, "web": g_web}


def measure(a) -> None:
    import warnings
    warnings.simplefilter("ignore", DeprecationWarning)  # old names on purpose on the parent checkouts
    import robodesign
    t0 = time.perf_counter()
    figs, info = GROUPS[a.measure](a, Path(a.shared))
    info["robodesign"] = str(Path(robodesign.__file__).parent)
    info["seconds"] = time.perf_counter() - t0
    print("RESULT " + json.dumps({"figures": figs, "info": info}), flush=True)


# ------------------------------------------------------------------------------------------------------------
# driver side
# ------------------------------------------------------------------------------------------------------------
def git(*args: str, cwd: Path = ROOT) -> str:
    return subprocess.run(["git", "-C", str(cwd), *args], check=True, capture_output=True, text=True).stdout.strip()


def worktree(sha: str, base: Path) -> Path:
    full = git("rev-parse", "--verify", sha + "^{commit}")
    wt = base / f"ab_{sha}"
    if not wt.exists():
        git("worktree", "add", "--detach", str(wt), full)
    head = git("rev-parse", "HEAD", cwd=wt)
    if head != full:
        raise SystemExit(f"{wt} is at {head[:12]}, not {sha}")
    if git("status", "--porcelain", "--untracked-files=no", cwd=wt):
        raise SystemExit(f"{wt} has local changes")
    return wt


def env_for(wt: Path, group: str) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("ROBODESIGN_JIT", "NUMBA_CACHE_DIR", "PYTHONPATH")}
    paths = [str(wt / "src")] + ([str(wt / "tests")] if group == "web" else [])
    env["PYTHONPATH"] = os.pathsep.join(paths)
    env["PYTHONHASHSEED"] = "0"
    return env


def prepare(wt: Path) -> float:
    """Compile the IK kernels into the worktree's numba cache (``__pycache__`` beside ik_kernel.py)."""
    env = env_for(wt, "")
    probe = [sys.executable, "-c", "from robodesign.solvers import ik_kernel as k; print(k.compiled())"]
    t0 = time.perf_counter()
    if subprocess.run(probe, env=env, capture_output=True, text=True, cwd=wt).stdout.strip() != "True":
        subprocess.run([sys.executable, "-m", "robodesign.solvers.ik_kernel"], env=dict(env, ROBODESIGN_COMPILE_NICE="0"),
                       check=True, cwd=wt)
        if subprocess.run(probe, env=env, capture_output=True, text=True, cwd=wt).stdout.strip() != "True":
            raise SystemExit(f"the IK kernels of {wt} did not compile")
    return time.perf_counter() - t0


def run_group(wt: Path, group: str, a) -> dict:
    cmd = [sys.executable, str(Path(__file__).resolve()), "--measure", group, "--shared", a.shared]
    if a.quick:
        cmd.append("--quick")
    p = subprocess.run(cmd, env=env_for(wt, group), capture_output=True, text=True, cwd=wt)
    lines = [x for x in p.stdout.splitlines() if x.startswith("RESULT ")]
    if p.returncode != 0 or not lines:
        raise SystemExit(f"{group} on {wt} failed ({p.returncode}):\n{p.stdout[-2000:]}\n{p.stderr[-3000:]}")
    out = json.loads(lines[-1][len("RESULT "):])
    if Path(out["info"]["robodesign"]).resolve() != (wt / "src" / "robodesign").resolve():
        raise SystemExit(f"{group}: imported {out['info']['robodesign']}, not {wt}")
    return out


def slowdown(a_val: float, b_val: float, better: str) -> float:
    """How much worse B is than A (0.05 = 5 % slower); negative when B is faster."""
    return b_val / a_val - 1 if better == "lower" else a_val / b_val - 1


def summarize(pair: dict) -> list:
    rows = []
    names = list(pair["rounds"][0]["A"].keys())
    for name in names:
        av = [r["A"][name]["value"] for r in pair["rounds"]]
        bv = [r["B"][name]["value"] for r in pair["rounds"]]
        better = pair["rounds"][0]["A"][name]["better"]
        am, bm = statistics.median(av), statistics.median(bv)
        paired = [slowdown(x, y, better) for x, y in zip(av, bv)]
        sd = slowdown(am, bm, better)
        rows.append({"figure": name, "unit": pair["rounds"][0]["A"][name]["unit"], "better": better, "A": am, "B": bm,
                     "ratio_B_over_A": bm / am, "slowdown": sd, "paired_slowdowns": paired, "A_rounds": av,
                     "B_rounds": bv,
                     "within_5pct": sd <= LIMIT,
                     "consistently_over_5pct": all(x > LIMIT for x in paired)})
    return rows


def fmt(x: float) -> str:
    return f"{x:.3g}" if abs(x) < 100 else f"{x:.0f}"


def table(pairs: list) -> str:
    lines = ["| pair (A → B) | figure | A median | B median | B/A | slowdown of B | paired rounds | within 5 % |",
             "|---|---|---:|---:|---:|---:|---|---|"]
    for p in pairs:
        for r in p["summary"]:
            rng = f"{100 * min(r['paired_slowdowns']):+.1f} … {100 * max(r['paired_slowdowns']):+.1f} %"
            verdict = "yes" if r["within_5pct"] else ("**no** (every round)" if r["consistently_over_5pct"] else
                                                      "**no** (not every round)")
            lines.append(f"| {p['A']} → {p['B']} | {r['figure']} | {fmt(r['A'])} | {fmt(r['B'])} | "
                         f"{r['ratio_B_over_A']:.3f} | {100 * r['slowdown']:+.1f} % | {rng} | {verdict} |")
    return "\n".join(lines)


def drive(a) -> None:
    base = Path(a.worktrees)
    pairs = []
    for spec in a.pair or DEFAULT_PAIRS:
        parts = spec.split(":")
        groups = parts[2].split(",") if len(parts) > 2 and parts[2] else ["models", "checker", "solve", "cold"]
        unknown = set(groups) - set(GROUPS)
        if unknown:
            raise SystemExit(f"unknown groups {sorted(unknown)}; known: {sorted(GROUPS)}")
        pairs.append({"A": parts[0], "B": parts[1], "groups": groups,
                      "A_subject": git("log", "-1", "--format=%s", parts[0])[:160],
                      "B_subject": git("log", "-1", "--format=%s", parts[1])[:160], "rounds": []})
    started = dt.datetime.now(dt.timezone.utc)
    meta = {"started_utc": started.isoformat(timespec="seconds"), "host": platform.node(), "cpus": os.cpu_count(),
            "python": sys.version.split()[0], "argv": sys.argv[1:], "rounds": a.rounds, "quick": a.quick,
            "loadavg_start": os.getloadavg(), "prepare_seconds": {}, "round_loadavg": []}
    wts = {}
    for p in pairs:
        for side in ("A", "B"):
            sha = p[side]
            if sha not in wts:
                wts[sha] = worktree(sha, base)
                meta["prepare_seconds"][sha] = round(prepare(wts[sha]), 1)
                print(f"worktree {wts[sha]} ready ({meta['prepare_seconds'][sha]} s)", flush=True)
    for r in range(a.rounds):
        for p in pairs:
            rec = {"A": {}, "B": {}, "info": {"A": {}, "B": {}}}
            for g in p["groups"]:
                for side in (("A", "B") if r % 2 == 0 else ("B", "A")):
                    out = run_group(wts[p[side]], g, a)
                    rec[side].update(out["figures"])
                    rec["info"][side][g] = out["info"]
            p["rounds"].append(rec)
            print(f"round {r}: {p['A']} -> {p['B']}: " + ", ".join(
                f"{k} {fmt(rec['A'][k]['value'])}/{fmt(rec['B'][k]['value'])}" for k in rec["A"]), flush=True)
        meta["round_loadavg"].append(os.getloadavg())
    meta["finished_utc"] = dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
    meta["loadavg_end"] = os.getloadavg()
    for p in pairs:
        p["summary"] = summarize(p)
    print()
    print(table(pairs))
    out = Path(a.out) if a.out else ROOT / "docs" / "results" / "house_ab" / (
        "ab_" + started.strftime("%Y%m%dT%H%MZ") + ("_quick" if a.quick else "") + ".json")
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"meta": meta, "pairs": pairs}, indent=1))
    print(f"\nwritten {out}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pair", action="append", help="A:B[:groups] (repeatable; default: the four pairs of issue 23)")
    ap.add_argument("--rounds", type=int, default=4)
    ap.add_argument("--quick", action="store_true", help="tiny settings (a dry check of the script)")
    ap.add_argument("--worktrees", default=str(ROOT.parent), help="folder of the ab_<sha> worktrees")
    ap.add_argument("--shared", default=str(SHARED), help="the CoBRA reference files (tasks/, modules/)")
    ap.add_argument("--out", help="JSON file (default docs/results/house_ab/ab_<UTC time>.json)")
    ap.add_argument("--measure", choices=sorted(GROUPS), help=argparse.SUPPRESS)  # worker mode
    a = ap.parse_args(argv)
    if a.measure:
        measure(a)
    else:
        drive(a)


if __name__ == "__main__":
    main()
