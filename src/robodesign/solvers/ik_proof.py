"""When the compiled IK descent may answer ``ToleratedPose.valid`` itself (:func:`valid_provable`).

:func:`~robodesign.solvers.ik.solve_ik` accepts a converged descent only when ``goal.valid(T)`` holds: for every
entry ``lo − 1e-12 ≤ v ≤ hi + 1e-12``, v computed from Δ = nominal⁻¹·T (numpy's product). The kernel's
:func:`~robodesign.solvers.ik_kernel.proven_valid` skips that call when its own values prove it true, under these
conditions (so ``valid`` would return True; issue 25: the same solutions, bit for bit):

* every entry of the goal is in the nominal frame, on x, y, z, r_cyl, r_sph or Theta_R, with its bounds infinite or
  within ±:data:`PROOF_BOUND`, and is one of the goal's kernel terms (an entry of a constraint covering its whole
  range has none); the term's proof interval is then the intersection of its entries, which each entry contains;
* the kernel's value of every term lies inside that interval;
* T's rotation entries are within ±1.01 and its position within ±16 m (``ik_kernel.PROOF_ROT``, ``PROOF_POS``), the
  kernel's Ninv likewise, and Ninv lies within :data:`PROOF_NINV` of the tolerance's own nominal⁻¹.

The margin: each entry of Δ is a sum of ≤ 4 products, so both products (any order of the sums, with or without
FMA) lie within γ₄·Σ|N||T| of the exact one (γ₄ = 4u/(1 − 4u), u = 2⁻⁵³); with the bounds Σ|N||T| ≤ 64.5 m for the
position and 3.1 for the rotation, and the inverses add ≤ 1e-15·49 m. So the two Δ differ by < 1.1e-13 m in
position and 6e-15 in rotation. x, y, z then differ by < 1.1e-13 m; r_sph and r_cyl (≤ 112 m, ≤ 3u of rounding on
each side) by < 2.7e-13 m; the angle atan2(s, c), the same formula on both sides, by ≤ 2·|(ds, dc)| < 5e-14 when
s² + c² ≥ 1/4 (the kernel asks it). A bound within ±64 loses ≤ 7.2e-15 to the rounding of ``lo − 1e-12``. Every
margin is below 3.1e-13 < 1e-12, so each of ``valid``'s tests holds (tests/test_ik_proof.py checks the proof against
``valid`` at poses k·1e-13 from their bounds).
"""
from __future__ import annotations

import math

import numpy as np

from robodesign.formats.tolerance import EPS, ToleratedPose

#: the projections the kernel proves (its radial terms)
PROVABLE = frozenset(("x", "y", "z", "r_cyl", "r_sph", "Theta_R"))
#: the largest finite bound of an entry the proof takes
PROOF_BOUND = 64.0
#: the most the kernel's Ninv may differ from the tolerance's nominal⁻¹, per entry
PROOF_NINV = 1e-15


def valid_provable(goal: ToleratedPose, N_inv: np.ndarray) -> bool:
    """Whether the compiled descent may prove ``goal.valid`` true for a goal whose kernel Ninv is ``N_inv`` (the
    module docstring's conditions; ``valid`` the tolerance's own, with its slack of 1e-12)."""
    from robodesign.solvers.ik_kernel import PROOF_POS, PROOF_ROT
    if type(goal).valid is not ToleratedPose.valid or EPS < 1e-12:
        return False
    terms = {c.key for c in goal.constraints if not c.covers_allowed_range()}
    for name, (lo, hi), frame in goal.entries:
        if frame != "nominal" or name not in PROVABLE or (name, frame) not in terms:
            return False
        if any(not (math.isinf(b) or abs(b) <= PROOF_BOUND) for b in (lo, hi)):
            return False
    N = np.asarray(N_inv, dtype=float)[:3]
    own = goal.delta(np.eye(4))[:3]   # the tolerance's nominal⁻¹ (times the identity: the same numbers)
    return bool(np.all(np.abs(N[:, :3]) <= PROOF_ROT) and np.all(np.abs(N[:, 3]) <= PROOF_POS)
                and np.all(np.abs(N - own) <= PROOF_NINV))
