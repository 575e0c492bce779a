"""The first-party optimizer plugins (optimizers/robodesign_optimizers) on a small enumerable search space
with a known optimum, plus the search-space methods they use.

The space: the built-in ``robodesign_arm`` set restricted to base 1, tool 12, no links except the adapter
3 and 3 DoF: 32 orders (``1,{L joints}…,3,{S joints}…,12``). The task (written to a tmp dir): two
position-only ``reach`` goals, no obstacles, fixed base. Cost ``Whit2`` (= 0.025·numJ + 0.1·mass), which
is deterministic and differs between designs. The optimum is computed by evaluating every candidate with
one shared ``Evaluator``; its cache makes the plugin runs afterwards cheap.
"""
from __future__ import annotations

import json
import math
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from robodesign.design.evaluator import Evaluation, Evaluator, EvaluatorSpec, score_of
from robodesign.design.optimize import Budget, SerialExecutor, Study, available_optimizers, load_optimizer
from robodesign.design.problem import Problem
from robodesign.design.search_space import BaseBounds, Candidate, SearchSpace
from robodesign.design.solve import STAGES
from robodesign.formats.module_io import load_module_set

PLUGINS = ("random", "genetic", "elimination", "heuristic", "optuna")
LINKS_OUT = ("4", "5", "6", "7", "8", "9", "10", "11", "15")  # every passive module except the adapter 3
RULES = dict(min_dof=3, max_dof=3, bases=("1",), end_effectors=("12",), exclude=LINKS_OUT, max_links_between=1)
COST = "Whit2"
OPTIONS = {  # per plugin, for the small space
    "random": {"max_duplicates": 2000},
    "genetic": {"population_size": 8},
    "elimination": {},
    "heuristic": {"beam_width": 4},
    "optuna": {"n_startup_trials": 8},
}


def _T(x, y, z):
    return [[1, 0, 0, x], [0, 1, 0, y], [0, 0, 1, z], [0, 0, 0, 1]]


def write_task(path: Path, goals) -> Path:
    """A task with position-only reach goals (r_sph ≤ 2 cm), no obstacles, a fixed base at the origin."""
    task = {
        "header": {"ID": f"test/{path.stem}", "version": "2022", "taskName": path.stem, "author": ["robodesign tests"],
                   "affiliation": ["robodesign"], "email": ["tests@robodesign.invalid"], "tags": ["test"],
                   "date": "2024-01-01", "timeStepSize": 0.01, "gravity": [0, 0, -9.81]},
        "obstacles": [],
        "constraints": [{"type": "joint", "parts": ["q", "dq", "tau"]}, {"type": "selfCollisionFree"},
                        {"type": "allGoalsFulfilled"}, {"type": "basePlacement", "pose": {"nominal": _T(0, 0, 0)}}],
        "goals": [{"ID": str(i + 1), "type": "reach",
                   "goalPose": {"nominal": _T(*g), "toleranceProjection": ["r_sph"], "tolerance": [[0.0, 0.02]]}}
                  for i, g in enumerate(goals)],
    }
    path.write_text(json.dumps(task, indent=1))
    return path


def _bench(folder: Path, goals):
    problem = Problem.build(write_task(folder / "task.json", goals), "robodesign_arm", COST, rules=RULES)
    ev = Evaluator(EvaluatorSpec(problem, seed=0))
    space = problem.space
    cands = [space.nominal_candidate(o) for o in space.enumerate_orders()]
    t0 = time.perf_counter()
    evals = {c.key(): ev(c) for c in cands}
    best = min(evals.values(), key=lambda e: e.score)
    return SimpleNamespace(ev=ev, problem=problem, space=space, cands=cands, evals=evals, best=best,
                           seconds=time.perf_counter() - t0)


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    """Several feasible designs of different cost; the optimum is not the lightest order of the space."""
    return _bench(tmp_path_factory.mktemp("two_reach"), [(0.3, 0.2, 0.45), (-0.2, 0.25, 0.55)])


@pytest.fixture(scope="module")
def far_bench(tmp_path_factory):
    """Farther goals: many orders fail at the reach stage (for the reach-pruning rule)."""
    return _bench(tmp_path_factory.mktemp("far_reach"), [(0.3, 0.2, 0.5), (-0.2, 0.3, 0.6)])


def run(bench, name, seed=0, budget=None, **options):
    opts = {**OPTIONS.get(name, {}), **options}
    opt = load_optimizer(name)(bench.problem, seed=seed, **opts)
    study = Study(opt, SerialExecutor(bench.ev), Budget(evaluations=budget or len(bench.cands)))
    return opt, study.run()


# -- the benchmark space ---------------------------------------------------------------------------------
def test_space_has_a_known_optimum(bench):
    sp = bench.space
    assert sp.base_dims == 0
    assert len(bench.cands) == sp.count_orders() == 32
    assert all(sp.validate_order(c.order) is None for c in bench.cands)
    feasible = sorted(e.score for e in bench.evals.values() if e.feasible)
    assert len(feasible) >= 3 and feasible[0] < feasible[1]  # several feasible designs, a unique optimum
    assert bench.best.feasible
    # Whit2 = 0.025·numJ + 0.1·mass: the cost of a feasible design is fixed by its order
    mass = sum(sp.module_info(m).mass for m in bench.best.candidate.order)
    assert bench.best.cost == pytest.approx(0.025 * 3 + 0.1 * mass)
    assert bench.best.costs["mass"] == pytest.approx(mass)
    # the lightest order of the space is infeasible: a search must learn from failures
    lightest = min(bench.cands, key=lambda c: sp.cost_lower_bound(c.order, COST))
    assert not bench.evals[lightest.key()].feasible


def test_all_plugins_are_installed():
    assert set(PLUGINS) <= set(available_optimizers())


# -- every plugin finds the optimum, deterministically ------------------------------------------------------
@pytest.mark.parametrize("name", PLUGINS)
def test_plugin_finds_the_optimum_deterministically(bench, name):
    opt, res = run(bench, name)
    keys = [e.candidate.key() for e in res.history]
    assert res.best.score == bench.best.score
    assert res.best.candidate == bench.best.candidate
    assert len(keys) == len(set(keys)), "a candidate was asked twice"
    assert all(bench.space.validate(e.candidate) is None for e in res.history)
    opt2, res2 = run(bench, name)
    assert [e.candidate.key() for e in res2.history] == keys  # same seed → same sequence
    if name in ("elimination", "heuristic"):  # informed: fewer evaluations than the space size
        assert res.stopped == "exhausted" and len(keys) < len(bench.cands)


@pytest.mark.parametrize("name", ["genetic", "heuristic", "optuna"])
def test_seed_changes_the_sequence(bench, name):
    _, a = run(bench, name, seed=0, budget=10)
    _, b = run(bench, name, seed=1, budget=10)
    assert [e.candidate.key() for e in a.history] != [e.candidate.key() for e in b.history]


# -- elimination ------------------------------------------------------------------------------------------------
def test_elimination_exhausts_and_returns_none(bench):
    for opts in ({}, {"cost_bound": False}, {"order_by": "enumeration"}):
        opt, res = run(bench, "elimination", budget=10 * len(bench.cands), **opts)
        assert res.stopped == "exhausted"
        assert res.best.candidate == bench.best.candidate
        assert opt.ask() is None and opt.ask() is None
        if opts.get("cost_bound") is False:  # no bound: every order is evaluated, once
            assert len(res.history) == len(bench.cands)


def test_elimination_bound_order(bench):
    """In bound order the orders come lightest first; the first feasible one is the optimum and ends the run."""
    opt, res = run(bench, "elimination")
    lbs = [bench.space.cost_lower_bound(e.candidate.order, COST) for e in res.history]
    assert lbs == sorted(lbs)
    assert [e.feasible for e in res.history].index(True) == len(res.history) - 1
    assert opt.pruned["bound"] >= 1


def test_elimination_reach_pruning_is_sound(far_bench):
    """Every candidate skipped by the reach rule does fail at the reach stage; the optimum is still found."""
    b = far_bench
    assert sum(e.stage == "reach" for e in b.evals.values()) >= 8
    for opts in ({}, {"cost_bound": False}):
        opt, res = run(b, "elimination", budget=100, keep_pruned=True, **opts)
        assert res.stopped == "exhausted" and res.best.candidate == b.best.candidate
        reach = [k for k, rule in opt.pruned_candidates if rule == "reach"]
        assert len(reach) >= 3
        assert all(b.evals[k].stage == "reach" for k in reach)
        if opts:  # without the bound every order is either evaluated or pruned
            assert len(res.history) + len(opt.pruned_candidates) == len(b.cands)
    _, res = run(b, "elimination", budget=100, cost_bound=False, reach_pruning=False)
    assert len(res.history) == len(b.cands)


def test_elimination_base_grid():
    """base_grid=k: the nominal base first, then the k^d grid over the free base dims (valid points only)."""
    ms = load_module_set("robodesign_arm")
    bb = BaseBounds(lower=(-0.2, -0.1, 0.0, 0.0), upper=(0.2, 0.1, 0.0, 0.0))
    sp = SearchSpace(ms, base_bounds=bb, **RULES)
    opt = load_optimizer("elimination")(_problem(sp), seed=0, base_grid=3)
    first = [opt.ask() for _ in range(10)]
    assert first[0].order == first[8].order and first[9].order != first[0].order
    assert first[0].base == (0.0, 0.0)
    assert {c.base for c in first[:9]} == {(x, y) for x in (-0.2, 0.0, 0.2) for y in (-0.1, 0.0, 0.1)}


def test_elimination_reach_rule_swallows_only_assembly_errors(monkeypatch):
    """An order that does not assemble gives no reach bound (the evaluation reports it); any other error
    from the reach bound is a bug and propagates instead of being taken for "no bound"."""
    from robodesign.core.errors import AssemblyError
    sp = SearchSpace(load_module_set("robodesign_arm"), **RULES)
    opt = load_optimizer("elimination")(_problem(sp), seed=0)
    c = sp.nominal_candidate(next(iter(sp.enumerate_orders())))

    def broken(space, candidate):
        raise RuntimeError("a bug in the reach bound")
    monkeypatch.setattr(SearchSpace, "reach_bound", broken)
    with pytest.raises(RuntimeError, match="a bug in the reach bound"):
        opt._reach(c)
    assert c.key() not in opt._reach_cache

    def unassembled(space, candidate):
        raise AssemblyError("module order is empty")
    monkeypatch.setattr(SearchSpace, "reach_bound", unassembled)
    assert opt._reach(c) == (None, None) and opt._reach_dominated(c) is False


# -- heuristic ----------------------------------------------------------------------------------------------------
def test_heuristic_without_cost_is_complete(bench):
    """Without a cost bound (f = 0) the learned ranking drives the beam; widening makes it exhaustive."""
    opt, res = run(bench, "heuristic", budget=100, cost_bound=False, beam_width=2)
    assert res.stopped == "exhausted" and len(res.history) == len(bench.cands)
    assert res.best.candidate == bench.best.candidate
    assert opt.ask() is None


# -- optuna -------------------------------------------------------------------------------------------------------
def test_optuna_nsga2_multi_objective(bench):
    opt, res = run(bench, "optuna", multi_objective=True, population_size=8)
    assert res.best.score == bench.best.score
    front = opt.study.best_trials
    assert front and all(len(t.values) == 2 for t in front)
    assert all(t.constraints["infeasibility"] == 0 for t in front)  # infeasible designs never make the front
    assert all(t.values[0] == bench.best.score for t in front)       # here Whit2 grows with the mass
    _, res2 = run(bench, "optuna", multi_objective=True, population_size=8)
    assert [e.candidate.key() for e in res2.history] == [e.candidate.key() for e in res.history]
    # conditional encoding: one categorical parameter per position, named m0, m1, … (m{i}.{k} for other choice sets)
    names = {n for t in opt.study.trials for n in t.params}
    assert {"m0", "m1", "m2"} <= names and all(n.startswith("m") for n in names)


# -- orders and base poses together (synthetic evaluations: fast, free base dims) -----------------------------------
def _problem(space: SearchSpace, cost: str = COST) -> Problem:
    """A problem over a hand-made search space (its task is never evaluated: the evaluations are synthetic)."""
    from robodesign.formats.costs import parse_cost
    from robodesign.formats.task_io import load_task
    return Problem(task=load_task("robodesign/pick_and_place"), module_set=space.module_set, cost=parse_cost(cost),
                   space=space)


def _synthetic(space):
    """Feasible iff the order holds a pitch joint (22 or 24); cost = mass/10 + distance of (x, y) to (0.1, -0.05)
    (the distance is 0 only off the nominal base and off the elimination grid)."""
    def evaluate(c: Candidate) -> Evaluation:
        feasible = any(m in ("22", "24") for m in c.order)
        x, y = c.base
        cost = 0.1 * sum(space.module_info(m).mass for m in c.order) + math.hypot(x - 0.1, y + 0.05)
        si = len(STAGES) if feasible else STAGES.index("ik")
        return Evaluation(candidate=c, feasible=feasible, cost=cost if feasible else None,
                          score=score_of(feasible, cost, si, 0), stage="done" if feasible else "ik", stage_index=si,
                          goals_reached=0, seconds=0.0, seed=0)
    return evaluate


@pytest.mark.parametrize("name", PLUGINS)
def test_orders_and_base_poses_together(name):
    ms = load_module_set("robodesign_arm")
    bb = BaseBounds(lower=(-0.2, -0.2, 0.0, 0.0), upper=(0.2, 0.2, 0.0, 0.0))
    sp = SearchSpace(ms, base_bounds=bb, **RULES)
    assert sp.base_dims == 2
    opts = {**OPTIONS[name], **({"base_grid": 3} if name == "elimination" else {})}
    problem = _problem(sp, "mass_0.1")  # the mass term of the synthetic cost: its bound is a valid lower bound

    def go():
        opt = load_optimizer(name)(problem, seed=3, **opts)
        return Study(opt, SerialExecutor(_synthetic(sp)), Budget(evaluations=60)).run()

    res = go()
    keys = [e.candidate.key() for e in res.history]
    assert len(set(keys)) == len(keys) and (len(keys) == 60 or res.stopped == "exhausted")
    assert all(sp.validate(e.candidate) is None for e in res.history)
    assert len({e.candidate.base for e in res.history}) > 3 and len({e.candidate.order for e in res.history}) > 3
    assert res.best.feasible
    assert [e.candidate.key() for e in go().history] == keys


# -- the search-space methods the plugins use -----------------------------------------------------------------------
def test_successors_follow_free_connectors():
    """After the L→S adapter only size-S modules may follow (the adapter's free connector is its S flange)."""
    ms = load_module_set("robodesign_arm")
    sp = SearchSpace(ms)
    after = set(sp.successors(("1", "21", "3")))
    assert after and all(ms[m].connectors[0].size == (0.075,) or "S" in ms[m].name for m in after)
    assert "21" not in after and "22" not in after and "23" in after
    assert sp.count_orders() == 87495424  # the number in assets/modules/robodesign_arm/README.md
    rng = np.random.default_rng(0)
    for order in [sp.random_order(rng) for _ in range(20)]:
        assert sp.validate_order(order) is None


def test_one_chaining_rule_for_orders_and_assemblies():
    """The search space and Assembly.from_order apply one rule (assembly.chain_step): extending a valid order by any
    module assembles iff chain_step attaches it (robodesign_arm and the IMPROV set)."""
    from conftest import IMPROV

    from robodesign.core.errors import AssemblyError
    from robodesign.formats.assembly import Assembly, chain_step, free_connectors
    for ms in (load_module_set("robodesign_arm"), load_module_set(IMPROV)):
        sp = SearchSpace(ms, min_dof=1, max_dof=7, max_links_between=2)
        rng = np.random.default_rng(1)
        checked = 0
        for _ in range(6):
            order = sp.random_order(rng)
            for n in range(1, len(order)):
                prefix = order[:n]
                free = free_connectors(ms, prefix[0])
                for prev, mid in zip(prefix, prefix[1:]):
                    free = chain_step(ms, prev, free, mid)
                for m in ms:
                    if m.kind == "base":
                        continue
                    try:
                        Assembly.from_order(ms, prefix + (m.id,))
                        assembles = True
                    except AssemblyError:
                        assembles = False
                    assert assembles == (chain_step(ms, prefix[-1], free, m.id) is not None), (prefix, m.id)
                    checked += 1
        assert checked > 500


def test_counts_and_bounds_match_brute_force(bench):
    sp = bench.space
    orders = [c.order for c in bench.cands]
    mass = {o: sum(sp.module_info(m).mass for m in o) for o in orders}
    for prefix in [(), ("1",), ("1", "21"), ("1", "21", "3"), ("1", "3", "24"), ("1", "22", "22", "22", "3")]:
        below = [o for o in orders if o[:len(prefix)] == prefix]
        assert sp.count_completions(prefix) == len(below)
        pm = sum(sp.module_info(m).mass for m in prefix)
        assert sp.lightest_completion(prefix) == pytest.approx(min(mass[o] for o in below) - pm)
        assert sp.cost_lower_bound(prefix, COST) == pytest.approx(min(0.075 + 0.1 * mass[o] for o in below))
    assert sp.count_completions(("1", "21", "21", "21", "21")) == 0 and sp.cost_lower_bound(("1", "23"), COST) == math.inf
    for o in orders:  # for Whit2 the bound of a complete order is the cost of the design
        e = bench.evals[sp.nominal_candidate(o).key()]
        if e.feasible:
            assert sp.cost_lower_bound(o, COST) == pytest.approx(e.cost)
    assert sp.cost_lower_bound(orders[0], "cyc") == 0.0
    assert sp.cost_lower_bound(orders[0], "fulfillN_-1") == -math.inf


def test_reach_bound_matches_the_reach_stage(far_bench):
    b = far_bench
    for e in b.evals.values():
        if e.stage == "reach":
            _, R = b.space.reach_bound(e.candidate)
            assert f"reaches at most {R:.3f} m" in e.message


@pytest.mark.parametrize("name", PLUGINS)
def test_batches(bench, name):
    """batch_size > 1 (asks before tells): still valid, never repeated, deterministic, and the optimum is found
    (the genetic algorithm fills a batch that outruns its generation with random immigrants)."""
    def go():
        opt = load_optimizer(name)(bench.problem, seed=0, **OPTIONS[name])
        return Study(opt, SerialExecutor(bench.ev),
                     Budget(evaluations=len(bench.cands)), batch_size=5).run()
    res = go()
    keys = [e.candidate.key() for e in res.history]
    assert len(keys) == len(set(keys))
    assert res.best.candidate == bench.best.candidate
    assert [e.candidate.key() for e in go().history] == keys


def test_genetic_generations_limit(bench):
    opt, res = run(bench, "genetic", budget=100, population_size=6, generations=2)
    assert res.stopped == "exhausted" and opt.generation == 1 and len(res.history) <= 12
    assert opt.ask() is None


def test_optuna_rejects_bad_objectives(bench):
    with pytest.raises(ValueError):
        load_optimizer("optuna")(bench.problem, multi_objective=True, objectives="score,speed")


# -- base_pose: the base alone for a fixed order ---------------------------------------------------------------------
def _base_space():
    ms = load_module_set("robodesign_arm")
    bb = BaseBounds(lower=(-0.2, -0.2, 0.0, 0.0), upper=(0.2, 0.2, 0.0, 0.0))
    sp = SearchSpace(ms, base_bounds=bb, **RULES)
    order = next(o for o in sp.enumerate_orders() if "22" in o)     # feasible under _synthetic
    return sp, order


def test_base_pose_plugin_finds_the_synthetic_optimum():
    """_synthetic's cost is mass/10 + distance of the base to (0.1, -0.05): 60 TPE evaluations of the base
    alone start at the nominal base (distance 0.112) and end within 1.5 cm of the optimum."""
    sp, order = _base_space()
    mass = 0.1 * sum(sp.module_info(m).mass for m in order)

    def go(seed):
        opt = load_optimizer("base_pose")(_problem(sp), seed=seed, order=",".join(order))
        return Study(opt, SerialExecutor(_synthetic(sp)), Budget(evaluations=60)).run()

    res = go(0)
    first = res.history[0]
    assert first.candidate == Candidate(tuple(order), (0.0, 0.0))
    assert first.cost - mass == pytest.approx(math.hypot(0.1, 0.05))
    assert all(e.candidate.order == tuple(order) for e in res.history)
    assert all(sp.validate(e.candidate) is None for e in res.history)
    keys = [e.candidate.key() for e in res.history]
    assert len(keys) == 60 == len(set(keys))
    assert res.best.cost - mass < 0.015
    x, y = res.best.candidate.base
    assert math.hypot(x - 0.1, y + 0.05) == pytest.approx(res.best.cost - mass)
    assert [e.candidate.key() for e in go(0).history] == keys        # same seed, same sequence
    assert [e.candidate.key() for e in go(1).history][1:] != keys[1:]


def test_base_pose_plugin_rejects_bad_options(bench):
    sp, order = _base_space()
    cls = load_optimizer("base_pose")
    with pytest.raises(ValueError, match="option 'order' is required"):
        cls(_problem(sp))
    with pytest.raises(ValueError, match="may not follow"):
        cls(_problem(sp), order="1,21,12")
    with pytest.raises(ValueError, match="base pose is fixed"):
        cls(bench.problem, order=",".join(bench.best.candidate.order))     # bench: fixed base


def test_base_pose_plugin_on_base_placement():
    """Real task: robodesign/base_placement, a design found by `robodesign optimize robodesign/base_placement
    --modules robodesign_arm --budget 90s --seed 0 --workers 1` (Panda joint limits; found at another base, at
    the nominal one it has no IK solution for a goal). The nominal base comes first (the same evaluation as the
    nominal candidate on its own); the best base is feasible, at least as good, and its solution passes the
    checker with the base inside the task's tolerance."""
    from robodesign.core.paths import project_root
    from robodesign.formats.solution import parse_solution
    from robodesign.judge.checker import check
    task_file = project_root() / "assets" / "tasks" / "robodesign" / "base_placement.json"
    problem = Problem.build(task_file, "robodesign_arm", "cyc")
    ev = Evaluator(EvaluatorSpec(problem, seed=0))
    sp = problem.space
    assert sp.base_dims == 3                                            # x, y, yaw
    order = "1,7,21,5,22,7,22,3,23,24,24,8,13"
    opt = load_optimizer("base_pose")(problem, seed=0, order=order)
    res = Study(opt, SerialExecutor(ev), Budget(evaluations=12)).run()
    assert len(res.history) == 12
    nominal = Evaluator(ev.spec)(sp.nominal_candidate(order.split(",")))
    assert res.history[0].candidate == nominal.candidate and res.history[0].cost == nominal.cost
    # the best base is feasible and scores at least as well as the nominal one (which may be infeasible)
    assert res.best.feasible and res.best.score <= nominal.score
    assert not nominal.feasible or res.best.cost <= nominal.cost
    sol = parse_solution(res.best.solution, "best")
    verdict = check(ev.task, sol, ev.module_set)
    assert verdict.valid and verdict.cost == res.best.cost
    assert ev.task.base_placement.valid(sol.base_pose)
    assert np.allclose(sol.base_pose, sp.base_pose(res.best.candidate))


# -- the time budget (a fake clock: the study's own accounting, no wall-clock race) -------------------------
class _Clock:
    """Stands in for the ``time`` module of robodesign.design.optimize: ``perf_counter`` is a fake clock
    that only the fake evaluations advance."""

    def __init__(self):
        self.now = 100.0

    def perf_counter(self):
        return self.now


def _slow_evaluations(clock, seconds):
    """Evaluations that each take ``seconds`` on the fake clock (infeasible at ik)."""
    def evaluate(c: Candidate) -> Evaluation:
        clock.now += seconds
        si = STAGES.index("ik")
        return Evaluation(candidate=c, feasible=False, cost=None, score=score_of(False, None, si, 0), stage="ik",
                          stage_index=si, goals_reached=0, seconds=seconds, seed=0)
    return evaluate


class _MapOnly:
    """An executor without ``imap`` (a third-party one): only ``map``."""

    def __init__(self, evaluate):
        self.evaluate = evaluate
        self.batches = []

    def map(self, candidates):
        self.batches.append(len(candidates))
        return [self.evaluate(c) for c in candidates]


@pytest.mark.parametrize("executor", ["serial", "map_only"])
@pytest.mark.parametrize("name", ["genetic", "random"])
def test_time_budget_stops_asking_at_the_deadline(bench, monkeypatch, name, executor):
    """--budget 10s with batches of 16 evaluations of 3 s each: before, the study evaluated the whole batch
    (48 s); now the candidates of a batch are sent one at a time until the deadline, so evaluations start at
    0, 3, 6 and 9 s and the study ends at 12 s: 2 s over, by the own time of the last evaluation (3 s), with
    the other 12 asked candidates of the batch not evaluated (and not told)."""
    import robodesign.design.optimize as optimize_module
    clock = _Clock()
    monkeypatch.setattr(optimize_module, "time", clock)
    evaluate = _slow_evaluations(clock, 3.0)
    ex = SerialExecutor(evaluate) if executor == "serial" else _MapOnly(evaluate)
    opt = load_optimizer(name)(bench.problem, seed=0, **OPTIONS[name])
    told = []
    res = Study(opt, ex, Budget(seconds=10.0), batch_size=16, on_evaluation=lambda i, e, b: told.append(i)).run()
    assert len(res.history) == 4 and told == [0, 1, 2, 3] and len(opt.history) == 4
    assert res.seconds == pytest.approx(12.0) and res.overrun == pytest.approx(2.0)
    assert res.last_evaluation_seconds == pytest.approx(3.0) and res.stopped == "budget"
    # random search on a streaming executor is asked only as the stream pulls: nothing asked is left over
    assert res.dropped == (0 if name == "random" and executor == "serial" else 12)
    if executor == "map_only":
        assert ex.batches == [1, 1, 1, 1]
    # the clock may start earlier (the CLI: before its worker pool started): the start-up is spent from the budget
    clock.now = 200.0
    opt = load_optimizer(name)(bench.problem, seed=0, **OPTIONS[name])
    res = Study(opt, SerialExecutor(evaluate), Budget(seconds=10.0), batch_size=16, clock_start=195.0).run()
    assert len(res.history) == 2 and res.seconds == pytest.approx(11.0) and res.overrun == pytest.approx(1.0)


def test_evaluation_budget_keeps_whole_batches(bench, monkeypatch):
    """Without a time budget a batch is evaluated whole, in one map call, as before; no overrun is reported."""
    import robodesign.design.optimize as optimize_module
    clock = _Clock()
    monkeypatch.setattr(optimize_module, "time", clock)
    ex = _MapOnly(_slow_evaluations(clock, 3.0))
    res = Study(load_optimizer("genetic")(bench.problem, seed=0, population_size=8), ex, Budget(evaluations=10),
                batch_size=4).run()
    assert ex.batches == [4, 4, 2] and len(res.history) == 10 and res.overrun is None and res.dropped == 0


def _crossover_as_before(opt, a, b):
    """GeneticOptimizer._crossover's one-point cuts as earlier releases found them (DoF sums and successor lists
    asked per cut), then the same choice: the chosen orders, or None."""
    A, B = list(a), list(b)
    sp = opt.space
    dof = lambda order: sum(sp.module_info(m).dof for m in order)  # noqa: E731
    cuts = []
    for i in range(len(A) - 1):
        succ_a = sp.successors(A[:i + 1])
        for j in range(len(B) - 1):
            if B[j + 1] not in succ_a:
                continue
            c1, c2 = A[:i + 1] + B[j + 1:], B[:j + 1] + A[i + 1:]
            if c1 in (A, B) or c2 in (A, B):
                continue
            d1, d2 = dof(A[:i + 1]) + dof(B[j + 1:]), dof(B[:j + 1]) + dof(A[i + 1:])
            if sp.min_dof <= d1 <= sp.max_dof and sp.min_dof <= d2 <= sp.max_dof and A[i + 1] in sp.successors(B[:j + 1]):
                cuts.append((c1, c2))
    for c1, c2 in opt._shuffled(cuts)[:30]:
        if opt._valid(c1) and opt._valid(c2):
            return c1, c2
    return None


def test_genetic_crossover_cuts_are_those_of_the_former_loop(tmp_path):
    """The crossover's cuts from DoF prefix sums and successor sets per junction: on 60 pairs of random orders of
    the built-in set (7-DoF arms of a generated Whitman task), the orders it makes and the random draws it takes
    are those of the former double loop."""
    from robodesign.generate.registry import generate
    from robodesign_optimizers.genetic import Individual
    task = generate("whitman2020", tmp_path, 1, 0, {"goals": 5, "obstacles": 5, "base": "xyz_any_rot"})[0]
    problem = Problem.build(task, "robodesign_arm", COST)
    new, old = load_optimizer("genetic")(problem, seed=3), load_optimizer("genetic")(problem, seed=3)
    rng = np.random.default_rng(1)
    crossed = 0
    for _ in range(60):
        a, b = (Individual(problem.space.random_order(rng), ()) for _ in range(2))
        before = (list(a), list(b))
        want = _crossover_as_before(old, list(a), list(b))
        new._crossover(a, b)
        if want is None:
            assert (list(a), list(b)) == before
            continue
        crossed += 1
        assert (list(a), list(b)) == (list(want[0]), list(want[1]))
        assert new.rng.random() == old.rng.random()   # the same draws so far
    assert crossed >= 20
