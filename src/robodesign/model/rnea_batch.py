"""pinocchio's inverse dynamics (RNEA) at many samples in one call: the time scaling's path terms and torque
check (robodesign.solvers.timing) and the judge's torques at the samples (robodesign.judge.quantities), issue 25.

``pinocchio.rneaInParallel`` with one thread runs pinocchio's own ``rnea`` once per column of its batch on a model
pool's copy of the model: the same algorithm on the same numbers, so the same torques **bit for bit** as one
``pinocchio.rnea`` call per sample (tests/test_rnea_batch.py), without Python's cost per call (about 4 µs of a
4.3 µs call on a 6-joint arm; 1.4 µs per sample batched). A pinocchio without it gets the loop of single calls.

A model's copy is kept per model and used again only while the model equals it (pinocchio's ``Model ==`` compares
every parameter, 1.4 µs): a robot's model changes with its base pose and gravity (``Robot.set_base_pose``,
``Robot.set_gravity``), and equal models give equal torques. Each of the two pools (with and without armature) is
made from that copy at its first ask, ~50 µs each: the judge's robot only ever asks for the link side's.
(``rneaInParallel`` sets OpenMP's thread count of the calling thread to 1.)

A model of revolute and prismatic joints about their frames' axes runs the compiled RNEA of
:mod:`robodesign.model.rnea_kernel` instead, once its kernel is compiled: pinocchio's operations in pinocchio's
order, the same torques bit for bit (tests/test_rnea_kernel.py), ~1.5× faster per sample. Its arrays are
packed once per kept copy, like the pools, at the first call of at least KERNEL_ROWS samples: packing (~60 µs) costs
more than a pool (~30 µs), and pays from some 80 samples on (the time scaling's ~1,650 per new arm, not the
planner's static torque tests of a few). A packed model is used only after the kernel gave this pinocchio's torques
bit for bit on a few of its samples (another pinocchio build, with fused multiply-adds for one, keeps pinocchio).
"""
from __future__ import annotations

from typing import Dict, List, Optional

import numpy as np
import pinocchio as pin

from robodesign.model import rnea_kernel

KERNEL_ROWS = 64  # the fewest samples a call runs the compiled RNEA on (fewer: pinocchio's pool)
_UNPACKED = ()   # a kept copy's kernel arrays not packed yet
# id(model) → [its copy, its pool or None, the link-side pool or None, its kernel arrays, the link side's]
# (kernel arrays: _UNPACKED, or None when the kernel does not cover the model)
_POOLS: Dict[int, List[object]] = {}


def _kept(model) -> List[object]:
    """The entry kept for ``model``: made again (its pools and arrays dropped) when ``model`` changed."""
    hit = _POOLS.get(id(model))
    if hit is None or not hit[0] == model:
        if len(_POOLS) >= 64:
            _POOLS.clear()
        hit = _POOLS[id(model)] = [pin.Model(model), None, None, _UNPACKED, _UNPACKED]
    return hit


def _packed(model, link_side: bool) -> Optional[rnea_kernel.Packed]:
    """The compiled RNEA's arrays for ``model`` (``link_side``: without armature), None when it does not cover
    the model; packed from the kept copy at the first ask."""
    hit = _kept(model)
    i = 4 if link_side else 3
    if hit[i] is _UNPACKED:
        packed = rnea_kernel.pack(hit[0], armature=not link_side)
        hit[i] = packed if packed is not None and _same_as_pinocchio(hit[0], packed, link_side) else None
    return hit[i]  # type: ignore[return-value]


def _same_as_pinocchio(model, packed: rnea_kernel.Packed, link_side: bool) -> bool:
    """Whether the compiled RNEA gives this pinocchio's torques bit for bit on a few samples of ``model`` (moderate
    and large values, a zero velocity row): a pinocchio built with other floating-point operations (fused
    multiply-adds, another summation order) keeps its own RNEA for the model, so results never depend on whether
    the kernel ran (~20 µs, once per packed model)."""
    rng = np.random.default_rng(0)
    Q, V, A = (rng.uniform(-s, s, (3, model.nv)) for s in (4.0, 10.0, 300.0))
    V[0] = 0.0
    model = _without_armature(model) if link_side else model
    data = model.createData()
    ref = np.array([pin.rnea(model, data, Q[k], V[k], A[k]) for k in range(3)])
    return bool(ref.tobytes() == rnea_kernel.rnea(*packed + (Q, V, A)).tobytes())


def _without_armature(model):
    """A copy of ``model`` without motor inertia (armature): Robot.link_torques' model."""
    bare = pin.Model(model)
    bare.armature = np.zeros(model.nv)
    return bare


def _pool(model, link_side: bool):
    """The pool of ``model`` (``link_side``: of the same model without motor inertia, armature), made from the copy
    kept for ``model`` at its first ask."""
    hit = _kept(model)
    i = 2 if link_side else 1
    if hit[i] is None:
        hit[i] = pin.ModelPool(_without_armature(hit[0]) if link_side else hit[0], 1)
    return hit[i]


def rnea_rows(model, Q: np.ndarray, V: np.ndarray, A: np.ndarray, link_side: bool = False) -> np.ndarray:
    """(N, nv) ``pinocchio.rnea(model, data, Q[k], V[k], A[k])`` for every row k; ``link_side``: on the model
    without armature (the link-side torques of ``Robot.link_torques``): the compiled RNEA when it covers the model,
    is compiled and there are at least KERNEL_ROWS samples, else pinocchio's (the same numbers)."""
    Q, V, A = (np.ascontiguousarray(x, dtype=float) for x in (Q, V, A))
    if len(Q) == 0:
        return np.empty((0, model.nv))
    packed = _packed(model, link_side) if Q.ndim == 2 and len(Q) >= KERNEL_ROWS and rnea_kernel.ready() else None
    if packed is not None:
        return rnea_kernel.rnea(*packed + (Q, V, A))
    if not hasattr(pin, "rneaInParallel"):   # pragma: no cover - pinocchio < 3
        model = _without_armature(model) if link_side else model
        data = model.createData()
        return np.array([pin.rnea(model, data, Q[k], V[k], A[k]) for k in range(len(Q))])
    pool = _pool(model, link_side)
    out = pin.rneaInParallel(1, pool, Q.T, V.T, A.T)   # (nv, N); (nv,) for one sample
    return np.ascontiguousarray(np.reshape(out, (model.nv, len(Q))).T)
