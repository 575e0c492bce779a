"""What the verdict-comparison scripts share (compare_verdicts, compare_verdicts_repeat, compare_feasible): the
checkout under test first on ``sys.path``, its IK kernel warmed, and the problems they evaluate."""
from __future__ import annotations

import glob
import sys
from pathlib import Path
from typing import Any, List, Tuple

ROOT = Path(__file__).resolve().parents[1]
COBRA = ROOT.parent / "shared" / "cobra"


def use_checkout(src: str) -> None:
    """Import robodesign from ``<src>/src`` from now on, with its compiled IK loop loaded."""
    sys.path.insert(0, str(Path(src).resolve() / "src"))
    from robodesign.solvers import ik_kernel
    ik_kernel.warm_up()


def ptp(name: str) -> Any:
    """The CoBRA task ``simple/<name>`` with the IMPROV set and cost cyc, as a Problem."""
    from robodesign.design.problem import Problem
    return Problem.build(COBRA / "tasks" / "simple" / f"{name}.json", COBRA / "modules" / "IMPROV", "cyc")


def profile_runs() -> List[Tuple[str, Any]]:
    """PTP_3 with IMPROV, then every task profile_evaluator.py generated (results/tasks/profile_*) with the
    built-in set: (name, Problem)."""
    from robodesign.design.problem import Problem
    runs = [("PTP_3", ptp("PTP_3"))]
    runs += [(Path(f).name, Problem.build(f, "robodesign_arm", "cyc"))
             for f in sorted(glob.glob(str(ROOT / "results" / "tasks" / "profile_*" / "*.json")))]
    return runs
