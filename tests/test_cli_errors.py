"""Exit codes and messages of the CLI on hostile or mistaken input (issue 13 §2, issue 15 §3).

0 success, 1 negative verdict, 2 bad input (one line naming file and field), 3 internal error.
With --json, stdout is JSON on every path.
"""
import json
import shutil
import subprocess
import sys

import numpy as np
import pytest

from robodesign.cli import entry as cli
from robodesign.cli.entry import main
from robodesign.core.jsonio import MAX_DEPTH, loads_json
from robodesign.core.errors import InputError
from robodesign.core.trajectory import Trajectory
from robodesign.formats.solution import Solution

from conftest import IMPROV, ROOT, TASKS

PTP3 = TASKS / "simple" / "PTP_3.json"
PTP1 = TASKS / "simple" / "PTP_1.json"


def run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


def one_line_error(err: str) -> str:
    assert "Traceback" not in err and err.count("\n") == 1, err
    assert err.startswith("robodesign: error: ")
    return err.strip().removeprefix("robodesign: error: ")


@pytest.fixture(scope="module")
def ptp3_solution(tmp_path_factory):
    """A schema-valid PTP_3 solution (a short rest trajectory of the IMPROV order): enough for the
    loaders; which verdict the checker gives does not matter for these tests."""
    t = np.arange(5) * 0.01
    q = np.zeros((5, 6))
    sol = Solution(task_id="simple/PTP_3", cost_function="cyc", module_set="IMPROV",
                   module_order=("1", "21", "4", "22", "5", "23", "12"), base_pose=np.eye(4),
                   trajectory=Trajectory(t, q, q.copy(), q.copy(), {"1": 0.02}))
    d = tmp_path_factory.mktemp("sol")
    return json.loads(sol.write(d / "sol.json").read_text())


def _text_with(data: dict, field_value: str, placeholder="__X__") -> str:
    """The JSON text of ``data`` with the string value ``placeholder`` replaced by raw JSON text."""
    return json.dumps(data).replace(f'"{placeholder}"', field_value)


# --------------------------------------------------------------------------- the JSON layer, once for all
@pytest.mark.parametrize("text,message,path", [
    ("[" * 1000 + "]" * 1000, f"JSON nested deeper than {MAX_DEPTH} levels at line 1, column {MAX_DEPTH + 1}", ""),
    ("[" * 500 + "]" * 500, f"nested deeper than {MAX_DEPTH} levels", "[0][0][0][0][0][0]..."),
    ('{"a": ' + "7" * 5000 + "}", "number 77777777777777777777... is out of range (beyond 1.8e308)", "a"),
    ('{"a": ' + "7" * 310 + "}", "number 77777777777777777777... is out of range (beyond 1.8e308)", "a"),
    ('{"a": {"b": [0.5, -1e400]}}', "number -1e400 is out of range (beyond 1.8e308)", "a.b[1]"),
    ('{"a": ["x", "y\\u0000z"]}', "NUL character (\\u0000) in a string", "a[1]"),
    ('{"k\\u0000": 1}', "NUL character (\\u0000) in a key", "k\\u0000"),
    ('{"a": [1, NaN]}', "NaN is not a valid value", "a[1]"),
])
def test_json_layer_rejects_with_file_and_field(text, message, path):
    with pytest.raises(InputError) as e:
        loads_json(text, "f.json")
    assert (e.value.file, e.value.reason, e.value.json_path) == ("f.json", message, path)


def test_json_layer_keeps_what_is_valid():
    # Infinity literals (CoBRA uses them for unbounded limits), tiny numbers, large but finite ones
    d = loads_json('{"a": Infinity, "b": -Infinity, "c": 1e-400, "d": 1.5e308, "e": ' + "9" * 300 + ', "f": "é✓"}')
    assert d["a"] == float("inf") and d["b"] == -float("inf") and d["c"] == 0.0 and d["d"] == 1.5e308
    assert d["e"] == int("9" * 300) and d["f"] == "é✓"
    nested = "[" * (MAX_DEPTH - 1) + "1" + "]" * (MAX_DEPTH - 1)   # 99 levels: accepted
    assert loads_json(nested) is not None


@pytest.mark.parametrize("make,field,message", [
    (lambda d: "[" * 1000 + "]" * 1000, None, f"JSON nested deeper than {MAX_DEPTH} levels at line 1, column 101"),
    (lambda d: _text_with(dict(d, cost="__X__"), "1" + "0" * 4400), "cost",
     "number 10000000000000000000... is out of range (beyond 1.8e308)"),
    (lambda d: _text_with(dict(d, computationTime="__X__"), "1e400"), "computationTime",
     "number 1e400 is out of range (beyond 1.8e308)"),
    (lambda d: _text_with(dict(d, trajectory=dict(d["trajectory"], t=[0.0, 0.01, "__X__", 0.03, 0.04])), "1e400"),
     "trajectory.t[2]", "number 1e400 is out of range (beyond 1.8e308)"),
    (lambda d: json.dumps(dict(d, moduleSet="IMP\0ROV")), "moduleSet", "NUL character (\\u0000) in a string"),
])
@pytest.mark.parametrize("as_json", [False, True])
def test_check_hostile_solution_is_bad_input(capsys, tmp_path, ptp3_solution, make, field, message, as_json):
    f = tmp_path / "hostile.json"
    f.write_text(make(ptp3_solution))
    code, out, err = run(capsys, "check", PTP3, f, "--modules", IMPROV, *(["--json"] if as_json else []))
    assert code == 2
    assert one_line_error(err) == f"hostile.json: {field + ': ' if field else ''}{message}"
    if as_json:
        assert json.loads(out) == {"error": message, "file": "hostile.json", "path": field}
    else:
        assert out == ""


def test_nul_in_a_task_mesh_reference_is_bad_input(capsys, tmp_path, ptp3_solution):
    task = json.loads(PTP3.read_text())
    task["obstacles"][0]["collision"][0]["parameters"]["file"] = "assets/QUASER\0.stl"
    (tmp_path / "simple").mkdir()
    f = tmp_path / "simple" / "PTP_3.json"
    f.write_text(json.dumps(task))
    sol = tmp_path / "sol.json"
    sol.write_text(json.dumps(ptp3_solution))
    code, out, err = run(capsys, "check", f, sol, "--modules", IMPROV, "--json")
    assert code == 2
    assert one_line_error(err) == ("PTP_3.json: obstacles[0].collision[0].parameters.file: "
                                   "NUL character (\\u0000) in a string")
    assert json.loads(out) == {"error": "NUL character (\\u0000) in a string", "file": "PTP_3.json",
                               "path": "obstacles[0].collision[0].parameters.file"}


@pytest.mark.parametrize("edit,field,message", [
    (lambda t: "[" * 1000 + "]" * 1000, None, f"JSON nested deeper than {MAX_DEPTH} levels at line 1, column 101"),
    (lambda t: t.replace('"mass": ', '"mass": ' + "9" * 5000 + ', "x": ', 1), "modules[0].bodies[0].mass",
     "number 99999999999999999999... is out of range (beyond 1.8e308)"),
    (lambda t: t.replace('"mass": ', '"mass": 1e400, "x": ', 1), "modules[0].bodies[0].mass",
     "number 1e400 is out of range (beyond 1.8e308)"),
    (lambda t: t.replace('"file": "', '"file": "\\u0000', 1), "modules[1].bodies[0].visual[0].parameters.file",
     "NUL character (\\u0000) in a string"),
])
def test_robot_hostile_modules_json_is_bad_input(capsys, tmp_path, edit, field, message):
    src = (IMPROV / "modules.json").read_text()
    folder = tmp_path / "IMPROV"
    folder.mkdir()
    (folder / "modules.json").write_text(edit(src))
    code, out, err = run(capsys, "robot", folder, "--order", "1,21,4,22,5,23,12", "--json")
    assert code == 2
    assert one_line_error(err) == f"IMPROV/modules.json: {field + ': ' if field else ''}{message}"
    assert json.loads(out) == {"error": message, "file": "IMPROV/modules.json", "path": field}


# --------------------------------------------------------------------------- internal errors: exit 3
def test_internal_error_exit_3_short_line_and_debug_traceback(capsys, monkeypatch):
    def boom(args):
        raise ZeroDivisionError("division by zero")
    monkeypatch.setattr(cli, "cmd_robot", boom)
    code, out, err = run(capsys, "robot", "robodesign_arm", "--order", "1")
    assert code == 3 and out == "" and err.count("\n") == 1 and "Traceback" not in err
    assert err == ("robodesign: internal error: ZeroDivisionError: division by zero. This is a bug in robodesign, "
                   "please report it (run again with --debug for the traceback)\n")
    code, out, err = run(capsys, "robot", "robodesign_arm", "--order", "1", "--json")
    assert code == 3 and json.loads(out) == {"error": "ZeroDivisionError: division by zero. This is a bug in "
                                                      "robodesign, please report it (run again with --debug for "
                                                      "the traceback)", "file": None, "path": None}
    for argv in (["--debug", "robot", "robodesign_arm", "--order", "1"],
                 ["robot", "robodesign_arm", "--order", "1", "--debug"]):
        code, out, err = run(capsys, *argv)
        assert code == 3 and err.startswith("Traceback (most recent call last):")
        assert 'raise ZeroDivisionError("division by zero")' in err
        assert err.endswith("please report it with the output of --debug\n")


def test_usage_errors_are_exit_2_and_json_with_json(capsys):
    code, out, err = run(capsys, "check", PTP3, "--json")
    assert code == 2 and err.startswith("usage: robodesign check")
    assert err.splitlines()[-1] == "robodesign: error: check: the following arguments are required: solution"
    assert json.loads(out) == {"error": "check: the following arguments are required: solution", "file": None,
                               "path": None}


def test_real_subprocess_exit_codes(tmp_path):
    """The installed entry point, not only main(): exit 2 on deep JSON, the version line."""
    exe = [sys.executable, "-m", "robodesign.cli"]
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 1000 + "]" * 1000)
    p = subprocess.run(exe + ["check", str(PTP3), str(deep), "--modules", str(IMPROV), "--json"],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and "Traceback" not in p.stderr
    assert json.loads(p.stdout)["error"] == f"JSON nested deeper than {MAX_DEPTH} levels at line 1, column 101"
    p = subprocess.run(exe + ["--version"], capture_output=True, text=True, timeout=120)
    from robodesign import __version__
    assert p.returncode == 0 and p.stdout.startswith(f"robodesign {__version__} (Python ")


# --------------------------------------------------------------------------- a CLI that explains itself
def _subparsers():
    parser = cli.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    return parser, sub.choices


def test_every_option_has_help_with_its_default():
    parser, subs = _subparsers()
    for name, sp in subs.items():
        for a in sp._actions:
            if not a.option_strings or a.dest == "help":
                continue
            assert a.help, f"{name} {a.option_strings[0]} has no help text"
            if a.default not in (None, False, [], "==SUPPRESS=="):
                shown = sp.formatter_class(prog="x")._get_help_string(a) % {"default": a.default}
                assert "default" in shown, f"{name} {a.option_strings[0]}: default {a.default!r} not shown"
    help_text = subs["solve"].format_help()
    assert "cost function, e.g. cyc, mechEnergy, Liu2, cyc_0.2,mechEnergy_1 (default: cyc)" in " ".join(
        help_text.split())


def test_view_help_matches_the_docs_table():
    """Every option of `robodesign view` is in docs/viewer.md's option table and vice versa."""
    _, subs = _subparsers()
    documented = set()
    for line in (ROOT / "docs" / "viewer.md").read_text().splitlines():
        if line.startswith("| `"):
            cell = line.split("|")[1]
            documented |= {w.strip("`,").split()[0] for w in cell.split("`") if w.strip("`, ").startswith("--")}
    options = {a.option_strings[-1] for a in subs["view"]._actions
               if a.option_strings and a.dest not in ("help", "debug")}
    assert documented == options


def test_budget_starting_with_a_dash_gets_the_budget_message(capsys):
    code, _, err = run(capsys, "optimize", PTP3, "--modules", IMPROV, "--budget", "-5s")
    assert code == 2 and one_line_error(err) == "budget '-5s': use e.g. 500evals, 60s, 10min or 500evals,60s"


def test_negative_values_after_options(capsys):
    code, out, _ = run(capsys, "robot", "robodesign_arm", "--order", "1,21", "--q", "-0.3", "--base-pose",
                       "-1,2,3", "--json")
    d = json.loads(out)
    assert code == 0 and d["q"] == [-0.3] and d["tcp_pose"][0][3] == pytest.approx(-1.0)


def test_solve_unknown_module_is_bad_input_like_robot(capsys):
    code, out, err = run(capsys, "solve", PTP3, "--modules", IMPROV, "--order", "1,99,4,22,5,23,12", "--json")
    msg = ("module '99' at position 1 is not in module set 'IMPROV' "
           "(IDs: 1, 4, 5, 6, 7, 8, 12, 13, 14, 15, 16, 21, 22, 23, 29, 101)")
    assert code == 2 and one_line_error(err) == "--order: " + msg
    assert json.loads(out) == {"error": "--order: " + msg, "file": None, "path": None}
    code, _, err = run(capsys, "robot", IMPROV, "--order", "1,99,4,22,5,23,12")
    assert code == 2 and one_line_error(err) == msg


def test_trajectory_mode_follows_the_cost():
    from robodesign.cli.commands import trajectory_mode
    assert trajectory_mode("cyc") == "time-optimal"
    assert trajectory_mode("mass") == "time-optimal"
    assert trajectory_mode("linkMechEnergy") == "time-optimal"  # not a term the trajectory optimizer has
    assert trajectory_mode("mechEnergy") == "optimize"
    assert trajectory_mode("Liu2") == "optimize"               # = mechEnergy + 0.2·cyc
    assert trajectory_mode("cyc_1,effort_0.1") == "optimize"
    assert trajectory_mode("mechEnergy", "time-optimal") == "time-optimal"
    assert trajectory_mode("cyc", "optimize") == "optimize"
    assert trajectory_mode("cyc", "auto", optimize_flag=True) == "optimize"
    with pytest.raises(InputError, match="--optimize-trajectory contradicts --trajectory time-optimal"):
        trajectory_mode("cyc", "time-optimal", optimize_flag=True)


@pytest.mark.slow
def test_solve_energy_cost_optimizes_the_trajectory_by_default(capsys):
    """PTP_3 with IMPROV for mechEnergy: the time-optimal profile costs ~117 J, the default (auto →
    trajectory optimization) ~38 J (docs/benchmarks.md); the output says which was used."""
    base = ["solve", PTP3, "--modules", IMPROV, "--order", "1,21,4,22,5,23,12", "--cost", "mechEnergy"]
    code, out, _ = run(capsys, *base, "--trajectory", "time-optimal")
    assert code == 0 and "trajectory   time-optimal (TOPP-RA)\n" in out
    code, out, _ = run(capsys, *base, "--trajectory", "time-optimal", "--json")
    fast = json.loads(out)
    code, out, _ = run(capsys, *base, "--json")
    auto = json.loads(out)
    assert code == 0 and fast["trajectory"] == "time-optimal" and auto["trajectory"] == "optimize"
    assert fast["cost"] == pytest.approx(fast["costs"]["mechEnergy"]) and fast["cost"] > 90
    assert auto["cost"] < 0.5 * fast["cost"]


def test_check_and_view_say_pass_modules_when_the_module_set_is_not_local(capsys, tmp_path, ptp3_solution):
    sol = tmp_path / "sol.json"
    sol.write_text(json.dumps(ptp3_solution))  # moduleSet "IMPROV": not a folder here, not built in
    msg = ("module set 'IMPROV' is not found locally (built-in: robodesign_arm, robodesign_heavy); pass --modules DIR "
           "(the folder holding its modules.json)")
    for argv in (["check", PTP3, sol], ["view", sol, "--task", PTP3, "--no-plots", "--out", tmp_path / "v.html"]):
        code, out, err = run(capsys, *argv)
        assert code == 2 and one_line_error(err) == f"{sol}: moduleSet: {msg}"


def test_view_of_another_tasks_solution_warns_and_exits_1(capsys, tmp_path, ptp3_solution):
    sol = tmp_path / "sol.json"
    sol.write_text(json.dumps(ptp3_solution))
    page = tmp_path / "v.html"
    code, out, err = run(capsys, "view", sol, "--task", PTP1, "--modules", IMPROV, "--no-plots", "--out", page)
    assert code == 1 and out.startswith(f"wrote {page}") and page.is_file()
    assert err == ("robodesign: warning: the solution is for task 'simple/PTP_3', not 'simple/PTP_1': the page "
                   "shows it in a cell it was not planned for\n")
    code, out, err = run(capsys, "view", sol, "--task", PTP3, "--modules", IMPROV, "--no-plots", "--out", page)
    assert code == 0 and err == ""
    # --check: the rest trajectory reaches none of PTP_3's goals, so the page is written and the exit is 1
    code, out, err = run(capsys, "view", sol, "--task", PTP3, "--modules", IMPROV, "--no-plots", "--check",
                         "--out", page)
    from robodesign.judge.checker import check
    from robodesign.formats.module_io import load_module_set
    from robodesign.formats.solution import load_solution
    from robodesign.formats.task_io import load_task
    verdict = check(load_task(PTP3), load_solution(sol), load_module_set(IMPROV))
    assert not verdict.valid and code == 1 and "INVALID" in page.read_text()
    assert err == (f"robodesign: warning: the checker finds the solution INVALID ({len(verdict.violations)} "
                   "violation(s), listed on the page)\n")


@pytest.mark.parametrize("text,message", [
    ("name: " + "[" * 1000 + "]" * 1000 + "\n", f"cfg.yaml: YAML nested deeper than {MAX_DEPTH} levels"),
    ("name: x\ntasks: " + "[" * 150 + "]" * 150 + "\n",
     f"cfg.yaml: tasks[0][0][0][0][0]...: nested deeper than {MAX_DEPTH} levels"),
    ("name: x\ntasks: [robodesign/pick_and_place]\noptimizers: [random]\nseeds: [.nan]\n",
     "cfg.yaml: seeds[0]: NaN is not a valid value"),
])
def test_hostile_experiment_config_is_bad_input(capsys, tmp_path, text, message):
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text(text)
    code, _, err = run(capsys, "run", cfg, "--out", tmp_path / "res", "--progress", "none")
    assert code == 2 and one_line_error(err) == f"{tmp_path}/{message}"
