"""The compiled kernels' warm-up (what ``python -m robodesign.<kernel module>`` and the background compiler put in
numba's cache) covers every argument type an evaluation passes: read-only limit vectors, a pinocchio rotation in
Fortran order. A type it missed was compiled at the first call of the first evaluation, some 5 s per kernel, on
every fresh install's first run."""
from __future__ import annotations

from pathlib import Path

from robodesign.design.evaluator import Evaluator, EvaluatorSpec
from robodesign.design.problem import Problem
from robodesign.design.search_space import Candidate
from robodesign.judge import interval_kernel
from robodesign.model import geometry_kernel, rnea_kernel, sweep_kernel
from robodesign.solvers import certificate_kernel, topp_kernel

SHARED = Path(__file__).resolve().parents[2] / "shared" / "cobra"
GOOD = ("1", "21", "4", "22", "5", "23", "12")   # IMPROV, feasible on PTP_3 at the nominal base
MODULES = (geometry_kernel, topp_kernel, interval_kernel, sweep_kernel, certificate_kernel, rnea_kernel)


def _signatures(module) -> dict:
    return {name: set(getattr(module, name).signatures) for name in module.KERNELS.cache.kernels}


def test_a_feasible_evaluation_compiles_nothing_the_warm_up_did_not():
    for m in MODULES:
        assert m.KERNELS.warm_up()          # numba is a dependency: the kernels load (or compile) now
    warmed = {m.__name__: _signatures(m) for m in MODULES}
    assert all(warmed[m.__name__] for m in MODULES)
    problem = Problem.build(SHARED / "tasks" / "simple" / "PTP_3.json", SHARED / "modules" / "IMPROV", "cyc")
    ev = Evaluator(EvaluatorSpec(problem, seed=0)).evaluate(Candidate(GOOD))
    assert ev.feasible and ev.stage == "done"   # every stage ran: IK, planning, time scaling, the check
    for m in MODULES:
        after = _signatures(m)
        new = {k: after[k] - warmed[m.__name__][k] for k in after if after[k] - warmed[m.__name__][k]}
        assert not new, f"{m.__name__}: compiled at first use, not by the warm-up: {new}"
