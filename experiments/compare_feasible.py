"""Print the verdicts of candidates that get through planning and time scaling, to compare two checkouts where
``compare_verdicts.py`` has few (issue 25: its random candidates mostly fail at reach or IK).

    nice .venv/bin/python experiments/compare_feasible.py --src . > after.txt
    nice .venv/bin/python experiments/compare_feasible.py --src ../old_checkout > before.txt; diff before.txt after.txt

One line per evaluation: scenario, index, stage reached, goals reached, feasible, cost, duration of the motion and
a hash of the solution's trajectory. Scenarios: the known-good IMPROV arm on PTP_1, PTP_2 and PTP_3 for
``--seeds`` study seeds each; random PTP_3 candidates (seeded, default search space) until ``--feasible`` of them
are feasible or ``--max`` are evaluated, every one printed; then ``--plans`` planning queries of the known-good
arm in the PTP_3 cell between random collision-free configurations whose midpoint collides (seeded; OMPL and the
shortcuts):
reason, checks, distinct states, waypoints and a hash of the path.
"""
from __future__ import annotations

import argparse
import hashlib
import json
from pathlib import Path

from verdict_runs import ptp, use_checkout

ROOT = Path(__file__).resolve().parents[1]
GOOD = ("1", "21", "4", "22", "5", "23", "12")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--src", default=str(ROOT), help="the checkout whose src/ is evaluated")
    ap.add_argument("--seeds", type=int, default=6)
    ap.add_argument("--feasible", type=int, default=12)
    ap.add_argument("--max", type=int, default=400)
    ap.add_argument("--plans", type=int, default=30)
    args = ap.parse_args()
    use_checkout(args.src)
    import numpy as np

    from robodesign.design.evaluator import Evaluator, EvaluatorSpec
    from robodesign.design.search_space import Candidate

    def line(name, i, e):
        tr = e.solution["trajectory"] if e.solution else None
        h = hashlib.md5(json.dumps(tr).encode()).hexdigest()[:10] if tr else "-"
        dur = f"{tr['t'][-1]:.2f}" if tr else "-"
        print(name, i, e.stage, e.goals_reached, e.feasible, e.cost, dur, h, flush=True)

    problems = {t: ptp(t) for t in ("PTP_1", "PTP_2", "PTP_3")}
    for t, p in problems.items():
        for s in range(args.seeds):
            line(f"{t} good", s, Evaluator(EvaluatorSpec(p, seed=s)).evaluate(Candidate(GOOD)))
    p = problems["PTP_3"]
    ev = Evaluator(EvaluatorSpec(p, seed=0))
    rng = np.random.default_rng(0)
    found = 0
    for i in range(args.max):
        e = ev.evaluate(p.space.random_candidate(rng))
        line("PTP_3 random", i, e)
        found += bool(e.feasible)
        if found >= args.feasible:
            break
    from robodesign.formats.assembly import Assembly
    from robodesign.model.cell import build_robot
    from robodesign.solvers.planning import plan_path
    from robodesign.solvers.schedule import static_cell
    robot = build_robot(static_cell(p.task), p.module_set, Assembly.from_order(p.module_set, GOOD),
                        p.task.nominal_base_pose)
    rng = np.random.default_rng(4)
    free = [q for q in (robot.random_configuration(rng) for _ in range(20 * args.plans))
            if not robot.in_collision(q)]
    pairs = [(a, b) for a, b in zip(free[::2], free[1::2]) if robot.in_collision(0.5 * (a + b))]  # blocked lines
    for i, (a, b) in enumerate(pairs[:args.plans]):
        r = plan_path(robot, a, b, time_limit=0.5, seed=i, static_torque=True)
        h = hashlib.md5(r.path.tobytes()).hexdigest()[:10]
        print("PTP_3 plan", i, r.stats["reason"], r.stats["checks"], r.stats["distinct_states"], len(r.path), h,
              flush=True)


if __name__ == "__main__":
    main()
