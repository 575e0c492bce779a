"""The diagnosis of unsolved tasks in `robodesign optimize` (text and --json) and in the suite summary
(solved / provably out of reach / not found per task and per family; docs/diagnosis.md)."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from robodesign.cli.entry import main
from robodesign.design.reach import set_reach
from robodesign.design.search_space import SearchSpace
from robodesign.experiment.suites import Diagnoser, SuiteRecord, markdown, summarize_suites, task_rows, unsolved_rows
from robodesign.formats.module_io import load_module_set

from test_reach_bound import reach_task_json  # noqa: E402

FIXED = {"x": [-1e-3, 1e-3], "y": [-1e-3, 1e-3], "z": [-1e-3, 1e-3]}


def _task_file(path, goals, base=FIXED):
    path.write_text(json.dumps(reach_task_json(goals, base, path.stem, [{"type": "allGoalsFulfilled"}])))
    return path


def test_optimize_says_provably_out_of_reach(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)  # optimize journals its search beside its output file
    R = set_reach(SearchSpace(load_module_set("robodesign_arm"))).bound
    assert R == pytest.approx(5.422)
    f = _task_file(tmp_path / "far.json", [(0.5, 0.0, 0.3), (7.0, 0.0, 0.0)])
    code = main(["optimize", str(f), "--modules", "robodesign_arm", "--optimizer", "random", "--budget", "4evals",
                 "--json"])
    cap = capsys.readouterr()
    out = json.loads(cap.out)
    assert code == 1 and not out["feasible"], out
    d = out["diagnosis"]
    assert d["verdict"] == "out_of_reach" and d["label"] == "provably out of reach"
    # 7 m from a base held within ±1 mm, minus the base box (1 mm along x) and the goal's corner (√3 mm)
    assert d["proof"]["needed"] == pytest.approx(7.0 - 1e-3 - math.sqrt(3) * 1e-3, abs=1e-9)
    assert d["proof"]["bound"] == pytest.approx(R) and d["proof"]["goals"] == ["g1"]
    assert main(["optimize", str(f), "--modules", "robodesign_arm", "--optimizer", "random",
                 "--budget", "4evals"]) == 1
    text = capsys.readouterr().out
    assert "diagnosis    provably out of reach: goal g1 is at least 6.997 m from every allowed base position; " \
           "the longest arm of the module set reaches at most 5.422 m from its base" in text


def test_optimize_not_found_names_the_best_stage(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    # reachable in principle (well within the bound), but 3 random designs at a fixed base find nothing
    f = _task_file(tmp_path / "hard.json", [(1.9, 0.0, -0.5), (-1.9, 0.0, -0.5)])
    code = main(["optimize", str(f), "--modules", "robodesign_arm", "--optimizer", "random", "--budget", "3evals",
                 "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 1
    d = out["diagnosis"]
    assert d["verdict"] in ("not_found", "torque") and d["label"] == "not found" and d["proof"] is None
    assert d["best_stage"] == out["stopped_at"] and d["evaluations"] == 3
    assert d["reach_bound"] == pytest.approx(5.422)


def test_suite_summary_counts_each_class(tmp_path):
    far = _task_file(tmp_path / "far.json", [(0.0, 0.0, 0.5), (9.0, 0.0, 0.0)])
    free = _task_file(tmp_path / "free.json", [(0.0, 0.0, 0.5), (9.0, 0.0, 0.0)], base=None)
    apart = _task_file(tmp_path / "apart.json", [(0.0, 0.0, 0.5), (0.0, 12.0, 0.5)], base=None)
    problems = {n: {"name": n, "task": str(f), "modules": "robodesign_arm", "cost": "cyc",
                    "rules": {"min_dof": 6, "max_dof": 6}} for n, f in (("far", far), ("free", free), ("apart", apart))}
    diag = Diagnoser(problems)
    rows = [{"feasible": False, "stage": "reach", "stage_index": 2, "message": "goal g1 is far", "cost": None}]
    recs = [SuiteRecord("fam", "solved1", "random", 0, True, best=3.0, verdict="solved"),
            diag(SuiteRecord("fam", "far", "random", 0, False, stopped_at="reach"), rows),
            diag(SuiteRecord("fam", "free", "random", 0, False, stopped_at="reach"), rows),
            diag(SuiteRecord("fam", "apart", "random", 0, False, stopped_at="reach"), rows)]
    assert [r.verdict for r in recs] == ["solved", "out_of_reach", "not_found", "out_of_reach"]
    assert [r.result for r in recs] == ["solved", "provably out of reach", "not found", "provably out of reach"]
    assert recs[3].diagnosis.startswith("provably out of reach: goals g0 and g1 are 12.000 m apart, so one of them is "
                                       "at least 5.998 m from any base")
    (s,) = summarize_suites(recs)
    assert (s["runs"], s["solved"], s["out_of_reach"], s["not_found"]) == (4, 1, 2, 1)
    assert s["solved_pct"] == pytest.approx(25.0) and s["solved_pct_reachable"] == pytest.approx(50.0)
    tasks = task_rows(recs)
    assert [t["reach_bound"] for t in tasks[1:]][0] == pytest.approx(5.422)
    assert math.isnan(tasks[2]["reach_bound"]) and tasks[0]["best_cost"] == 3.0
    md = markdown([s], unsolved_rows(recs), tasks)
    assert "| fam | far | random | 0 | provably out of reach | – | 5.422 |" in md
    assert "| fam | free | random | 0 | not found | – | – | not found: the search ran out of budget" in md



def test_torque_verdict_reads_the_pipelines_own_message(tmp_path):
    """A real static_torque failure: robodesign_arm with its shoulder pitch joint (module 22) limited to 5 Nm.
    The pipeline's own message is parsed into the torque the pose needs; the shortfall is that minus 5 Nm."""
    from robodesign.core.paths import builtin_module_sets
    from robodesign.design.diagnosis import diagnose, torque_shortfall
    from robodesign.design.problem import Problem
    from robodesign.design.solve import solve

    data = json.loads((builtin_module_sets()["robodesign_arm"] / "modules.json").read_text())
    for m in data["modules"]:
        if m["header"]["ID"] == "22":
            m["joints"][0]["limits"]["peakTorque"] = 5.0
    weak = tmp_path / "weak"
    weak.mkdir()
    (weak / "modules.json").write_text(json.dumps(data))
    (weak / "meshes").symlink_to(builtin_module_sets()["robodesign_arm"] / "meshes")
    task = _task_file(tmp_path / "near.json", [(0.6, 0.0, 0.4)])
    prob = Problem.build(task, weak, "cyc")
    res = solve(prob.task, prob.module_set, ["1", "21", "22", "4", "22", "3", "23", "24", "23", "12"], np.eye(4))
    assert res.stage == "static_torque"
    need, limit, joint = torque_shortfall(res.message)
    assert limit == 5.0 and joint in (1, 2) and need > 5.0
    d = diagnose(prob, [{"feasible": False, "stage": res.stage, "stage_index": res.stage_index,
                         "message": res.message}])
    assert d.verdict == "torque" and d.torque_shortfall == pytest.approx(need - 5.0)


def test_run_suite_report_lists_each_task_with_its_class(tmp_path, capsys):
    """`robodesign run` on a folder suite with a provably out-of-reach task: suites.csv counts it, suites_tasks.csv
    and suites.md list it with the set's reach bound, and the printed suite line says so."""
    import csv
    tasks = tmp_path / "tasks"
    tasks.mkdir()
    _task_file(tasks / "far.json", [(0.0, 0.0, 0.5), (8.0, 0.0, 0.0)])
    _task_file(tasks / "near.json", [(0.5, 0.2, 0.4)])
    cfg = tmp_path / "suite.yaml"
    cfg.write_text("name: diag\nmodules: robodesign_arm\nsuites:\n  - name: cells\n    folder: tasks\n"
                   "optimizers: [random]\nbudget: 2evals\nseeds: [0]\n")
    out = tmp_path / "out"
    assert main(["run", str(cfg), "--out", str(out), "--progress", "none"]) == 0
    printed = capsys.readouterr().out
    with open(out / "suites.csv") as f:
        (s,) = list(csv.DictReader(f))
    with open(out / "suites_tasks.csv") as f:
        rows = {r["task"]: r for r in csv.DictReader(f)}
    assert (int(s["runs"]), int(s["out_of_reach"])) == (2, 1)
    assert int(s["solved"]) + int(s["not_found"]) == 1
    far = rows["cells/far"]
    assert far["result"] == "provably out of reach" and float(far["reach_bound"]) == pytest.approx(5.422)
    assert far["diagnosis"].startswith("provably out of reach: goal g1 is at least 7.99")
    assert rows["cells/near"]["result"] in ("solved", "not found") and rows["cells/near"]["reach_bound"] == ""
    assert "| cells | cells/far | random | 0 | provably out of reach | – | 5.422 |" in (out / "suites.md").read_text()
    assert "1 provably out of reach" in printed
