"""pinocchio's inverse dynamics (RNEA) at many samples in one call, for the time scaling (issue 25).

``pinocchio.rneaInParallel`` with one thread runs pinocchio's own ``rnea`` once per column of its batch on a model
pool's copy of the model: the same algorithm on the same numbers, so the same torques **bit for bit** as one
``pinocchio.rnea`` call per sample (tests/test_rnea_batch.py), without Python's cost per call (about 4 µs of a
4.3 µs call on a 6-joint arm; 1.4 µs per sample batched). A pinocchio without it gets the loop of single calls.
The pool copies the model when it is made, so it is made per call: a robot's model changes with its base pose and
gravity (``Robot.set_base_pose``, ``Robot.set_gravity``).
"""
from __future__ import annotations

import numpy as np
import pinocchio as pin


def rnea_rows(model, Q: np.ndarray, V: np.ndarray, A: np.ndarray) -> np.ndarray:
    """(N, nv) ``pinocchio.rnea(model, data, Q[k], V[k], A[k])`` for every row k."""
    Q, V, A = (np.asarray(x, dtype=float) for x in (Q, V, A))
    if len(Q) == 0:
        return np.empty((0, model.nv))
    if not hasattr(pin, "rneaInParallel"):   # pragma: no cover - pinocchio < 3
        data = model.createData()
        return np.array([pin.rnea(model, data, Q[k], V[k], A[k]) for k in range(len(Q))])
    out = pin.rneaInParallel(1, pin.ModelPool(model, 1), Q.T, V.T, A.T)   # (nv, N); (nv,) for one sample
    return np.ascontiguousarray(np.reshape(out, (model.nv, len(Q))).T)


def link_model(robot):
    """A copy of ``robot``'s pinocchio model without motor inertia (armature): the link-side RNEA of
    ``Robot.link_torques``, which makes the same copy."""
    m = pin.Model(robot.model)
    m.armature = np.zeros(robot.model.nv)
    return m
