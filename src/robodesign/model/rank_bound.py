"""What a robot's structure alone says about the rank of its TCP Jacobian (:meth:`Robot.generic_rank
<robodesign.model.robot.Robot.generic_rank>`'s shortcut for arms of rank below six).

*Structural bound.* On a TCP chain of revolute joints about their frames' ±z (every robodesign robot), the axis of
joint i+1 seen from joint i's moving frame is ``R·e_z`` of the placement between them, the same at every q: when it
is ±e_z the two axes are parallel at every configuration, and when the placement's translation also has no x and y
the two axes are one line (coaxial). A run of consecutive parallel joints moves in a plane: its Jacobian columns
(twists) span at most 3 dimensions, and at most as many as the run has distinct lines (coaxial neighbours give the
same twist). The rank of the Jacobian is at most the sum over the runs (the rank of a matrix is at most the sum of
the ranks of its column blocks): :func:`structural_rank_bound`. The placements are floats (a rotation by 90° has
entries like 6e-17): parallel and coaxial are taken within 1e-12 (relative to the reach radius for the
translation); the exactly parallel model differs from the float one by far less than 1e-9 of the Jacobian's norm,
so every singular value beyond the bound is below 1e-9·σ₁ (Weyl), also after pinocchio's and LAPACK's rounding
(< 1e-12·σ₁): no sample counts more than the bound at the ranks' rtol ≥ 1e-8 (rtol below 1e-8: not used).

*Certified lower bound.* :func:`certainly_rank_at_least` shows that a matrix J has ``r`` singular values above
c·√tr(JᵀJ) ≥ c·σ₁ (c = max(1000·rtol, 1e-5)): columns S are picked greedily such that the Cholesky factorization
of JᵀJ restricted to S minus t·I, t = c²·tr(JᵀJ), succeeds (in Python floats, the error analysis of
:func:`robodesign.model.robot._certainly_full_rank`); then σ_min(J[:, S])² ≥ t − δ, and σ_r(J) ≥ σ_min(J[:, S])
(removing columns does not increase a singular value). LAPACK's values are off by less than 1e-12·σ₁: the rank
counted from them is at least r.

Both bounds equal: the rank that :meth:`Robot.generic_rank` counts at every sample is at most the structural bound,
at the first sample at least it, so the largest over the samples is that number without any SVD.
"""
from __future__ import annotations

import math
from typing import List, Optional

import numpy as np

_PARALLEL = 1e-12   # |x|, |y| of the next axis (a unit vector) at most this: parallel
_COAXIAL = 1e-12    # |x|, |y| of the next origin at most this times the reach radius: on the same line


def structural_rank_bound(robot, scale: float) -> Optional[int]:
    """An upper bound of the rank of ``robot``'s TCP Jacobian at every configuration from the parallel and coaxial
    neighbours on its TCP chain (``scale``: the reach radius); None when a joint on it is not revolute (the robots
    :func:`robodesign.model.robot_build.walk` builds turn a revolute joint about their frame's ±z)."""
    chain, infos = robot.tcp_chain(), robot.joint_infos
    if not chain or any(infos[j - 1].type != "revolute" for j in chain):
        return None
    placements = robot.kinematic_model.jointPlacements   # (chain: each joint's parent is the one before it)
    bound, lines = 0, 1   # (the runs before the current one; the current run's distinct lines)
    for j in chain[1:]:
        P = placements[j]
        zx, zy = P.rotation[:2, 2].tolist()
        if abs(zx) <= _PARALLEL and abs(zy) <= _PARALLEL:
            tx, ty, _ = P.translation.tolist()
            lines += not (abs(tx) <= _COAXIAL * scale and abs(ty) <= _COAXIAL * scale)
        else:
            bound, lines = bound + min(lines, 3), 1
    return bound + min(lines, 3)


def structural_rank(robot, J: np.ndarray, scale: float, rtol: float) -> Optional[int]:
    """The rank :meth:`Robot.generic_rank` counts when the structure decides it: the structural bound when it is
    below ``min(J.shape)`` and ``J`` (the scaled TCP Jacobian at the first sample) certainly has that rank (the
    module's docstring); None otherwise (and for rtol below 1e-8)."""
    if rtol < 1e-8:
        return None
    bound = structural_rank_bound(robot, scale)
    if bound is None or bound >= min(J.shape) or not certainly_rank_at_least(J, bound, rtol):
        return None
    return bound


def certainly_rank_at_least(J: np.ndarray, r: int, rtol: float) -> bool:
    """Whether at least ``r`` of ``J``'s singular values certainly exceed ``rtol`` times the largest (see the
    module's docstring; False: not shown). Only for rtol ≤ 1e-6, a finite J of at most 1000 columns."""
    if J.ndim != 2 or not J.size or max(J.shape) > 1000 or rtol > 1e-6 or r > min(J.shape):
        return False
    g = (J.T @ J).tolist()
    tr = 0.0
    for i, gi in enumerate(g):
        tr += gi[i]
    if not 0.0 < tr < 1e300:
        return False
    t = tr * max(1e3 * rtol, 1e-5) ** 2
    picked: List[int] = []
    L: List[List[float]] = []
    for k, gk in enumerate(g):
        row: List[float] = []
        for a, la in zip(picked, L):
            s = gk[a]
            for m in range(len(row)):
                s -= row[m] * la[m]
            row.append(s / la[len(row)])
        d = gk[k] - t
        for x in row:
            d -= x * x
        if d > 0.0:
            row.append(math.sqrt(d))
            picked.append(k)
            L.append(row)
            if len(picked) == r:
                return True
    return False
