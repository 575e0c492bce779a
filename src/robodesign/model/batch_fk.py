"""Forward kinematics batched over samples: the pinocchio model's joint tree as arrays, and every sample's poses
from it in compiled loops (:mod:`.geometry_kernel`) or, before numba's cache holds them, in one vectorised numpy
pass per joint over all samples (for :func:`fk_batch` and :meth:`Robot.fk_batch
<robodesign.model.robot.Robot.fk_batch>`)."""
from __future__ import annotations

from typing import Any, Dict, Optional, Tuple

import numpy as np
import pinocchio as pin

from robodesign.model import geometry_kernel

_AXES = {"RX": (0, (1.0, 0.0, 0.0)), "RY": (0, (0.0, 1.0, 0.0)), "RZ": (0, (0.0, 0.0, 1.0)),
         "PX": (1, (1.0, 0.0, 0.0)), "PY": (1, (0.0, 1.0, 0.0)), "PZ": (1, (0.0, 0.0, 1.0))}


def _is_plus_z(ax: Tuple[float, ...]) -> bool:
    """``np.allclose(ax, (0, 0, 1), atol=0)`` of a 3-axis, without its ~15 µs: numpy's test per entry is
    ``|a − b| ≤ atol + rtol·|b|`` (rtol 1e-5) or ``a == b``, which for b = 0 is ``a == 0`` and for b = 1 is
    ``|a − 1| ≤ 1e-5`` (NaN fails both)."""
    return ax[0] == 0.0 and ax[1] == 0.0 and abs(ax[2] - 1.0) <= 1e-05


class _BatchKinematics:
    """The pinocchio model's joint tree as arrays (for the current base pose): per joint its parent, the
    placement in the parent (R, t), its kind (0 revolute, 1 prismatic) and unit axis, its q index."""

    def __init__(self, model: "pin.Model"):
        self.parents, self.R, self.t, self.kind, self.axis, self.iq, self.z = [], [], [], [], [], [], []
        for j in range(1, model.njoints):
            jm = model.joints[j]
            name = jm.shortname()
            ax: Tuple[float, ...]
            if name.startswith("JointModel") and name[10:] in _AXES:
                kind, ax = _AXES[name[10:]]
            elif name in ("JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned"):
                kind = 0 if "Revolute" in name else 1
                ax = tuple(float(x) for x in (jm.extract().axis if hasattr(jm, "extract") else jm.axis))
            else:
                raise NotImplementedError(f"batched FK does not model {name}")
            if jm.nq != 1:
                raise NotImplementedError("multi-DoF joint")
            M = model.jointPlacements[j]
            self.parents.append(int(model.parents[j]))
            self.R.append(np.array(M.rotation, dtype=float))
            self.t.append(np.array(M.translation, dtype=float))
            self.kind.append(kind)
            self.axis.append(np.asarray(ax, dtype=float))
            self.iq.append(int(jm.idx_q))
            self.z.append(kind == 0 and _is_plus_z(ax))
        self.model = model
        self.frames: Dict[int, Tuple[int, np.ndarray, np.ndarray]] = {}   # (parent joint, R, t), on first use
        self.njoints = model.njoints
        self._arrays: Optional[tuple] = None

    def _walk(self, Q: np.ndarray, need: Optional[set] = None):
        """World rotation (3×3×N: entry (i, j) of every sample contiguous) and position (3×N) of every
        joint in ``need`` (all if None); index 0 = the world (None: identity)."""
        N = len(Q)
        Rs: Dict[int, Optional[np.ndarray]] = {0: None}
        ps: Dict[int, Optional[np.ndarray]] = {0: None}
        QT = np.ascontiguousarray(Q.T)
        for j in range(1, self.njoints):
            if need is not None and j not in need:
                continue
            k = j - 1
            par = self.parents[k]
            Rl, tl = self.R[k], self.t[k]
            Rpar, ppar = Rs[par], ps[par]
            if Rpar is None or ppar is None:  # the world (both None)
                Rp = np.repeat(Rl[:, :, None], N, axis=2)
                pp = np.repeat(tl[:, None], N, axis=1)
            else:   # (R·Rl)[i] = Rlᵀ-combination of the columns of R[i]: three (3×3)·(3×N) products
                Rp = np.matmul(Rl.T, Rpar)
                pp = ppar + np.matmul(tl, Rpar)
            q = QT[self.iq[k]]
            a = self.axis[k]
            if self.kind[k] == 1:                 # prismatic: p += R·a·q
                R = Rp
                p = pp + np.matmul(a, Rp) * q
            elif self.z[k]:                       # revolute about +z: mix columns 0 and 1
                c, s = np.cos(q), np.sin(q)
                c0, c1 = Rp[:, 0], Rp[:, 1]
                R = np.empty_like(Rp)
                R[:, 0] = c0 * c + c1 * s
                R[:, 1] = c1 * c - c0 * s
                R[:, 2] = Rp[:, 2]
                p = pp
            else:                                 # revolute about a: Rodrigues, R·Rj
                c, s = np.cos(q), np.sin(q)
                K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
                Rj = np.eye(3)[:, :, None] + s * K[:, :, None] + (1.0 - c) * (K @ K)[:, :, None]   # 3×3×N
                R = np.einsum("ikn,kjn->ijn", Rp, Rj)
                p = pp
            Rs[j], ps[j] = R, p
        return Rs, ps

    def _needed(self, j: int) -> set:
        need = set()
        while j > 0:
            need.add(j)
            j = self.parents[j - 1]
        return need

    def arrays(self) -> tuple:
        """The joint tree as the compiled kernels take it (:mod:`.geometry_kernel`): parents, placements (R, t),
        kinds, axes, q indices; and scratch space for the joints' world poses."""
        if self._arrays is None:
            J = len(self.parents)
            self._arrays = ((np.array(self.parents, np.int64), np.array(self.R, float).reshape(J, 3, 3),
                             np.array(self.t, float).reshape(J, 3), np.array(self.kind, np.int64),
                             np.array(self.axis, float).reshape(J, 3), np.array(self.iq, np.int64)),
                            (np.zeros((J + 1, 3, 3)), np.zeros((J + 1, 3))))
        return self._arrays

    def frame_poses(self, Q: np.ndarray, frame: int) -> np.ndarray:
        hit = self.frames.get(frame)
        if hit is None:
            fr = self.model.frames[frame]
            hit = self.frames[frame] = (int(fr.parentJoint), np.array(fr.placement.rotation, dtype=float),
                                        np.array(fr.placement.translation, dtype=float))
        jid, Rf, tf = hit
        if geometry_kernel.ready():
            tree, work = self.arrays()
            out = np.empty((len(Q), 4, 4))
            kernel: Any = geometry_kernel.frame_poses    # (numba's stub takes one argument)
            kernel(np.ascontiguousarray(Q, dtype=float), *tree, jid, Rf, tf, *work, out)
            return out
        Rs, ps = self._walk(Q, self._needed(jid))
        N = len(Q)
        out = np.zeros((N, 4, 4))
        out[:, 3, 3] = 1.0
        if Rs[jid] is None:
            out[:, :3, :3] = Rf
            out[:, :3, 3] = tf
        else:
            out[:, :3, :3] = np.matmul(Rf.T, Rs[jid]).transpose(2, 0, 1)
            out[:, :3, 3] = (ps[jid] + np.matmul(tf, Rs[jid])).T
        return out

    def joint_poses(self, Q: np.ndarray) -> np.ndarray:
        if geometry_kernel.ready():
            tree, work = self.arrays()
            out = np.empty((len(Q), self.njoints, 4, 4))
            kernel: Any = geometry_kernel.joint_poses    # (numba's stub takes one argument)
            kernel(np.ascontiguousarray(Q, dtype=float), *tree, *work, out)
            return out
        Rs, ps = self._walk(Q)
        N = len(Q)
        out = np.zeros((N, self.njoints, 4, 4))
        out[:, :, 3, 3] = 1.0
        out[:, 0, :3, :3] = np.eye(3)
        for j in range(1, self.njoints):
            out[:, j, :3, :3] = Rs[j].transpose(2, 0, 1)
            out[:, j, :3, 3] = ps[j].T
        return out


_TREES: Dict[tuple, tuple] = {}   # (id(module set), assembly key) → (module set, _BatchKinematics of such a robot)


def _adopted(kept: _BatchKinematics, model: "pin.Model") -> _BatchKinematics:
    """``_BatchKinematics(model)`` of a model of ``kept``'s module set and assembly: a base pose changes only the
    root joints' placements (those on the base), so ``kept``'s tree (its lists shared, never changed) with those
    read from ``model``, and its kernel arrays with those rows."""
    out = object.__new__(_BatchKinematics)
    out.parents, out.kind, out.axis, out.iq, out.z = kept.parents, kept.kind, kept.axis, kept.iq, kept.z
    out.R, out.t = list(kept.R), list(kept.t)
    tree, _ = kept.arrays()
    R, t = tree[1].copy(), tree[2].copy()
    for k, parent in enumerate(out.parents):
        if parent == 0:
            M = model.jointPlacements[k + 1]
            out.R[k], out.t[k] = np.array(M.rotation, dtype=float), np.array(M.translation, dtype=float)
            R[k], t[k] = out.R[k], out.t[k]
    out.model, out.frames, out.njoints = model, {}, model.njoints
    J = len(out.parents)
    out._arrays = ((tree[0], R, t) + tree[3:], (np.zeros((J + 1, 3, 3)), np.zeros((J + 1, 3))))
    return out


def batch_kinematics(robot) -> _BatchKinematics:
    """The robot's :class:`_BatchKinematics` (kept on the robot, ``_batch_chain``, until its base pose changes),
    made of the last one of a robot of the same module set and assembly when there is one (:func:`_adopted`; the
    same arrays, tests/test_fk_trees.py)."""
    if robot._batch_chain is None:
        ms, assembly = getattr(robot, "module_set", None), getattr(robot, "assembly", None)
        key = (id(ms), assembly.key()) if ms is not None and assembly is not None else None
        kept = _TREES.get(key) if key is not None else None
        if kept is not None and kept[0] is ms:
            robot._batch_chain = _adopted(kept[1], robot.kinematic_model)
        else:
            robot._batch_chain = _BatchKinematics(robot.kinematic_model)
            if key is not None:
                if len(_TREES) >= 64:
                    _TREES.clear()
                _TREES[key] = (ms, robot._batch_chain)
    return robot._batch_chain


def fk_batch(robot, Q, frame: Optional[int] = None) -> np.ndarray:
    """World poses (N×4×4) of ``frame`` (default: the TCP) at every row of ``Q`` (N×dof, or one
    configuration): the compiled loop over the samples (or, before it is compiled, one vectorised pass of
    numpy per joint of the frame's chain) instead of one pinocchio call per sample. Revolute and prismatic joints
    about any fixed axis (every joint a :class:`~robodesign.model.robot.Robot` builds); another joint type falls
    back to ``robot.fk`` per row.
    Equal to ``robot.fk`` to floating-point rounding (tests/test_fk_batch.py)."""
    Q = robot._Q(Q)
    f = robot.tcp_frame if frame is None else int(frame)
    try:
        bk = batch_kinematics(robot)
    except NotImplementedError:
        return np.array([robot.fk(q, f) for q in Q]).reshape(len(Q), 4, 4)
    return bk.frame_poses(Q, f)
