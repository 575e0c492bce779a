"""The cost travels as one CostFunction object (issue 23 §3): from Problem.cost through the evaluator and solve to
trajectory optimization and the solution file, parsed once; a cost term registered at run time in the driver
is known in spawned worker processes (it travels with the pickled cost)."""
import json
import os
import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np

from robodesign.design import solve as solve_module
from robodesign.design.solve import SolveSettings, solve
from robodesign.formats import costs
from robodesign.formats.costs import CostContext, CostFunction, parse_cost, register_cost
from robodesign.formats.module_io import load_module_set
from robodesign.formats.solution import load_solution
from robodesign.formats.task_io import load_task

from conftest import IMPROV, TASKS

PLUGINS = Path(__file__).parent / "plugins"
PTP3 = TASKS / "simple" / "PTP_3.json"
ORDER = ["1", "21", "4", "22", "5", "23", "12"]


def _triple_cyc(ctx) -> float:  # module level: a term's function must pickle by reference
    return 3.0 * float(ctx.t[-1])


def test_a_cost_pickles_with_its_run_time_terms():
    register_cost("tripleCycT", _triple_cyc, "3 × cycle time", non_negative=True, overwrite=True)
    try:
        blob = pickle.dumps(parse_cost("tripleCycT_2,cyc"))
    finally:
        del costs._REGISTRY["tripleCycT"]  # a fresh process: the term was never registered there
    cf = pickle.loads(blob)
    assert cf.terms == (("cyc", 1.0), ("tripleCycT", 2.0)) and cf.descriptor() == "cyc,tripleCycT_2.0"
    ctx = CostContext(t=np.array([0.0, 0.5, 1.25]), q=np.zeros((3, 2)))
    assert cf.evaluate(ctx) == 1.25 + 2 * 3 * 1.25
    assert parse_cost("tripleCycT").terms == (("tripleCycT", 1.0),)  # and it is registered again
    del costs._REGISTRY["tripleCycT"]
    # built-in terms travel by name only
    assert b"_cyc" not in pickle.dumps(parse_cost("Liu2")) and pickle.loads(pickle.dumps(parse_cost("Liu2"))).name == "Liu2"


def test_solve_takes_the_cost_object_and_parses_nothing(monkeypatch):
    """A CostFunction given to solve is used as it is: no descriptor is parsed on the way (the checker reads the
    solution file's costFunction, as it does for any upload); trajectory optimization gets its weights."""
    task, ms = load_task(PTP3), load_module_set(IMPROV)
    calls = []
    monkeypatch.setattr(solve_module, "parse_cost", lambda *a, **k: calls.append(a) or parse_cost(*a, **k))
    from robodesign.solvers import trajopt
    sent = []
    real = trajopt.optimize_trajectory

    def spy(robot, seg, cost, **kw):
        sent.append(cost)
        return real(robot, seg, cost=cost, **kw)
    monkeypatch.setattr(trajopt, "optimize_trajectory", spy)
    cf = parse_cost("Liu2")
    res = solve(task, ms, ORDER, cost=cf, settings=SolveSettings(seed=1, optimize_trajectory=True, trajopt_nodes=12))
    assert calls == []
    assert res.feasible, res.message
    assert res.solution.cost_function == "Liu2"
    assert sent and all(c == {"cyc": 0.2, "mechEnergy": 1.0} for c in sent)
    assert res.verdict.cost == res.verdict.costs["Liu2"]
    solve(task, ms, ORDER, cost="Liu2", settings=SolveSettings(seed=1, stop_after="ik"))
    assert len(calls) == 1  # a descriptor is parsed once, at the door


def test_a_cost_registered_in_the_driver_is_used_in_the_workers(tmp_path):
    log, pid = tmp_path / "evaluated_by", tmp_path / "driver_pid"
    prog = (f"import os, sys\nsys.path.insert(0, {str(PLUGINS)!r})\nimport cost_samples\n"
            "from robodesign.formats.costs import register_cost\n"
            "register_cost('samples', cost_samples.samples, 'time steps', non_negative=True)\n"
            f"open({str(pid)!r}, 'w').write(str(os.getpid()))\n"
            "from robodesign.cli.entry import main\nsys.exit(main(sys.argv[1:]))\n")
    best = tmp_path / "best.json"
    p = subprocess.run([sys.executable, "-c", prog, "optimize", str(PTP3), "--modules", str(IMPROV), "--optimizer",
                        "random", "--budget", "16evals", "--workers", "2", "--cost", "samples", "--seed", "0",
                        "--json", "--out", str(best)], capture_output=True, text=True, timeout=900,
                       env={**os.environ, "RD_COST_LOG": str(log)})
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout)
    assert out["workers"] == 2 and out["feasible"]
    evaluators = {int(x) for x in log.read_text().split()}
    assert evaluators and int(pid.read_text()) not in evaluators  # evaluated in the workers only
    sol = load_solution(best)
    assert sol.cost_function == "samples"
    # the reported cost is the term's value on the written trajectory: its number of time steps
    assert out["best"]["cost"] == len(sol.trajectory.t) - 1 == out["best"]["costs"]["samples"]
    assert out["best"]["costs"]["cyc"] == sol.trajectory.t[-1]


def test_the_checker_takes_the_cost_object_and_parses_the_files_text_once(tmp_path, monkeypatch):
    """check(..., cost=cf) judges with the object the caller has and parses no cost text; without it the
    solution's costFunction is parsed once (the list of every known cost is built from the registry, not
    parsed name by name). Verdicts are the same either way."""
    import pytest

    from robodesign.judge import checker
    from test_checker import plan, solution, task_json
    from conftest import toy_module_set
    ms = load_module_set(toy_module_set(tmp_path))
    f = tmp_path / "toy" / "all.json"
    f.write_text(json.dumps(task_json()))
    task = load_task(f)
    calls = []
    monkeypatch.setattr(checker, "parse_cost", lambda *a, **k: calls.append(a) or parse_cost(*a, **k))
    sol = solution(*plan(), cost="Liu2")
    v_obj = checker.check(task, sol, ms, cost=parse_cost("Liu2"))
    assert calls == []
    v_text = checker.check(task, sol, ms)
    assert calls == [("Liu2",)]
    assert v_obj.valid and v_obj.to_json() | {"timings": None} == v_text.to_json() | {"timings": None}
    assert v_obj.cost == v_obj.costs["Liu2"] == pytest.approx(v_obj.costs["mechEnergy"] + 0.2 * v_obj.costs["cyc"])
    assert set(v_obj.costs) == set(costs.known_costs())
    with pytest.raises(ValueError, match="not the solution's costFunction"):
        checker.check(task, sol, ms, cost=parse_cost("cyc"))


def test_robodesign_solve_parses_the_cost_once(tmp_path, monkeypatch, capsys):
    """The command line parses --cost once; the CostFunction goes to the trajectory choice, solve and the
    solution file (which writes it in the reference's notation)."""
    from robodesign.cli.entry import main
    calls = []

    def counted(*a, **k):
        calls.append(a[0])
        return parse_cost(*a, **k)
    monkeypatch.setattr(costs, "parse_cost", counted)
    monkeypatch.setattr(solve_module, "parse_cost", counted)
    out = tmp_path / "sol.json"
    code = main(["solve", str(PTP3), "--modules", str(IMPROV), "--order", ",".join(ORDER), "--cost", "qDist_0.5,cyc",
                 "--out", str(out), "--json"])
    res = json.loads(capsys.readouterr().out)
    assert code == 0 and res["feasible"] and res["trajectory"] == "time-optimal"
    assert calls == ["qDist_0.5,cyc"]
    assert load_solution(out).cost_function == "cyc,qDist_0.5"
    assert res["cost"] == res["costs"]["cyc"] + 0.5 * res["costs"]["qDist"]
