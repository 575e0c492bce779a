"""What :class:`robodesign.solvers.ik.ChainBounds` reads of a goal that does not depend on the robot, or only on its
TCP offset, kept for the process: robots of a search meet the same goals again and again, and many share their tool
(the same offset c of the last joint's frame seen from the TCP). The numbers are the goal model's own methods' and
the same products, made once instead of once per robot.
"""
from __future__ import annotations

import math
from typing import Dict, Tuple

import numpy as np

_GOALS: Dict[int, tuple] = {}                # id(goal model) → (it, position radius, nominal position, rotation)
_TCPS: Dict[Tuple[int, bytes], tuple] = {}   # (id(goal model), c's bytes) → (it, rotation slack, p − R·c or None)
_KEPT = 4096   # entries of each, at most (emptied beyond)


def goal_terms(gm) -> Tuple[float, np.ndarray, np.ndarray]:
    """(``gm.position_radius()``, the nominal pose's position and rotation as float arrays) of a goal model."""
    hit = _GOALS.get(id(gm))
    if hit is None or hit[0] is not gm:   # (the model is held: its id is not reused while the entry lives)
        if len(_GOALS) >= _KEPT:
            _GOALS.clear()
        N = gm.goal.nominal
        hit = _GOALS[id(gm)] = (gm, gm.position_radius(), np.asarray(N[:3, 3], float), np.asarray(N[:3, :3], float))
    return hit[1], hit[2], hit[3]


def tcp_terms(gm, c: np.ndarray) -> Tuple[float, np.ndarray]:
    """(``gm.rotation_slack(c)``, p − R·c of the nominal pose (R, p), or None where the slack is not finite) of a goal
    model and a TCP offset ``c``."""
    key = (id(gm), c.tobytes())
    hit = _TCPS.get(key)
    if hit is None or hit[0] is not gm:
        if len(_TCPS) >= _KEPT:
            _TCPS.clear()
        rs = gm.rotation_slack(c)
        _, pn, NR = goal_terms(gm)
        hit = _TCPS[key] = (gm, rs, pn - NR @ c if math.isfinite(rs) else None)
    return hit[1], hit[2]
