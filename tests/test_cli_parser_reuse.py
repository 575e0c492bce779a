"""``main()`` builds its argparse parser once per process (issue 24: the fuzz tests call it thousands of times);
a later call must not see an earlier call's options, defaults or replaced commands."""
import argparse

import pytest

import robodesign.cli.commands as commands
from robodesign.cli import entry
from robodesign.cli.entry import main


def _recorder(calls, mutate=False):
    def cmd(args):
        calls.append({k: list(v) if isinstance(v, list) else v for k, v in vars(args).items()})
        if mutate:  # a command that changes its (list) arguments in place
            for value in vars(args).values():
                if isinstance(value, list):
                    value.append("changed=1")
        return 0
    return cmd


def test_the_parser_is_built_once_per_process():
    assert isinstance(entry._parser(), argparse.ArgumentParser)
    assert entry._parser() is entry._parser()
    assert entry.build_parser() is not entry._parser()  # the public builder still builds a new one


def test_a_second_call_does_not_see_the_first_calls_options(monkeypatch):
    calls = []
    monkeypatch.setattr(entry, "cmd_robot", _recorder(calls))
    assert main(["robot", "setA", "--order", "1,2", "--q", "0.1,0.2", "--base-pose", "1,2,3", "--json",
                 "--urdf", "a.urdf"]) == 0
    assert main(["robot", "setB", "--order", "3"]) == 0
    first, second = calls
    assert (first["modules"], first["order"], first["q"], first["json"], first["urdf"]) == \
        ("setA", "1,2", "0.1,0.2", True, "a.urdf")
    assert (second["modules"], second["order"], second["q"], second["base_pose"], second["json"], second["urdf"]) == \
        ("setB", "3", None, None, False, None)
    assert second["argv"] == ["robot", "setB", "--order", "3"]


def test_list_defaults_are_not_shared_between_calls(monkeypatch):
    """``--opt`` / ``--robot`` default to a list: a command that appends to it must not change the parser's
    default, and a given list must not leak into a call without the option."""
    calls = []
    monkeypatch.setattr(commands, "cmd_optimize", _recorder(calls, mutate=True))
    assert main(["optimize", "t.json", "--modules", "M", "--opt", "a=1", "--opt", "b=2", "--budget", "9evals"]) == 0
    assert main(["optimize", "t.json", "--modules", "M"]) == 0
    assert main(["optimize", "t.json", "--modules", "M"]) == 0
    assert [c["opt"] for c in calls] == [["a=1", "b=2"], [], []]
    assert [c["budget"] for c in calls] == ["9evals", "50evals", "50evals"]
    calls.clear()
    monkeypatch.setattr(commands, "cmd_solve", _recorder(calls, mutate=True))
    for _ in range(2):
        assert main(["solve", "t.json", "--modules", "M", "--order", "1"]) == 0
    assert [c["robot"] for c in calls] == [[], []]


def test_a_replaced_command_is_found_at_each_call(monkeypatch):
    calls = []
    assert main(["robot", "no_such_module_set", "--order", "1"]) == 2  # the real command first: bad input
    monkeypatch.setattr(entry, "cmd_robot", _recorder(calls))
    assert main(["robot", "no_such_module_set", "--order", "1"]) == 0
    assert len(calls) == 1


@pytest.mark.parametrize("argv,code", [(["robot"], 2), (["robto"], 2), (["optimize", "t", "--budjet", "1"], 2)])
def test_usage_errors_are_unchanged_after_reuse(capsys, argv, code):
    for _ in range(2):
        assert main(argv) == code
        err = capsys.readouterr().err
        assert err.startswith("usage: robodesign")
