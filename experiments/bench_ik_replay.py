"""The IK stage of the genetic search's candidates, replayed alone (issue 25): its time and its results.

    nice .venv/bin/python experiments/bench_ik_replay.py --src CHECKOUT [--task oven_hard] [--rounds 3]

Runs the genetic search of experiments/bench_front_ga.py (200 evaluations, seed 0) on one generated task (a
substring of its name: bpo2024's ``oven_hard_s0_0001``, whitman2020's ``..._0001``), records every
IK search (``solvers.ik.IKSearch``, which ``solve_ik`` makes too; robot: assembly, base pose, obstacles, margin; goal,
the random generator's state, options, and the runs asked of it), then replays them ``--rounds`` times on fresh robots, robot by robot in the search's order (the robot's base
contacts asked first, as the base stage asks them). Per round it prints the wall and process CPU time of the
robots whose IK stage failed (sum, median per robot); at the end a hash of every call's solutions (their
bytes), statistics (time excluded) and the generator's state after it: equal hashes mean the same IK
solutions, verdicts and random streams. ``--src`` evaluates another checkout's src/ (an A/B in one command
line per side; compare the CPU times on a shared machine).
"""
from __future__ import annotations

import argparse
import copy
import hashlib
import pickle
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--src", default=str(ROOT), help="the checkout whose src/ is evaluated")
    ap.add_argument("--task", default="oven_hard", help="a substring of the generated task's file name")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--dump", default="", help="pickle the results here")
    args = ap.parse_args()
    sys.path.insert(0, str(Path(args.src).resolve() / "src"))
    from robodesign.design.evaluator import Evaluator, EvaluatorSpec, evaluation_settings
    from robodesign.design.optimize import Budget, SerialExecutor, Study, create_optimizer
    from robodesign.design.problem import Problem
    from robodesign.design.solve import warm_up
    from robodesign.model.robot import Robot
    from robodesign.solvers import ik, ik_kernel
    ik_kernel.warm_up()
    warm_up()
    import robodesign
    print("# src:", Path(robodesign.__file__).parent, flush=True)
    from profile_evaluator import family_tasks
    family = "whitman2020_g5o5" if "whitman" in args.task else "bpo2024"
    task = next(f for f in family_tasks(family, 2, 0) if args.task in f.name)
    problem = Problem.build(task, "robodesign_arm", "cyc")
    ev = Evaluator(EvaluatorSpec(problem, evaluation_settings(), seed=0))
    opt = create_optimizer("genetic", problem, seed=0, options={})
    calls: dict = {}
    plain = ik.IKSearch

    class Spy(plain):   # every IK search (solve_ik makes one per call) and the runs asked of it
        def __init__(self, robot, goal, rng=None, **kw):
            key = (id(robot), robot.base_pose.tobytes())
            if key not in calls:
                calls[key] = (robot.module_set, robot.assembly, robot.base_pose.copy(), list(robot.obstacles),
                              robot.safety_margin, [])
            gen = rng if isinstance(rng, np.random.Generator) else getattr(rng, "generator", None)
            state = copy.deepcopy(gen.bit_generator.state) if gen is not None else rng
            self.runs: list = []
            calls[key][5].append((goal, state, kw, self.runs))
            super().__init__(robot, goal, rng, **kw)

        def run(self, n):
            self.runs.append(n)
            return super().run(n)

    ik.IKSearch = Spy   # (goal_planner and solve_ik look it up at each call)
    Study(opt, SerialExecutor(ev), Budget.parse("200evals"), batch_size=16).run()
    ik.IKSearch = plain
    cases = list(calls.values())
    print(f"# {task.name}: {len(cases)} robots, {sum(len(c[5]) for c in cases)} IK searches", flush=True)

    def replay():
        results, times = [], []
        for ms, asm, T, obstacles, margin, todo in cases:
            robot = Robot(ms, asm, base_pose=T)
            robot.set_obstacles(obstacles, safety_margin=margin)
            robot.base_collisions()
            t, c = time.perf_counter(), time.process_time()
            out = []
            for goal, state, kw, runs in todo:
                rng = np.random.default_rng()
                rng.bit_generator.state = state
                search = plain(robot, goal, rng, **kw)
                r = None
                for n in runs:
                    r = search.run(n)
                sols = [] if r is None else [s.tobytes() for s in r.solutions]
                stats = {} if r is None else {k: v for k, v in r.stats.items() if k != "time"}
                out.append((sols, stats, rng.bit_generator.state))
            times.append((time.perf_counter() - t, time.process_time() - c))
            results.append(out)
        return results, times

    results: list = []
    for k in range(args.rounds):
        results, times = replay()
        failed = [t for t, out in zip(times, results) if not out[-1][0]]
        wall, cpu = [t[0] for t in failed], [t[1] for t in failed]
        print(f"round {k}: failing robots {len(failed)}: wall total {sum(wall) * 1e3:.1f} ms median "
              f"{np.median(wall) * 1e3:.2f} ms; cpu total {sum(cpu) * 1e3:.1f} ms median {np.median(cpu) * 1e3:.2f} ms",
              flush=True)
    if args.dump:
        with open(args.dump, "wb") as fh:
            pickle.dump(results, fh)
    print("result hash", hashlib.md5(pickle.dumps(results)).hexdigest()[:12])


if __name__ == "__main__":
    main()
