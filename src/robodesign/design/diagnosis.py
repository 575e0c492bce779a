"""Why a task is unsolved: after a search that found no valid design, say which of these holds, with its figure.

* ``out_of_reach`` — *provably out of reach for this module set*: a real bound
  (:func:`robodesign.design.reach.reach_proof`): the longest arm the set can build under the search-space
  rules against the goals' distances from the base region the task allows, or their spread; or a goal the
  tool cannot be at (:func:`robodesign.design.blocked.blocked_goal_proof`): every end effector the search
  space allows, held at some goal's pose, lies inside an obstacle deeper than the goal's tolerance can move
  it. Only a proof gives this verdict; it does not depend on the search.
* ``torque`` — *torque-infeasible at every tried design*: no evaluated design got past the
  ``static_torque`` stage and some failed there; the figure is the smallest shortfall (Nm needed to hold a
  goal's pose beyond the joint's limit) among them.
* ``not_found`` — *the search ran out of budget* (or exhausted its space) without a valid design; the
  figure is the furthest stage any design reached.

``solved`` when some evaluation is feasible. The same :func:`diagnose` serves ``robodesign optimize`` (its
evaluations) and the suite report (the stored rows of a run).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any, List, Optional, Sequence, Tuple, Union

from robodesign.core.paths import builtin_module_sets
from robodesign.design.blocked import BlockedGoalProof, blocked_goal_proof
from robodesign.design.problem import Problem
from robodesign.design.reach import ReachProof, SetReach, reach_proof, set_reach
from robodesign.design.solve import STAGES
from robodesign.formats.module_io import load_module_set

VERDICTS = ("solved", "out_of_reach", "torque", "not_found")

# the static_torque stage's messages (design/solve.py, GoalPlanner.filter_static_torque)
_HOLD = re.compile(r"needs (?P<need>[-+0-9.eE]+) Nm at joint (?P<joint>\d+) \(limit (?P<limit>[-+0-9.eE]+)\)")
_FOLLOW = re.compile(r"static torque (?P<need>[-+0-9.eE]+) Nm > (?P<limit>[-+0-9.eE]+) at joint (?P<joint>\d+)")


def torque_shortfall(message: str) -> Optional[Tuple[float, float, int]]:
    """(torque needed [Nm], limit [Nm], joint index) from a ``static_torque`` failure message, else None."""
    m = _HOLD.search(message or "") or _FOLLOW.search(message or "")
    if m is None:
        return None
    return float(m["need"]), float(m["limit"]), int(m["joint"])


def stronger_builtin_sets(torque: float, exclude: str = "") -> List[Tuple[str, float]]:
    """(name, strongest joint's peak torque [Nm]) of every built-in module set other than ``exclude`` that has a
    joint of at least ``torque``."""
    out = []
    for name in builtin_module_sets():
        if name == exclude:
            continue
        ms = load_module_set(name)
        strongest = max((j.limits.torque for m in ms for j in m.joints if j.actuated), default=0.0)
        if strongest >= torque:
            out.append((name, float(strongest)))
    return out


def allowed_end_effectors(space) -> List[Any]:
    """The end-effector modules the search space's orders may end with."""
    return [m for m in space.module_set.of_kind("eef") if space._allowed(m.id)]


def _get(e: Any, key: str, default=None):
    return e.get(key, default) if isinstance(e, dict) else getattr(e, key, default)


@dataclass
class Diagnosis:
    verdict: str                                 # one of VERDICTS
    message: str                                 # one line with the figure
    evaluations: int = 0
    reach_bound: Optional[float] = None          # m: the module set's reach bound (when computed)
    proof: Optional[Union[ReachProof, BlockedGoalProof]] = None  # out_of_reach
    torque_needed: Optional[float] = None        # torque: Nm needed at the best design's worst joint
    torque_limit: Optional[float] = None
    torque_shortfall: Optional[float] = None     # torque: needed − limit [Nm], the smallest one seen
    torque_failures: int = 0                     # evaluations that failed at static_torque
    best_stage: str = ""                         # the furthest stage any evaluation reached (first failed)
    best_message: str = ""
    stopped: str = ""                            # the search's stop reason ("budget", "exhausted")

    @property
    def label(self) -> str:
        """The suite report's three classes: solved, provably out of reach, not found."""
        return {"solved": "solved", "out_of_reach": "provably out of reach"}.get(self.verdict, "not found")

    def to_json(self) -> dict:
        return {"verdict": self.verdict, "label": self.label, "message": self.message,
                "evaluations": self.evaluations,
                "reach_bound": self.reach_bound if self.reach_bound is not None and math.isfinite(self.reach_bound)
                else None,  # strict JSON: an unbounded (or empty) set has no figure
                "proof": None if self.proof is None else self.proof.to_json(),
                "torque_needed": self.torque_needed, "torque_limit": self.torque_limit,
                "torque_shortfall": self.torque_shortfall, "torque_failures": self.torque_failures,
                "best_stage": self.best_stage, "best_message": self.best_message, "stopped": self.stopped}


def diagnose(problem: Problem, evaluations: Sequence[Any], stopped: str = "budget",
             reach: Optional[SetReach] = None) -> Diagnosis:
    """The diagnosis of a search over ``problem`` whose evaluations are ``evaluations`` (Evaluation objects or
    dicts with ``feasible``, ``stage``, ``stage_index``, ``message``). ``reach``: a precomputed set reach of
    ``problem.space`` (computed here otherwise: 0.1–0.4 s for the built-in sets)."""
    n = len(evaluations)
    if any(_get(e, "feasible") for e in evaluations):
        return Diagnosis("solved", f"solved: a valid design among {n} evaluations", evaluations=n, stopped=stopped)
    reach = reach or set_reach(problem.space)
    proof: Optional[Union[ReachProof, BlockedGoalProof]] = reach_proof(problem.task, problem.space, reach)
    if proof is None:
        proof = blocked_goal_proof(problem.task, allowed_end_effectors(problem.space), problem.space)
    # the furthest design: latest stage, then most goals reached (the evaluator's ranking of infeasible ones)
    far = max(evaluations, key=lambda e: (_get(e, "stage_index", -1), _get(e, "goals_reached", 0) or 0), default=None)
    best_stage = "" if far is None else str(_get(far, "stage", ""))
    best_message = "" if far is None else str(_get(far, "message", "") or "")
    d = Diagnosis("not_found", "", evaluations=n, reach_bound=reach.bound, best_stage=best_stage,
                  best_message=best_message, stopped=stopped)
    if proof is not None:
        d.verdict, d.proof, d.message = "out_of_reach", proof, proof.message
        return d
    torque = [(t, e) for e in evaluations if _get(e, "stage") == "static_torque"
              for t in [torque_shortfall(str(_get(e, "message", "")))] if t is not None]
    d.torque_failures = len(torque)
    if torque and best_stage == "static_torque":
        (need, limit, joint), _ = min(torque, key=lambda te: te[0][0] - te[0][1])
        d.verdict = "torque"
        d.torque_needed, d.torque_limit, d.torque_shortfall = need, limit, need - limit
        d.message = (f"torque-infeasible at every tried design that reached the goals: {len(torque)} of {n} designs "
                     f"had IK solutions and none could hold them (static_torque); the best needs {need:.1f} Nm at "
                     f"joint {joint} (limit {limit:.1f}), {need - limit:.1f} Nm short")
        stronger = stronger_builtin_sets(need, exclude=problem.module_set.name)
        if stronger:
            d.message += "; stronger built-in sets: " + ", ".join(
                f"{n} (joints up to {t:.0f} Nm; --modules {n})" for n, t in stronger)
        return d
    why = "the search exhausted its space" if stopped == "exhausted" else "the search ran out of budget"
    if far is None:
        d.message = f"not found: {why} before any evaluation"
    else:
        k = STAGES.index(best_stage) if best_stage in STAGES else -1
        past = f", past {STAGES[k - 1]}" if k > 0 else ""
        d.message = (f"not found: {why} ({n} evaluations); the best design stopped at stage '{best_stage}'{past}: "
                     f"{best_message}")
    return d
