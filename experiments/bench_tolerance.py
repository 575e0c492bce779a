"""Time of ``ToleratedPose.valid`` on a published goal tolerance (x, y, z ±1 mm, Theta_R ≤ 0.5°): the IK stage
asks it for every converged configuration and the checker for every sample of a goal's window.

    .venv/bin/python experiments/bench_tolerance.py            # this tree
    PYTHONPATH=/path/to/other/checkout/src .venv/bin/python experiments/bench_tolerance.py   # another commit

Prints the median of 5 rounds of 20,000 calls in µs per call."""
import statistics
import timeit

import numpy as np

from robodesign.formats.tolerance import ToleratedPose

tp = ToleratedPose.from_json({"nominal": np.eye(4).tolist(), "toleranceProjection": ["x", "y", "z", "Theta_R"],
                              "tolerance": [[-0.001, 0.001], [-0.001, 0.001], [-0.001, 0.001],
                                            [0, 0.008726646259971648]]})
T = np.eye(4)
T[0, 3] = 0.0005
N = 20000
rounds = [timeit.timeit(lambda: tp.valid(T), number=N) / N * 1e6 for _ in range(5)]
print(f"ToleratedPose.valid: {statistics.median(rounds):.1f} µs per call (median of 5 x {N})")
