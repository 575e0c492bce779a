"""Errors keep their kind (issue 23 §4): bad input is exit 2 naming file and field wherever it is found, an
infeasible design is a failing stage, and neither becomes the other. Through the real entry point (a
subprocess) for the planner name and for an InputError raised inside a stage of the solve pipeline."""
import json
import subprocess
import sys

import numpy as np
import pytest

from robodesign.core.errors import AssemblyError, InfeasibleError, InputError
from robodesign.design.solve import SolveSettings, check_settings, solve
from robodesign.formats.module_io import load_module_set
from robodesign.formats.task_io import load_task
from robodesign.solvers.planning import planner_name
from robodesign.solvers.timing import TimingError
from robodesign.solvers.trajopt import TrajoptError

from conftest import IMPROV, TASKS

RD = [sys.executable, "-m", "robodesign.cli"]
PTP3 = TASKS / "simple" / "PTP_3.json"
ORDER = "1,21,4,22,5,23,12"


def _run(args, code="", timeout=600):
    """The CLI in a fresh interpreter; ``code`` runs first (e.g. to make a stage raise)."""
    prog = code + "\nimport sys\nfrom robodesign.cli.entry import main\nsys.exit(main(sys.argv[1:]))\n"
    return subprocess.run([sys.executable, "-c", prog, *map(str, args)], capture_output=True, text=True,
                          timeout=timeout)


def test_misspelt_planner_exits_2_before_any_evaluation(tmp_path):
    p = subprocess.run(RD + ["optimize", str(PTP3), "--modules", str(IMPROV), "--optimizer", "random",
                             "--budget", "50evals", "--planner", "rrtconect", "--out", str(tmp_path / "best.json"),
                             "--json"], capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert p.returncode == 2, (p.stdout, p.stderr)
    assert "Traceback" not in p.stderr
    err = json.loads(p.stdout)["error"]
    assert err.startswith("--planner: unknown planner 'rrtconect' (did you mean 'rrtconnect'?); available: ")
    assert "evaluation" not in p.stdout and not (tmp_path / "best.json").exists()
    assert not any(tmp_path.iterdir())  # no journal, no solution: nothing was evaluated


def test_misspelt_planner_of_solve_exits_2():
    p = subprocess.run(RD + ["solve", str(PTP3), "--modules", str(IMPROV), "--order", ORDER, "--planner", "RRTstr"],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 2 and "Traceback" not in p.stderr
    assert p.stderr.strip() == ("robodesign: error: --planner: unknown planner 'RRTstr' (did you mean 'rrtstar'?); "
                                "available: " + ", ".join(__import__("robodesign.solvers.planning", fromlist=["x"])
                                                         .available_planners()))


def test_misspelt_planner_in_a_config_names_file_and_field(tmp_path):
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text("name: x\nmodules: robodesign_arm\ntasks: [robodesign/pick_and_place]\noptimizers: [random]\n"
                   "budget: 4evals\nsolve: {planner: bitstr}\n")
    p = subprocess.run(RD + ["run", str(cfg), "--out", str(tmp_path / "out")], capture_output=True, text=True,
                       timeout=600)
    assert p.returncode == 2, p.stderr
    assert "cfg.yaml: solve.planner: unknown planner 'bitstr' (did you mean 'bitstar'?)" in p.stderr
    assert not (tmp_path / "out" / "evaluations.sqlite").exists()


def test_input_error_inside_a_stage_is_exit_2_not_an_infeasible_stage(tmp_path):
    """A stage meeting bad input (here the reach stage, made to raise what a parser deep below would) stops
    the command with exit 2 and the file and field, instead of 'failed at stage reach' (exit 1)."""
    patch = ("from robodesign.core.errors import InputError\n"
             "from robodesign.design import solve as s\n"
             "def reach(self):\n"
             "    raise InputError('expected a number, got \"x\"', file='task.json', path=['goals', 0, 'pose'])\n"
             "s._Pipeline.reach = reach\n")
    p = _run(["solve", PTP3, "--modules", IMPROV, "--order", ORDER, "--out", tmp_path / "sol.json"], patch)
    assert p.returncode == 2, (p.stdout, p.stderr)
    assert p.stderr.strip() == 'robodesign: error: task.json: goals[0].pose: expected a number, got "x"'
    assert "reach" not in p.stdout and not (tmp_path / "sol.json").exists()


def test_a_bug_inside_a_stage_is_exit_3_not_an_infeasible_stage():
    patch = ("from robodesign.design import solve as s\n"
             "def ik(self):\n"
             "    raise ZeroDivisionError('a bug')\n"
             "s._Pipeline.ik = ik\n")
    p = _run(["solve", PTP3, "--modules", IMPROV, "--order", ORDER], patch)
    assert p.returncode == 3, (p.stdout, p.stderr)
    assert "robodesign: internal error: ZeroDivisionError: a bug. This is a bug in robodesign" in p.stderr


# ------------------------------------------------------------------------------------ in-process, by kind
@pytest.fixture(scope="module")
def ptp3():
    return load_task(PTP3), load_module_set(IMPROV)


def test_unknown_planner_raises_from_solve_instead_of_failing_at_plan(ptp3):
    task, ms = ptp3
    with pytest.raises(InputError, match=r"unknown planner 'nope'"):
        solve(task, ms, ORDER.split(","), settings=SolveSettings(planner="nope", ik_restarts=50, ik_solutions=4))


def test_infeasible_errors_are_failing_stages(ptp3, monkeypatch):
    """An InfeasibleError of a solver (timing) is the stage's failure with its message; an order that does
    not assemble fails the assembly stage (a candidate is a design, not a file)."""
    task, ms = ptp3
    assert issubclass(TimingError, InfeasibleError) and issubclass(TrajoptError, InfeasibleError)
    assert not issubclass(InfeasibleError, InputError)
    from robodesign.design import solve as s

    def timing(self):
        raise TimingError("toppra failed: 7")
    monkeypatch.setattr(s._Pipeline, "timing", timing)
    res = solve(task, ms, ORDER.split(","), settings=SolveSettings(ik_restarts=100, ik_solutions=4))
    assert (res.stage, res.message) == ("timing", "toppra failed: 7")
    assert [st.name for st in res.stages] == ["assembly", "base", "reach", "ik", "static_torque", "plan", "timing"]
    res = solve(task, ms, ["1", "1", "1"])  # a base module after a base module
    assert res.stage == "assembly" and res.message
    with pytest.raises(AssemblyError):  # the same error outside the assembly stage is not swallowed
        from robodesign.formats.assembly import Assembly
        Assembly.from_order(ms, ["1", "1", "1"])


@pytest.mark.parametrize("settings,file,message", [
    (SolveSettings(planner="rrtconect"), None, "--planner: unknown planner 'rrtconect' (did you mean 'rrtconnect'?)"),
    (SolveSettings(timing="topra"), None, "--timing: unknown timing method 'topra' (did you mean 'toppra'?); "
                                          "available: toppra, ruckig"),
    (SolveSettings(plan_time=0.0), None, "--plan-time: must be a positive number of seconds, got 0.0"),
    (SolveSettings(plan_time=float("nan")), "c.yaml", "c.yaml: solve.plan_time: must be a positive number"),
    (SolveSettings(stop_after="iks"), "c.yaml", "c.yaml: solve.stop_after: unknown stage 'iks'"),
])
def test_check_settings_names_the_option_or_field(settings, file, message):
    with pytest.raises(InputError) as e:
        check_settings(settings, file=file, path=["solve"])
    assert str(e.value).startswith(message), str(e.value)


def test_check_settings_accepts_every_available_planner_in_any_case():
    from robodesign.solvers.planning import available_planners
    avail = available_planners()
    assert "rrtconnect" in avail and len(avail) >= 5
    for name in avail:
        check_settings(SolveSettings(planner=name.upper()))
        assert planner_name(name.upper()) == name
    assert np.isfinite(SolveSettings().plan_time)


def test_a_plugin_that_cannot_be_imported_is_bad_input_but_a_bug_in_it_is_not(monkeypatch, tmp_path):
    """A config naming an installed optimizer whose module cannot be imported names the file and field (exit 2);
    any other exception while loading it is a bug and keeps its kind (exit 3), instead of becoming bad input."""
    from robodesign.design import optimize
    from robodesign.design.problem import Problem
    from robodesign.experiment.config import check_optimizer
    problem = Problem.build(PTP3, IMPROV, "cyc")

    def missing(name):
        raise ModuleNotFoundError("No module named 'gone'")
    monkeypatch.setattr(optimize, "load_optimizer", missing)
    with pytest.raises(InputError) as e:
        check_optimizer("random", {}, problem, "cfg.yaml", ["optimizers", 0])
    assert str(e.value) == ("cfg.yaml: optimizers[0].name: optimizer 'random' is registered but cannot be loaded: "
                            "ModuleNotFoundError: No module named 'gone'")

    def broken(name):
        raise ZeroDivisionError("a bug in the plugin")
    monkeypatch.setattr(optimize, "load_optimizer", broken)
    with pytest.raises(ZeroDivisionError):
        check_optimizer("random", {}, problem, "cfg.yaml", ["optimizers", 0])
