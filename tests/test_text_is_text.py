"""Issue 22 case 11, the command-line half: text that is not text, broken pipes and YAML alias bombs.

* a lone UTF-16 surrogate (``"\\ud800"``) anywhere in a JSON file (a key, a goal2time key, an author) is refused by
  the JSON reader itself (robodesign.core.jsonio), so ``check`` and ``view`` end with exit 2 naming the field;
* ``robodesign check ... --json | true`` ends quietly with the verdict's exit code (no BrokenPipe traceback);
* an experiment config whose aliases expand to more than MAX_YAML_NODES values is refused at once (exit 2).
"""
from __future__ import annotations

import contextlib
import io
import json
import os
import subprocess
import sys
import time

import pytest
from test_web import make_seed, sol_json

from robodesign.cli.entry import main
from robodesign.core.errors import InputError
from robodesign.core.jsonio import loads_json
from robodesign.experiment.config import MAX_YAML_NODES, read_yaml
from robodesign.experiment.config_models import _expanded_size

SURROGATE = "\\ud800"  # as written in the JSON text: a lone high surrogate


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("text")
    seed = make_seed(d / "seed")
    sol = d / "sol.json"
    sol.write_text(json.dumps(sol_json(1.0)))
    return {"task": seed / "tasks" / "toy" / "all.json", "modules": seed / "modules" / "toy", "sol": sol, "dir": d}


def run(*args):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in args])
    return code, out.getvalue(), err.getvalue()


def test_reader_refuses_lone_surrogates_naming_the_field():
    with pytest.raises(InputError) as e:
        loads_json('{"goal2time": {"' + SURROGATE + '": 1.0}}', "s.json")
    assert str(e.value) == "s.json: goal2time.\\ud800: lone UTF-16 surrogate (\\ud800) in a key: not text"
    with pytest.raises(InputError) as e:
        loads_json('{"author": ["ok", "x\\uDFFF"]}', "s.json")
    assert e.value.json_path == "author[1]" and "(\\udfff) in a string" in str(e.value)
    # a proper pair is one character (U+1F600) and stays
    assert loads_json('{"a": "\\ud83d\\ude00"}', "s.json") == {"a": "\U0001F600"}


@pytest.mark.parametrize("where", ["key", "goal2time", "author"])
def test_check_and_view_exit_2_naming_the_field(files, where, tmp_path):
    data = sol_json(1.0)
    text = json.dumps(data)
    if where == "key":
        text = text[:-1] + ', "x' + SURROGATE + '": 1}'
        path = "x\\ud800"
    elif where == "goal2time":
        goal = next(iter(data["trajectory"]["goal2time"]))
        text = text.replace(f'"{goal}":', f'"{goal}{SURROGATE}":', 1)
        path = f"trajectory.goal2time.{goal}\\ud800"
    else:
        text = text[:-1] + ', "author": ["A' + SURROGATE + '"]}'
        path = "author[0]"
    bad = tmp_path / "bad.json"
    bad.write_text(text)
    code, out, err = run("check", files["task"], bad, "--modules", files["modules"], "--json")
    assert code == 2, (out, err)
    assert json.loads(out)["path"] == path and json.loads(out)["file"] == "bad.json"
    assert f"bad.json: {path}: lone UTF-16 surrogate" in err and "Traceback" not in err
    code, out, err = run("view", bad, "--task", files["task"], "--modules", files["modules"],
                         "--out", tmp_path / "v.html")
    assert code == 2 and f"bad.json: {path}: lone UTF-16 surrogate" in err


def test_broken_pipe_ends_quietly_with_the_verdict(files, tmp_path):
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    cmd = [sys.executable, "-m", "robodesign.cli.entry", "check", str(files["task"]), str(files["sol"]),
           "--modules", str(files["modules"]), "--json"]
    # the reader is gone before robodesign writes a byte: its stdout is a pipe nobody reads
    r, w = os.pipe()
    os.close(r)
    try:
        p = subprocess.run(cmd, stdout=w, stderr=subprocess.PIPE, env=env, timeout=300, cwd=tmp_path)
    finally:
        os.close(w)
    assert p.returncode == 0, p.stderr.decode()  # VALID
    assert p.stderr.decode() == ""
    bad = tmp_path / "broken.json"
    data = sol_json(1.0, broken=True)
    bad.write_text(json.dumps(data))
    r, w = os.pipe()
    os.close(r)
    try:
        p = subprocess.run(cmd[:5] + [str(bad)] + cmd[6:], stdout=w, stderr=subprocess.PIPE, env=env, timeout=300,
                           cwd=tmp_path)
    finally:
        os.close(w)
    assert p.returncode == 1 and p.stderr.decode() == ""  # INVALID, quietly


def _bomb(levels: int) -> str:
    lines = ["a0: &a0 [" + ",".join(['"lol"'] * 10) + "]"]
    for i in range(1, levels):
        lines.append(f"a{i}: &a{i} [" + ",".join([f"*a{i - 1}"] * 10) + "]")
    return "\n".join(lines) + "\n"


def test_yaml_alias_bomb_is_refused_at_once(tmp_path):
    text = _bomb(9)  # 10^9 strings once expanded, from < 600 bytes
    assert len(text) < 600
    t0 = time.process_time()
    with pytest.raises(InputError, match=f"more than {MAX_YAML_NODES} values once its aliases"):
        read_yaml(text, "bomb.yaml")
    assert time.process_time() - t0 < 2.0  # CPU time, not wall-clock: counting never expands
    cfg = tmp_path / "bomb.yaml"
    cfg.write_text(text)
    code, _out, err = run("run", cfg)
    assert code == 2 and "bomb.yaml: the YAML holds more than" in err
    # counted exactly without expanding: 4 levels = the root map + its 4 keys + a0 (1 list + 10 strings = 11),
    # a1 (1 + 10·11), a2 (1 + 10·111), a3 (1 + 10·1111)
    import yaml
    node = yaml.compose(_bomb(4))
    assert _expanded_size(node) == 1 + 4 + 11 + 111 + 1111 + 11111
    assert read_yaml("a: &x [1, 2]\nb: *x\nc: {d: *x}\n", "ok.yaml") == {"a": [1, 2], "b": [1, 2], "c": {"d": [1, 2]}}
    with pytest.raises(InputError, match="aliases"):
        read_yaml("a: &x [1, *x]\n", "loop.yaml")
