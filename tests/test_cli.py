"""The command line: real outputs, exit codes 0/1/2, one-line errors for bad input."""
import json

import numpy as np
import pytest

from robodesign import Robot, load_module_set
from robodesign.cli.entry import main
from robodesign.core.defaults import DEFAULT_ORDER

from conftest import IMPROV, TASKS


def run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_robot_json_matches_the_model(capsys):
    code, out, _ = run(capsys, "robot", "robodesign_arm", "--order", ",".join(DEFAULT_ORDER), "--q",
                       "0.1,0.2,-0.3,0.4,0.5,0.6", "--json")
    assert code == 0
    d = json.loads(out)
    ms = load_module_set("robodesign_arm")
    r = Robot.from_order(ms, DEFAULT_ORDER)
    q = np.array([0.1, 0.2, -0.3, 0.4, 0.5, 0.6])
    assert d["dof"] == 6 and d["mass"] == pytest.approx(sum(ms[m].mass for m in DEFAULT_ORDER))
    np.testing.assert_allclose(d["tcp_pose"], r.fk(q), atol=1e-12)
    np.testing.assert_allclose(d["gravity_torque"], r.gravity_torque(q), atol=1e-12)
    assert d["joint_limits"]["upper"][0] == pytest.approx(np.radians(170))
    assert d["self_collision"] is False


def test_robot_base_pose_and_urdf(capsys, tmp_path):
    code, out, _ = run(capsys, "robot", IMPROV, "--order", "1,21,4,22,5,23,12", "--base-pose", "1,2,3",
                       "--json", "--urdf", tmp_path / "arm.urdf")
    d = json.loads(out)
    r = Robot.from_order(load_module_set(IMPROV), ["1", "21", "4", "22", "5", "23", "12"])
    np.testing.assert_allclose(np.array(d["tcp_pose"])[:3, 3], r.fk(np.zeros(6))[:3, 3] + [1, 2, 3], atol=1e-12)
    assert (tmp_path / "arm.urdf").is_file() and d["urdf"].endswith("arm.urdf")


@pytest.mark.parametrize("args,msg", [
    (["robot", "robodesign_arm", "--order", "1,12,21"], "do not connect"),
    (["robot", "robodesign_arm", "--order", "1,21,99"], "not in module set"),
    (["robot", "robodesign_arm", "--order", ",".join(DEFAULT_ORDER), "--q", "1,2"], "--q: the robot has 6 joints"),
    (["robot", "robodesign_arm", "--order", ",".join(DEFAULT_ORDER), "--q", "1,2,nan,4,5,6"], "entry 2 is not finite"),
    (["robot", "nosuchset", "--order", "1"], "nosuchset: no such module set"),
    (["robot", "robodesign_arm", "--order", "1,21", "--base-pose", "1,2"], "--base-pose: expected 3"),
])
def test_bad_input_exit_2_one_line(capsys, args, msg):
    code, out, err = run(capsys, *args)
    assert code == 2 and msg in err and "Traceback" not in err and err.count("\n") == 1


PANDA = TASKS.parent / "urdf" / "panda" / "urdf" / "panda.urdf"


@pytest.mark.parametrize("name,modules,order,base", [
    ("PTP_3", IMPROV, "1,21,4,22,5,23,12", None),
    # PTP_1's goals point the tool up 0.71 m from a base between them: beyond IMPROV arms, fine for the Panda
    # (imported from its URDF as a one-module set); PTP_1 leaves the base pose free
    ("PTP_1", PANDA, "panda", "1.5,1.5,2.7"),
])
def test_solve_check_round_trip_on_cobra_tasks(capsys, tmp_path, name, modules, order, base):
    task = TASKS / "simple" / f"{name}.json"
    sol = tmp_path / f"{name}.json"
    extra = ["--base-pose", base] if base else []
    code, out, _ = run(capsys, "solve", task, "--modules", modules, "--order", order, "--seed", 1, "--out", sol,
                       "--json", *extra)
    res = json.loads(out)
    assert code == 0 and res["feasible"], res
    code, out, _ = run(capsys, "check", task, sol, "--modules", modules, "--json")
    v = json.loads(out)
    assert code == 0 and v["valid"] and v["violations"] == []
    assert v["cost"] == pytest.approx(res["cost"]) and v["costs"]["cyc"] == pytest.approx(res["costs"]["cyc"])
    assert set(v["costs"]) >= {"cyc", "mechEnergy", "linkMechEnergy", "qDist", "effort", "mass", "numJ",
                               "fulfillN", "fulfillP", "Liu2", "Whit2"}
    # the same file, one sample pushed beyond the first joint's limit: invalid, exit 1, the violation named
    d = json.loads(sol.read_text())
    d["trajectory"]["q"][5][0] = 3.5
    bad = tmp_path / f"{name}_bad.json"
    bad.write_text(json.dumps(d))
    code, out, _ = run(capsys, "check", task, bad, "--modules", modules, "--json")
    v = json.loads(out)
    assert code == 1 and not v["valid"]
    assert any(x["constraint"] == "joint.q" and x["sample"] == 5 and x["joint"] == 0 for x in v["violations"])


def test_check_bad_files_exit_2(capsys, tmp_path):
    task = TASKS / "simple" / "PTP_1.json"
    f = tmp_path / "broken.json"
    f.write_text('{"taskID": "simple/PTP_1", ')
    code, _, err = run(capsys, "check", task, f, "--modules", IMPROV)
    assert code == 2 and "broken.json: malformed JSON at line 1" in err
    code, _, err = run(capsys, "check", task, tmp_path / "missing.json", "--modules", IMPROV)
    assert code == 2 and "missing.json: file not found" in err
    f.write_text(json.dumps({"taskID": "simple/PTP_1", "costFunction": "cyc", "trajectory": {"t": [0.0], "q": [["a"]]}}))
    code, _, err = run(capsys, "check", task, f, "--modules", IMPROV)
    assert code == 2 and "broken.json: trajectory.q[0][0]" in err


def test_optimizers_lists_the_five_plugins(capsys):
    code, out, _ = run(capsys, "optimizers", "--json")
    assert code == 0 and {"random", "genetic", "elimination", "heuristic", "optuna", "base_pose"} <= set(json.loads(out))


def test_optimize_base_pose_cli(capsys, tmp_path):
    """The base of a fixed design on robodesign/base_placement: the best of 6 evaluations (the nominal base
    first) is reported with its checked solution; bad plugin options are one-line errors with exit code 2."""
    order = "2,5,21,22,21,11,22,4,21,5,22,14"
    out_file = tmp_path / "best.json"
    code, out, _ = run(capsys, "optimize", "robodesign/base_placement", "--modules", "robodesign_arm",
                       "--optimizer", "base_pose", "--opt", f"order={order}", "--budget", "6evals",
                       "--out", out_file, "--json")
    d = json.loads(out)
    assert code == 0 and d["evaluations"] == 6 and d["best"]["order"] == order.split(",")
    assert len(d["best"]["base"]) == 3 and abs(d["best"]["base"][0]) <= 0.4 and abs(d["best"]["base"][1]) <= 0.4
    code, out, _ = run(capsys, "check", "robodesign/base_placement", out_file, "--modules", "robodesign_arm", "--json")
    assert code == 0 and json.loads(out)["cost"] == d["best"]["cost"]
    code, _, err = run(capsys, "optimize", "robodesign/base_placement", "--modules", "robodesign_arm",
                       "--optimizer", "base_pose", "--budget", "2evals")
    assert code == 2 and err.startswith("robodesign: error: optimizer 'base_pose': option 'order' is required")
    code, _, err = run(capsys, "optimize", "robodesign/base_placement", "--modules", "robodesign_arm",
                       "--optimizer", "base_pose", "--opt", "order=1,21,12", "--budget", "2evals")
    assert code == 2 and "order 1,21,12: module '12' may not follow" in err and "Traceback" not in err
