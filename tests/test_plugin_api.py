"""A third-party optimizer plugin, defined OUTSIDE the robodesign packages, is discovered through its entry
point and runs in a Study.

The test writes a tiny distribution (a pyproject with an entry point in the group ``robodesign.optimizers``
and one module holding a hill-climber, the example of docs/plugins.md) into a tmp dir and installs it into
the current venv with ``pip install --no-deps --no-build-isolation`` (uninstalled again at the end).

Fallback: building a wheel without build isolation needs the ``wheel`` package (setuptools < 70.1); when
the venv lacks it, or pip fails or takes more than 60 s, the test instead puts the package and a
``<name>.dist-info`` folder (``METADATA`` + ``entry_points.txt``) into a tmp dir on the subprocess's
``PYTHONPATH`` — exactly what an installed distribution looks like to ``importlib.metadata``, which is how
``robodesign.design.optimize.available_optimizers`` discovers plugins. Either way the checks run in a fresh
Python process.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path


DIST = "rdtest-hill-climber"
MODULE = "rdtest_hill"
ENTRY = "hill-test"

HILL_CLIMBER = '''
"""A hill-climber: the minimal robodesign optimizer plugin."""
from dataclasses import dataclass

from robodesign.plugin import Candidate, Optimizer, option


class HillClimber(Optimizer):
    name = "hill"
    description = "first-improvement hill climbing: replace one module or nudge the base"

    @dataclass(frozen=True)
    class Options:
        step: float = option(0.1, low=0.0, high=1.0, help="base-pose step, as a fraction of each range")

    def __init__(self, problem, seed=0, **options):
        super().__init__(problem, seed, **options)  # self.problem, self.space, self.cost, self.rng, self.options
        self.current = None          # the best evaluation so far (the point we climb from)
        self.seen = set()            # keys already asked: never ask a candidate twice

    def ask(self):
        for _ in range(50):          # a neighbour of the current design ...
            c = self.neighbour()
            if c is not None and c.key() not in self.seen:
                self.seen.add(c.key())
                return c
        for _ in range(200):         # ... or a random restart
            c = self.space.random_candidate(self.rng)
            if c.key() not in self.seen:
                self.seen.add(c.key())
                return c
        return None                  # nothing new left: the study stops

    def tell(self, evaluation):
        if self.current is None or evaluation.score < self.current.score:
            self.current = evaluation

    def neighbour(self):
        if self.current is None:
            return None
        order, base = list(self.current.candidate.order), list(self.current.candidate.base)
        bb = self.space.base_bounds
        if base and self.rng.random() < 0.5:     # nudge one free base parameter
            k = int(self.rng.integers(len(base)))
            i = bb.free[k]
            sigma = self.options.step * (bb.upper[i] - bb.lower[i])
            base[k] = min(bb.upper[i], max(bb.lower[i], base[k] + self.rng.normal(0, sigma)))
            return Candidate(tuple(order), tuple(base)) if bb.valid(base) else None
        i = int(self.rng.integers(len(order)))   # replace module i by one that fits after order[:i]
        choices = [m for m in self.space.successors(order[:i]) if m != order[i]]
        if not choices:
            return None
        order[i] = choices[int(self.rng.integers(len(choices)))]
        if self.space.validate_order(order) is not None:
            return None
        return Candidate(tuple(order), tuple(base))
'''

PYPROJECT = f'''
[build-system]
requires = ["setuptools>=61"]
build-backend = "setuptools.build_meta"

[project]
name = "{DIST}"
version = "0.0.1"
description = "test plugin for robodesign"
dependencies = ["robodesign"]

[project.entry-points."robodesign.optimizers"]
{ENTRY} = "{MODULE}:HillClimber"

[tool.setuptools]
py-modules = ["{MODULE}"]
'''

CHECK = f'''
import json, sys
from robodesign.core.errors import InputError
from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.optimize import (Budget, SerialExecutor, Study, available_optimizers, create_optimizer, load_optimizer,
                                 optimize)
from robodesign.design.problem import Problem
eps = available_optimizers()
cls = load_optimizer("{ENTRY}")
rules = dict(min_dof=3, max_dof=3, bases=["1"], end_effectors=["12"],
             exclude=["4", "5", "6", "7", "8", "9", "10", "11", "15"])
problem = Problem.build(sys.argv[1], "robodesign_arm", "Whit2", rules=rules)
ev = Evaluator(EvaluatorSpec(problem))
opt = create_optimizer("{ENTRY}", problem, seed=0, options={{"step": "0.05"}})
res = Study(opt, SerialExecutor(ev), Budget(evaluations=32)).run()
runs = [[e.candidate.key() for e in res.history]]
res2 = optimize(problem, "{ENTRY}", "32evals", seed=0, options={{"step": 0.05}})   # the same study, one call
runs.append([e.candidate.key() for e in res2.history])
try:
    create_optimizer("{ENTRY}", problem, options={{"stpe": 0.2}})
    typo = None
except InputError as e:
    typo = str(e)
print(json.dumps({{"names": sorted(eps), "value": eps["{ENTRY}"].value, "cls": cls.__name__,
                  "feasible": res.best.feasible, "best": res.best.candidate.key(), "cost": res.best.cost,
                  "n": len(res.history), "same": runs[0] == runs[1], "unique": len(set(runs[0])) == len(runs[0]),
                  "step": opt.options.step, "typo": typo}}))
'''


def _T(x, y, z):
    return [[1, 0, 0, x], [0, 1, 0, y], [0, 0, 1, z], [0, 0, 0, 1]]


def _task(path: Path) -> Path:
    """Two position-only reach goals for a 3-DoF robodesign_arm, no obstacles, fixed base."""
    goals = [(0.3, 0.2, 0.45), (-0.2, 0.25, 0.55)]
    path.write_text(json.dumps({
        "header": {"ID": "test/plugin_api", "version": "2022", "taskName": "plugin_api", "author": ["robodesign tests"],
                   "affiliation": ["robodesign"], "email": ["tests@robodesign.invalid"], "tags": ["test"],
                   "date": "2024-01-01", "timeStepSize": 0.01, "gravity": [0, 0, -9.81]},
        "obstacles": [],
        "constraints": [{"type": "joint", "parts": ["q", "dq", "tau"]}, {"type": "selfCollisionFree"},
                        {"type": "allGoalsFulfilled"}, {"type": "basePlacement", "pose": {"nominal": _T(0, 0, 0)}}],
        "goals": [{"ID": str(i + 1), "type": "reach", "goalPose": {"nominal": _T(*g), "toleranceProjection": ["r_sph"],
                                                                 "tolerance": [[0.0, 0.02]]}}
                  for i, g in enumerate(goals)]}))
    return path


def _write_package(root: Path) -> Path:
    pkg = root / "pkg"
    pkg.mkdir()
    (pkg / "pyproject.toml").write_text(textwrap.dedent(PYPROJECT).lstrip())
    (pkg / f"{MODULE}.py").write_text(textwrap.dedent(HILL_CLIMBER).lstrip())
    return pkg


def _fake_install(pkg: Path, site: Path) -> None:
    """What an installed distribution is to importlib.metadata: the module plus ``<dist>.dist-info``."""
    site.mkdir()
    (site / f"{MODULE}.py").write_text((pkg / f"{MODULE}.py").read_text())
    info = site / f"{DIST.replace('-', '_')}-0.0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {DIST}\nVersion: 0.0.1\n")
    (info / "entry_points.txt").write_text(f"[robodesign.optimizers]\n{ENTRY} = {MODULE}:HillClimber\n")


def _pip(*args, timeout=60):
    return subprocess.run([sys.executable, "-m", "pip", *args], capture_output=True, text=True, timeout=timeout)


def test_external_plugin_is_discovered_and_runs(tmp_path):
    pkg = _write_package(tmp_path)
    task = _task(tmp_path / "task.json")
    env = dict(os.environ)
    installed = False
    try:
        try:
            r = _pip("install", "--no-deps", "--no-build-isolation", "-q", str(pkg))
            installed = r.returncode == 0
        except subprocess.TimeoutExpired:
            installed = False
        if not installed:  # e.g. no `wheel` in the venv: the dist-info fallback (see the module docstring)
            site = tmp_path / "site"
            _fake_install(pkg, site)
            env["PYTHONPATH"] = os.pathsep.join(p for p in (str(site), env.get("PYTHONPATH", "")) if p)
        out = subprocess.run([sys.executable, "-c", CHECK, str(task)], capture_output=True, text=True, env=env,
                             cwd=tmp_path, timeout=300)
        assert out.returncode == 0, out.stderr[-3000:]
        res = json.loads(out.stdout.strip().splitlines()[-1])
        assert ENTRY in res["names"] and {"random", "genetic", "elimination", "heuristic", "optuna"} <= set(res["names"])
        assert res["value"] == f"{MODULE}:HillClimber" and res["cls"] == "HillClimber"
        assert res["feasible"] and res["cost"] > 0
        assert res["same"] and res["unique"]
        assert res["step"] == 0.05                                  # "0.05" from the CLI, converted to a float
        assert res["typo"] == ("optimizer 'hill': unknown option 'stpe' (did you mean 'step'?) (valid options: "
                               "step (float, default 0.1, in [0.0, 1.0]))")
        # the CLI lists it too, with its options
        cli = subprocess.run([sys.executable, "-m", "robodesign.cli", "optimizers", "--json"], capture_output=True,
                             text=True, env=env, cwd=tmp_path, timeout=120)
        assert cli.returncode == 0, cli.stderr[-2000:]
        assert json.loads(cli.stdout)[ENTRY] == f"{MODULE}:HillClimber"
        cli = subprocess.run([sys.executable, "-m", "robodesign.cli", "optimizers", "--verbose"], capture_output=True,
                             text=True, env=env, cwd=tmp_path, timeout=120)
        assert "--opt step (float, default 0.1, in [0.0, 1.0]): base-pose step" in cli.stdout
    finally:
        if installed:
            _pip("uninstall", "-y", "-q", DIST, timeout=120)
    # gone again (a fresh process; the fallback never touched the venv)
    after = subprocess.run([sys.executable, "-c", "from robodesign.design.optimize import available_optimizers as a; "
                            "print(sorted(a()))"], capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert ENTRY not in after.stdout


def test_docs_example_is_the_tested_plugin():
    """docs/plugins.md shows the same hill-climber that this test installs."""
    doc = (Path(__file__).resolve().parents[1] / "docs" / "plugins.md").read_text()
    blocks = [b.split("```", 1)[0] for b in doc.split("```python\n")[1:]]
    example = next(b for b in blocks if "class HillClimber" in b)
    assert example.strip() == textwrap.dedent(HILL_CLIMBER).strip()


# -- the plugin API before Problem (removed after its deprecation release) ------------------------------------------
LEGACY = '''
from robodesign.design.optimize import Optimizer


class LegacyRandom(Optimizer):
    """Written against the old API: takes the search space, reads its options (and the cost) itself."""
    name = "legacy"

    def __init__(self, space, seed=0, tries=50, **options):
        super().__init__(space, seed, **options)
        self.tries = int(tries)

    def ask(self):
        return self.space.random_candidate(self.rng)
'''


def test_plugins_written_against_the_old_api_are_refused_with_how_to_port(tmp_path):
    """Optimizer(space, seed, **options) plugins ran with a DeprecationWarning for one release; now they are bad
    input (exit 2) that says how to port them, and the base class refuses a SearchSpace."""
    import pytest
    from robodesign.core.errors import InputError
    from robodesign.design.optimize import Optimizer, create_optimizer
    from robodesign.design.problem import Problem
    ns: dict = {}
    exec(LEGACY, ns)
    problem = Problem.build(_task(tmp_path / "task.json"), "robodesign_arm", "Whit2")
    with pytest.raises(InputError) as e:
        create_optimizer(ns["LegacyRandom"], problem, seed=0, options={"tries": "7"})
    assert str(e.value).startswith("optimizer 'legacy' is written against the plugin API before Problem "
                                   "(__init__(self, space, ...)), which this release no longer runs: take a Problem")

    class Bare(Optimizer):
        def ask(self):
            return None
    with pytest.raises(TypeError, match="takes a robodesign.design.problem.Problem, got SearchSpace"):
        Bare(problem.space)
    assert Bare(problem).cost is problem.cost


def test_a_plugin_without_options_takes_none(tmp_path):
    """Undeclared options reached self.options with a DeprecationWarning for one release; now they are refused."""
    import pytest
    from robodesign.design.optimize import Optimizer, OptionError, create_optimizer
    from robodesign.design.problem import Problem

    class NoOptions(Optimizer):
        name = "bare"

        def ask(self):
            return self.space.random_candidate(self.rng)

    problem = Problem.build(_task(tmp_path / "task.json"), "robodesign_arm", "Whit2")
    assert create_optimizer(NoOptions, problem).options == {}
    with pytest.raises(OptionError) as e:
        create_optimizer(NoOptions, problem, options={"tries": "3"})
    assert str(e.value) == "optimizer 'bare' takes no options (it declares no Options), got 'tries'" and e.value.option == "tries"
