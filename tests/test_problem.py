"""The Problem (task, module set, cost, search space) and the typed optimizer options.

The problem is built once by the CLI, the experiment runner and the API and handed to optimizers and
evaluators; a plugin reads the study's cost from it (no ``cost`` option), and its options are declared,
converted and validated by the base class.
"""
from __future__ import annotations

import math
import pickle
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Tuple

import pytest

from robodesign.core.errors import InputError
from robodesign.design.optimize import Optimizer, OptionError, create_optimizer, option, option_specs, parse_options
from robodesign.design.problem import Problem

ROOT = Path(__file__).resolve().parents[1]
BASE_PLACEMENT = ROOT / "assets" / "tasks" / "robodesign" / "base_placement.json"


# -- the problem ----------------------------------------------------------------------------------------------
def test_build_derives_the_base_bounds_from_the_task_once():
    """robodesign/base_placement: x, y and yaw free within the task's tolerance; base_search=False fixes them."""
    p = Problem.build("robodesign/base_placement", "robodesign_arm", "cyc")
    assert p.space.base_dims == 3 and p.base_bounds.free == (0, 1, 3)
    assert p.base_bounds.lower[:2] == (-0.4, -0.4) and p.base_bounds.upper[:2] == (0.4, 0.4)  # the file's x, y
    assert p.base_bounds.tolerance is p.task.base_placement
    fixed = Problem.build("robodesign/base_placement", "robodesign_arm", "cyc", base_search=False)
    assert fixed.space.base_dims == 0
    assert fixed.with_(base_search=True).base_bounds.free == (0, 1, 3)
    assert (fixed.base_pose(fixed.space.nominal_candidate(("1",))) == p.task.nominal_base_pose).all()
    # the candidate's base parameters are decoded by the problem: nominal pose ∘ (x, y, z, yaw) offsets
    c = p.space.nominal_candidate(("1",))
    c2 = type(c)(c.order, (0.1, -0.05, 0.2))
    T = p.base_pose(c2)
    N = p.task.nominal_base_pose
    assert T[:3, 3] == pytest.approx(N[:3, 3] + N[:3, :3] @ [0.1, -0.05, 0.0])
    assert math.atan2(T[1, 0], T[0, 0]) == pytest.approx(math.atan2(N[1, 0], N[0, 0]) + 0.2)


def test_cost_rules_and_errors():
    p = Problem.build("robodesign/pick_and_place", "robodesign_arm", "Whit2", rules={"min_dof": 5, "max_dof": 7,
                                                                                     "bases": ["1"]})
    assert p.cost_descriptor == "Whit2" and dict(p.cost.terms) == pytest.approx({"mass": 0.1, "numJ": 0.025})
    assert (p.space.min_dof, p.space.max_dof, p.space.bases) == (5, 7, ("1",))
    assert p.rules()["bases"] == ["1"]
    with pytest.raises(InputError, match=r"rules.bases\[0\]: module '12' is a eef module, not a base module"):
        Problem.build("robodesign/pick_and_place", "robodesign_arm", rules={"bases": ["12"]})
    with pytest.raises(InputError, match="unknown search-space rule 'dofs'"):
        Problem.build("robodesign/pick_and_place", "robodesign_arm", rules={"dofs": 6})
    with pytest.raises(InputError, match="unknown cost"):
        Problem.build("robodesign/pick_and_place", "robodesign_arm", "cyk")
    with pytest.raises(InputError, match="min_dof"):
        Problem.build("robodesign/pick_and_place", "robodesign_arm", rules={"min_dof": 7, "max_dof": 6})
    q = p.with_(cost="mass")
    assert q.cost_descriptor == "mass" and q.space is p.space and p.cost_descriptor == "Whit2"  # immutable
    with pytest.raises(Exception):
        p.cost = q.cost  # frozen


def test_pickles_as_references_and_fingerprints_what_changes_a_score():
    p = Problem.build("robodesign/base_placement", "robodesign_arm", "cyc", rules={"min_dof": 6, "max_dof": 7})
    data = pickle.dumps(p)
    assert len(data) < 5000  # the references, cost, rules and bounds; not the module set
    q = pickle.loads(data)
    assert q.task is p.task and q.module_set is p.module_set  # loaded once per process
    assert q.fingerprint() == p.fingerprint() and q.rules() == p.rules()
    assert q.base_bounds.free == p.base_bounds.free and q.space.max_dof == 7
    assert p.with_(cost="Whit2").fingerprint() != p.fingerprint()
    assert p.with_(base_search=False).fingerprint() != p.fingerprint()
    assert p.with_(rules={"min_dof": 6, "max_dof": 6}).fingerprint() == p.fingerprint()  # rules do not score
    assert p.to_json()["base_bounds"]["free"] == [0, 1, 3]


# -- typed options --------------------------------------------------------------------------------------------
class _Toy(Optimizer):
    name = "toy"

    @dataclass(frozen=True)
    class Options:
        size: int = option(20, low=2, help="a size")
        rate: float = option(0.5, low=0.0, high=1.0)
        flag: bool = option(False)
        limit: Optional[int] = option(None, low=1)
        mode: str = option("a", choices=("a", "b"))
        order: Tuple[str, ...] = option(("1", "2"))

    def ask(self):
        return None


def test_options_are_converted_from_cli_strings_and_yaml_values():
    o = parse_options(_Toy, {"size": "12", "rate": 1, "flag": "yes", "limit": "none", "mode": "b", "order": "1,21, 12"})
    assert (o.size, o.rate, o.flag, o.limit, o.mode, o.order) == (12, 1.0, True, None, "b", ("1", "21", "12"))
    o = parse_options(_Toy, {"size": 3.0, "flag": False, "limit": 4, "order": [1, 21]})
    assert (o.size, o.flag, o.limit, o.order, o.rate) == (3, False, 4, ("1", "21"), 0.5)  # rate: its default
    assert [s.name for s in option_specs(_Toy)] == ["size", "rate", "flag", "limit", "mode", "order"]


@pytest.mark.parametrize("options, message", [
    ({"siz": 3}, "unknown option 'siz' (did you mean 'size'?)"),
    ({"size": 1}, "option 'size': 1 is not ≥ 2"),
    ({"size": "many"}, "option 'size': expected int, got 'many'"),
    ({"size": 2.5}, "option 'size': expected int"),
    ({"size": True}, "option 'size': expected int"),
    ({"rate": 1.5}, "option 'rate': 1.5 is not in [0.0, 1.0]"),
    ({"rate": "nan"}, "option 'rate': expected float"),
    ({"flag": "maybe"}, "option 'flag': expected bool"),
    ({"mode": "c"}, "option 'mode': 'c' is not one of a, b"),
])
def test_bad_options_are_one_error_listing_the_valid_ones(options, message):
    with pytest.raises(OptionError) as e:
        _Toy(Problem.build("robodesign/pick_and_place", "robodesign_arm"), **options)
    assert str(e.value).startswith(f"optimizer 'toy': {message}")
    assert str(e.value).endswith("(valid options: size (int, default 20, ≥ 2), rate (float, default 0.5, in [0.0, "
                                 "1.0]), flag (bool, default false), limit (int or none, default none, ≥ 1), mode "
                                 "(str, default a, one of a|b), order (comma-separated strs, default 1,2))")
    assert e.value.option == next(iter(options))


def test_every_first_party_option_table_is_declared():
    """The docstring defaults of the first-party plugins are what `robodesign optimizers --verbose` shows."""
    from robodesign.design.optimize import load_optimizer
    specs = {n: {s.name: s for s in option_specs(load_optimizer(n))}
             for n in ("random", "genetic", "elimination", "heuristic", "optuna", "base_pose")}
    assert specs["genetic"]["population_size"].default == 20 and specs["genetic"]["population_size"].low == 2
    assert specs["elimination"]["order_by"].choices == ("bound", "enumeration")
    assert specs["base_pose"]["order"].required
    assert "cost" not in specs["elimination"] and "cost" not in specs["heuristic"]


# -- the study's cost reaches the bound-pruning plugins without any option ---------------------------------------
def test_elimination_bounds_with_the_problems_cost():
    """elimination's first candidate is the lightest order (bound order for Whit2 = 0.025·numJ + 0.1·mass)."""
    rules = {"min_dof": 3, "max_dof": 3, "bases": ["1"], "end_effectors": ["12"],
             "exclude": ["4", "5", "6", "7", "8", "9", "10", "11", "15"]}
    p = Problem.build("robodesign/pick_and_place", "robodesign_arm", "Whit2", rules=rules, base_search=False)
    opt = create_optimizer("elimination", p)
    assert opt.cost is p.cost and opt.use_bound and opt.order_by == "bound"
    first = opt.ask()
    sp = p.space
    lightest = min(sp.enumerate_orders(), key=lambda o: sum(sp.module_info(m).mass for m in o))
    assert sum(sp.module_info(m).mass for m in first.order) == pytest.approx(sum(sp.module_info(m).mass
                                                                                 for m in lightest))
    assert sp.cost_lower_bound(first.order, p.cost) == pytest.approx(
        0.025 * 3 + 0.1 * sum(sp.module_info(m).mass for m in lightest))
    # with a cost whose bound is -inf (a reward: negative weight on fulfillN) it enumerates instead
    assert create_optimizer("elimination", p.with_(cost="cyc,fulfillN_-1")).order_by == "enumeration"


def test_experiment_gives_elimination_the_cost_without_a_config_line(tmp_path):
    from robodesign.experiment.config import load_experiment
    cfg = tmp_path / "x.yaml"
    cfg.write_text("tasks: [robodesign/pick_and_place]\nmodules: robodesign_arm\ncost: Whit2\n"
                   "optimizers: [elimination, {name: genetic, options: {population_size: '8'}}]\n")
    exp, _ = load_experiment(cfg)
    (entry,) = exp.problems
    assert entry.problem.cost_descriptor == "Whit2" and entry.to_json()["fingerprint"] == entry.problem.fingerprint()
    opt = create_optimizer("elimination", entry.problem)
    assert opt.cost is entry.problem.cost and opt.use_bound
    spec = exp.evaluator_specs()[exp.spec_id(entry, 0)]
    assert spec.problem is entry.problem


def test_a_config_option_typo_names_file_and_field(tmp_path):
    from robodesign.experiment.config import load_experiment
    cfg = tmp_path / "typo.yaml"
    cfg.write_text("tasks: [robodesign/pick_and_place]\noptimizers:\n  - random\n"
                   "  - {name: genetic, options: {populaton_size: 12}}\n")
    with pytest.raises(InputError) as e:
        load_experiment(cfg)
    assert str(e.value).startswith(f"{cfg}: optimizers[1].options.populaton_size: optimizer 'genetic': unknown option "
                                   "'populaton_size' (did you mean 'population_size'?) (valid options: population_size")


def _cli(*args):
    env = {"PYTHONPATH": f"{ROOT / 'src'}:{ROOT / 'optimizers'}", "PATH": "/usr/bin:/bin"}
    return subprocess.run([sys.executable, "-m", "robodesign.cli", *args], capture_output=True, text=True, env=env,
                          timeout=300)


def test_cli_rejects_a_misspelt_option_and_lists_options():
    r = _cli("optimize", "robodesign/pick_and_place", "--modules", "robodesign_arm", "--optimizer", "genetic",
             "--opt", "populaton_size=12", "--budget", "2evals")
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr
    assert "unknown option 'populaton_size' (did you mean 'population_size'?)" in r.stderr
    r = _cli("optimizers", "--verbose")
    assert r.returncode == 0
    assert "    --opt population_size (int, default 20, ≥ 2): individuals per generation" in r.stdout
    assert "    --opt order (comma-separated strs, required): the module order" in r.stdout


# -- the problem in the results store ------------------------------------------------------------------------------
def test_fingerprint_follows_file_contents_not_paths(tmp_path):
    import json
    src = json.loads(BASE_PLACEMENT.read_text())
    a = tmp_path / "a" / "robodesign" / "base_placement.json"
    b = tmp_path / "b" / "robodesign" / "base_placement.json"
    for f in (a, b):
        f.parent.mkdir(parents=True)
        f.write_text(json.dumps(src))
        (f.parent.parent / "assets").symlink_to(BASE_PLACEMENT.parents[1] / "assets")
    pa, pb = (Problem.build(f, "robodesign_arm", "cyc") for f in (a, b))
    assert pa.task_ref != pb.task_ref and pa.fingerprint() == pb.fingerprint()  # moved, same contents
    src["goals"][0]["goalPose"]["tolerance"][0] = [0.0, 0.002]
    b.write_text(json.dumps(src))
    assert Problem.build(b, "robodesign_arm", "cyc").fingerprint() != pa.fingerprint()  # edited


def test_results_store_refuses_to_resume_a_changed_problem(tmp_path):
    from robodesign.design.evaluator import Evaluation
    from robodesign.experiment.storage import ExperimentDB
    p = Problem.build("robodesign/pick_and_place", "robodesign_arm", "cyc")
    db = ExperimentDB(tmp_path / "evaluations.sqlite")
    db.ensure_run("r", "pick", "random", "random", 0, 0, "2evals", 1)
    c = p.space.random_candidate(__import__("numpy").random.default_rng(0))
    ev = Evaluation(candidate=c, feasible=False, cost=None, score=2e9, stage="ik", stage_index=3, goals_reached=0,
                    seconds=0.1, seed=1)
    db.storage("r", p).append(0, ev)
    assert db.info("problem:r") == p.fingerprint()
    assert [e.candidate for e in db.storage("r", p).load()] == [c]          # same problem: resumes
    with pytest.raises(InputError, match="cannot resume run 'r': its problem changed"):
        db.storage("r", p.with_(cost="Whit2")).load()
    db.close()


def test_results_store_refuses_a_run_made_under_other_evaluation_rules(tmp_path):
    """A run records the evaluation rules it was made under; a run made under others (an older robodesign's: no
    record means rules 1) is not resumed, since its remaining candidates would be evaluated differently."""
    from robodesign.design.evaluator import EVALUATION_RULES, Evaluation
    from robodesign.experiment.storage import ExperimentDB
    p = Problem.build("robodesign/pick_and_place", "robodesign_arm", "cyc")
    db = ExperimentDB(tmp_path / "evaluations.sqlite")
    c = p.space.random_candidate(__import__("numpy").random.default_rng(0))
    ev = Evaluation(candidate=c, feasible=False, cost=None, score=2e9, stage="ik", stage_index=3, goals_reached=0,
                    seconds=0.1, seed=1)
    for run in ("now", "old", "other"):
        db.ensure_run(run, "pick", "random", "random", 0, 0, "2evals", 1)
        db.storage(run, p).append(0, ev)
    assert EVALUATION_RULES >= 2 and db.info("rules:now") == str(EVALUATION_RULES)
    assert [e.candidate for e in db.storage("now", p).load()] == [c]          # same rules: resumes
    db.con.execute("DELETE FROM info WHERE key='rules:old'")                    # as an older robodesign stored it
    db.set_info("rules:other", str(EVALUATION_RULES + 1))
    for run, rules in (("old", 1), ("other", EVALUATION_RULES + 1)):
        with pytest.raises(InputError, match=f"cannot resume run '{run}': its evaluations were made under evaluation "
                                             f"rules {rules}, this robodesign evaluates under rules {EVALUATION_RULES}"):
            db.storage(run, p).load()
    db.close()


# -- the default DoF: seven joints where a pose is fixed among obstacles ----------------------------------------
PTP_3 = ROOT.parent / "shared" / "cobra" / "tasks" / "simple" / "PTP_3.json"


def _ptp3_variant(tmp_path, name, change):
    """PTP_3 (three reach goals, r_sph ≤ 1 cm and Theta_R ≤ 0.01 rad: position and orientation fixed; one
    obstacle) with ``change`` applied to its JSON, written in the CoBRA folder layout (the obstacle's mesh
    path is relative to the tasks folder: a link to the reference's assets)."""
    import json
    d = json.loads(PTP_3.read_text())
    change(d)
    f = tmp_path / name / "simple" / "PTP_3.json"
    f.parent.mkdir(parents=True)
    (tmp_path / name / "assets").symlink_to(PTP_3.parents[1] / "assets")
    f.write_text(json.dumps(d))
    return f


def _loosen(d):
    for g in d["goals"]:
        g["goalPose"]["tolerance"][1] = [0, 0.1]  # 5.7°: the orientation is no longer fixed


def test_default_dof_is_seven_for_full_pose_goals_among_obstacles(tmp_path):
    from robodesign.design.problem import default_dof
    p = Problem.build(PTP_3, "robodesign_heavy", "cyc")
    assert (p.space.min_dof, p.space.max_dof) == (7, 7)
    assert default_dof(p.task, p.cost) == (7, 7)
    # a cost that charges joints or mass lets the search weigh the seventh joint: 6 to 7
    w = Problem.build(PTP_3, "robodesign_heavy", "Whit2")
    assert (w.space.min_dof, w.space.max_dof) == (6, 7)
    assert (Problem.build(PTP_3, "robodesign_heavy", "cyc_1,mass_0.1").space.min_dof) == 6
    assert (Problem.build(PTP_3, "robodesign_heavy", "mechEnergy").space.min_dof) == 7
    # without obstacles, or with the orientation left free within 5.7°: six joints
    no_obstacles = _ptp3_variant(tmp_path, "free", lambda d: d.update(obstacles=[]))
    loose = _ptp3_variant(tmp_path, "loose", _loosen)
    for f in (no_obstacles, loose):
        q = Problem.build(f, "robodesign_heavy", "cyc")
        assert (q.space.min_dof, q.space.max_dof) == (6, 6), f
    # rules win; a one-sided rule keeps the other bound consistent with it
    assert (Problem.build(PTP_3, "robodesign_heavy", rules={"min_dof": 6, "max_dof": 6}).space.max_dof) == 6
    one = Problem.build(PTP_3, "robodesign_heavy", rules={"max_dof": 6}).space
    assert (one.min_dof, one.max_dof) == (6, 6)
    one = Problem.build(PTP_3, "robodesign_heavy", rules={"min_dof": 5}).space
    assert (one.min_dof, one.max_dof) == (5, 7)
    one = Problem.build(PTP_1_TASK, "robodesign_heavy", rules={"max_dof": 4}).space
    assert (one.min_dof, one.max_dof) == (4, 4)
    assert (p.with_(rules={"max_dof": 6}).space.min_dof, p.with_(rules={"max_links_between": 0}).space.min_dof) == (6, 7)
    # a module set without 7-joint orders (IMPROV: its connectors allow none) keeps 6, even for this task
    from robodesign.design.search_space import SearchSpace
    improv = Problem.build(PTP_3, IMPROV, "cyc")
    assert SearchSpace(improv.module_set, min_dof=7, max_dof=7).count_orders() == 0
    assert (improv.space.min_dof, improv.space.max_dof) == (6, 6)
    # the default reaches the optimizers: every candidate of a fresh search has 7 joints
    opt = create_optimizer("random", p, seed=0)
    dofs = {sum(p.module_set[m].dof for m in opt.ask().order) for _ in range(8)}
    assert dofs == {7}


IMPROV = ROOT.parent / "shared" / "cobra" / "modules" / "IMPROV"
PTP_1_TASK = ROOT.parent / "shared" / "cobra" / "tasks" / "simple" / "PTP_1.json"


def test_experiment_rules_leave_the_dof_to_the_task(tmp_path):
    """An experiment whose rules do not name the DoF gets the task's default; named ones are kept."""
    from robodesign.experiment.config import Rules
    r = Rules.model_validate({})
    assert (r.min_dof, r.max_dof) == (None, None)
    p = Problem.build(PTP_3, "robodesign_heavy", "cyc", rules=r.model_dump())
    assert (p.space.min_dof, p.space.max_dof) == (7, 7)
    p = Problem.build(PTP_3, "robodesign_heavy", "cyc", rules=Rules.model_validate({"dof": 6}).model_dump())
    assert (p.space.min_dof, p.space.max_dof) == (6, 6)
    with pytest.raises(ValueError, match="min_dof"):
        Rules.model_validate({"min_dof": 7, "max_dof": 6})
