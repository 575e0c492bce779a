"""Quiet by default off a terminal, --quiet/--verbose, "did you mean" for misspelt options and commands, and
the small output fixes of issue 24 (base pose without negative zeros, plot units, built-in task list)."""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from robodesign.cli import main
from robodesign.cli.progress import SUMMARY_SECONDS, Progress, progress_mode
from robodesign.design.optimize import Budget


def _ev(k: int, feasible: bool):
    return SimpleNamespace(feasible=feasible, cost=2.0 - k * 0.01 if feasible else math.inf, stage="ik",
                           candidate=SimpleNamespace(key=lambda: f"cand{k}"))


def _feed(monkeypatch, mode: str, n: int = 100, seconds: float = 12.0) -> Progress:
    """n evaluations spread evenly over ``seconds`` of a fake clock."""
    clock = {"t": 1000.0}
    monkeypatch.setattr("robodesign.cli.progress.time.perf_counter", lambda: clock["t"])
    p = Progress(Budget(evaluations=n), mode)
    best = None
    for k in range(n):
        clock["t"] += seconds / n
        ev = _ev(k, k % 10 == 3)
        best = ev if ev.feasible else best
        p(k, ev, best)
    p.close()
    return p


def test_off_a_terminal_the_progress_is_one_line_per_five_seconds(monkeypatch, capsys):
    p = _feed(monkeypatch, "summary")
    lines = capsys.readouterr().err.splitlines()
    # 12 s of evaluations: a line at 5 s and one at 10 s, not one per evaluation
    assert len(lines) == 2 == int(12.0 // SUMMARY_SECONDS)
    # 0.12 s per evaluation: 5 s after the 42nd; feasible are 3, 13, 23, 33 (the best: 33, cost 2 - 0.33)
    assert lines[0].startswith("[    5.0s] 42 evaluations, 4 feasible, best 1.67")
    assert p.count == 100 and p.feasible == 10


def test_verbose_prints_every_evaluation_and_quiet_nothing(monkeypatch, capsys):
    _feed(monkeypatch, "lines")
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 100 and "failed at ik" in err[0] and "cost 1.97" in err[3]
    _feed(monkeypatch, "none")
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("flags, mode", [({"json": True}, "none"), ({"quiet": True}, "none"),
                                          ({"verbose": True}, "lines"), ({}, "summary")])
def test_progress_mode_of_the_flags_off_a_terminal(flags, mode):
    args = SimpleNamespace(**{"json": False, "quiet": False, "verbose": False, **flags})
    assert progress_mode(args) == mode  # pytest's stderr is not a terminal


@pytest.mark.parametrize("argv, hint", [
    (["optimize", "t.json", "--modules", "m", "--budjet", "5"], "--budjet (did you mean '--budget'?)"),
    (["solve", "t.json", "--modules", "m", "--ordr", "1"], "--ordr (did you mean '--order'?)"),
    (["run", "--resme", "x"], "--resme (did you mean '--resume'?)"),
    (["optimise", "t.json"], "unknown command 'optimise' (did you mean 'optimize'?)"),
])
def test_did_you_mean(argv, hint, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert hint in err and "Traceback" not in err
    if argv[0] != "optimise":  # the usage shown is the subcommand's, not the bare top-level one
        assert f"usage: robodesign {argv[0]}" in err


def test_an_unknown_builtin_task_lists_the_builtin_tasks(capsys):
    assert main(["solve", "robodesign/pick_and_plac", "--modules", "robodesign_arm", "--order", "1"]) == 2
    err = capsys.readouterr().err
    assert "did you mean 'robodesign/pick_and_place'?" in err
    assert "built-in tasks: robodesign-collab/shared_conveyor, robodesign/base_placement," in err


def test_long_commands_take_quiet_and_verbose(capsys):
    for command in ("optimize", "run", "solve", "generate"):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        out = capsys.readouterr().out
        assert "--quiet" in out and "--verbose" in out, command
    with pytest.raises(SystemExit):
        main(["serve", "--help"])
    assert "checker processes (threads with --check-threads" in " ".join(capsys.readouterr().out.split())


def test_base_pose_text_has_no_negative_zero():
    from robodesign.experiment.report import base_pose_text, search_offsets_text
    T = np.eye(4)
    T[:3, 3] = [-0.00001, 0.00042, -0.0]
    assert base_pose_text(T.tolist()) == "xyz = (0.0000, 0.0004, 0.0000) m, yaw = 0.0°"
    assert search_offsets_text([0.00042, -0.00001]) == "[0.0004, 0.0000]"
    from robodesign.viewer.html import _fmt_pose
    R = np.diag([1.0, -1.0, -1.0])  # roll π: the pitch comes out as asin(-0.0) = -0.0
    T = np.eye(4)
    T[:3, :3] = R
    assert _fmt_pose(T) == "xyz [0, 0, 0] m, rpy [180°, 0°, 0°]"


def test_anytime_plot_axis_names_the_cost_and_its_unit():
    from robodesign.experiment.report import cost_axis_label
    assert cost_axis_label("cyc") == "best cyc so far [s]"
    assert cost_axis_label("mass") == "best mass so far [kg]"
    assert cost_axis_label("cyc_0.2,mass_1") == "best cyc_0.2,mass_1 so far (weighted sum: cyc [s], mass [kg])"
