"""Batched inverse kinematics: many seeds at once, vectorised in numpy over a serial joint chain.

The sequential solver (:mod:`robodesign.solvers.ik`) runs one Levenberg–Marquardt attempt after the
other; each attempt pays Python overhead per iteration. Here all N seeds iterate together: forward
kinematics and the world-aligned Jacobian of the TCP are computed with batched Rodrigues rotations and
matrix products over the chain (a few dozen numpy calls per iteration for all seeds), and the damped
least-squares steps are solved as one stacked linear system. 64 seeds × 40 iterations cost about as
much as two or three sequential attempts.

The error drives the TCP to the goal's *nominal* pose; rotation components the tolerance leaves free
(e.g. the rotation about the tool axis when only N_x/N_y are bounded) get weight 0. Converged seeds are
verified exactly (``goal.valid``) and checked for collisions before they count.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Dict, List, Optional

import numpy as np

from ..tolerance import ToleratedPose

_ALL_ROT = {"Theta_R", "R", "P", "Y", "Alpha", "Beta", "Gamma", "A", "B", "C", "D"}


class ChainKinematics:
    """Vectorised FK and Jacobian of the joint chain from the base to the TCP of a :class:`Robot`."""

    def __init__(self, robot):
        m = robot.model
        fr = m.frames[robot.tcp_frame]
        chain = []
        j = fr.parentJoint
        while j > 0:
            chain.append(j)
            j = m.parents[j]
        chain.reverse()
        if len(chain) != robot.dof:
            raise ValueError("batched IK needs every joint on the TCP's chain")
        self.placements = np.array([m.jointPlacements[j].homogeneous for j in chain])  # (n,4,4)
        axes, revolute, idx = [], [], []
        for j in chain:
            jm = m.joints[j]
            name = jm.shortname()
            if name in ("JointModelRZ", "JointModelPZ"):
                a = np.array([0.0, 0.0, 1.0])
            elif name in ("JointModelRX", "JointModelPX"):
                a = np.array([1.0, 0.0, 0.0])
            elif name in ("JointModelRY", "JointModelPY"):
                a = np.array([0.0, 1.0, 0.0])
            elif "Unaligned" in name:
                a = np.asarray(jm.extract().axis if hasattr(jm, "extract") else jm.axis, dtype=float)
            else:
                raise ValueError(f"batched IK does not support {name}")
            axes.append(a / np.linalg.norm(a))
            revolute.append("Revolute" in name or name.startswith("JointModelR"))
            idx.append(jm.idx_q)
        self.axes = np.array(axes)
        self.revolute = np.array(revolute)
        self.idx = np.array(idx)
        self.tcp = fr.placement.homogeneous.copy()
        self.n = len(chain)
        self._I3 = np.eye(3)
        self._K = np.array([[[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]] for a in self.axes])
        self._K2 = self._K @ self._K

    def fk_jac(self, Q: np.ndarray):
        """TCP poses (N,4,4) and world-aligned Jacobians (N,6,n) for configurations Q (N,n)."""
        N = len(Q)
        R = np.broadcast_to(np.eye(3), (N, 3, 3))
        p = np.zeros((N, 3))
        origins = np.empty((self.n, N, 3))
        zs = np.empty((self.n, N, 3))
        for k in range(self.n):
            P = self.placements[k]
            p = p + R @ P[:3, 3]
            R = R @ P[:3, :3]
            a = self.axes[k]
            q = Q[:, self.idx[k]]
            origins[k] = p
            z = R @ a
            zs[k] = z
            if self.revolute[k]:
                s_, c_ = np.sin(q)[:, None, None], np.cos(q)[:, None, None]
                R = R @ (self._I3 + s_ * self._K[k] + (1.0 - c_) * self._K2[k])
            else:
                p = p + q[:, None] * z
        p = p + R @ self.tcp[:3, 3]
        R = R @ self.tcp[:3, :3]
        T = np.empty((N, 4, 4))
        T[:, :3, :3] = R
        T[:, :3, 3] = p
        T[:, 3] = (0.0, 0.0, 0.0, 1.0)
        J = np.empty((N, 6, self.n))
        d = p[None] - origins  # (n,N,3)
        cr = zs[..., [1, 2, 0]] * d[..., [2, 0, 1]] - zs[..., [2, 0, 1]] * d[..., [1, 2, 0]]
        rev = self.revolute
        J[:, :3, :] = np.where(rev[:, None, None], cr, zs).transpose(1, 2, 0)
        J[:, 3:, :] = np.where(rev[:, None, None], zs, 0.0).transpose(1, 2, 0)
        return T, J


def _log3_batch(R: np.ndarray) -> np.ndarray:
    """Rotation vectors (N,3) of rotation matrices (N,3,3)."""
    c = np.clip((np.trace(R, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    th = np.arccos(c)
    v = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], axis=1)
    s = np.sin(th)
    small = s < 1e-6
    out = np.where(small[:, None], 0.5 * v, v * (th / np.where(small, 1.0, 2.0 * s))[:, None])
    near_pi = small & (th > 3.0)
    if np.any(near_pi):  # θ ≈ π: axis from the diagonal
        for i in np.nonzero(near_pi)[0]:
            d = np.sqrt(np.maximum((np.diag(R[i]) + 1.0) / 2.0, 0.0))
            k = int(np.argmax(d))
            axis = R[i][:, k] / (2 * d[k]) if d[k] > 1e-9 else np.array([1.0, 0, 0])
            axis[k] = d[k]
            out[i] = axis / np.linalg.norm(axis) * th[i]
    return out


def rotation_weights(goal: ToleratedPose) -> np.ndarray:
    """Weights of the rotation-error components (in the nominal frame) the tolerance constrains."""
    names = {e[0] for e in goal.entries}
    if names & _ALL_ROT:
        return np.ones(3)
    return np.array([float("N_x" in names), float("N_y" in names), float("N_z" in names)])


@dataclass
class BatchIKResult:
    solutions: List[np.ndarray]
    stats: Dict[str, object] = field(default_factory=dict)

    def __bool__(self) -> bool:
        return bool(self.solutions)


def batch_ik(robot, goal: ToleratedPose, rng, n_seeds: int = 64, max_iter: int = 40, check_collision: bool = True,
             n_solutions: int = 1, distinct_tol: float = 0.1, seeds: Optional[np.ndarray] = None,
             chain: Optional[ChainKinematics] = None) -> BatchIKResult:
    chain = chain or ChainKinematics(robot)
    lo = np.where(np.isfinite(robot.q_lower), robot.q_lower, -math.pi)
    hi = np.where(np.isfinite(robot.q_upper), robot.q_upper, math.pi)
    Q = rng.uniform(lo, hi, size=(n_seeds, robot.dof)) if seeds is None else np.array(seeds, dtype=float)
    Tg = np.asarray(goal.nominal, dtype=float)
    Rg, pg = Tg[:3, :3], Tg[:3, 3]
    wr = rotation_weights(goal) * 0.5  # metres per radian
    active = np.ones(len(Q), dtype=bool)
    conv = np.zeros(len(Q), dtype=bool)
    last_err = np.full(len(Q), np.inf)
    checkpoint = np.full(len(Q), np.inf)
    iterations = 0
    n = robot.dof
    eye = np.eye(n)
    for it in range(max_iter):
        idx = np.nonzero(active)[0]
        if len(idx) == 0:
            break
        T, J = chain.fk_jac(Q[idx])
        ep = T[:, :3, 3] - pg  # world
        er_w = _log3_batch(T[:, :3, :3] @ Rg.T)  # world frame rotation error
        # weight the rotation error in the goal frame (free axes → 0)
        er_g = er_w @ Rg  # = Rgᵀ·er_w per row
        e = np.concatenate([ep, (er_g * wr) @ Rg.T], axis=1)
        Jw = J.copy()
        Jw[:, 3:] = np.einsum("ij,njk->nik", Rg @ np.diag(wr) @ Rg.T, J[:, 3:])
        err2 = np.einsum("ni,ni->n", e, e)
        if it % 6 == 5:  # drop seeds that stalled (error not down by 10 % in 6 iterations) far from the goal
            stalled = (err2 > 0.9 * checkpoint[idx]) & (err2 > 1e-4)
            checkpoint[idx] = err2
        else:
            stalled = np.zeros(len(idx), dtype=bool)
        if it == 0:
            checkpoint[idx] = err2
        last_err[idx] = err2
        done = (err2 < 1e-10) | stalled
        active[idx[stalled]] = False
        conv[idx[done & ~stalled]] = True
        active[idx[done]] = False
        go = ~done
        if not np.any(go):
            break
        iterations += 1
        Jg, eg = Jw[go], e[go]
        lam = 1e-6 + 0.5 * err2[go]
        A = np.einsum("nji,njk->nik", Jg, Jg) + lam[:, None, None] * eye
        b = np.einsum("nji,nj->ni", Jg, eg)
        dq = -np.linalg.solve(A, b[..., None])[..., 0]
        m = np.abs(dq).max(axis=1, keepdims=True)
        dq = np.where(m > 1.0, dq / np.maximum(m, 1e-12), dq)
        ii = idx[go]
        Q[ii] = np.clip(Q[ii] + dq, lo, hi)
    sols: List[np.ndarray] = []
    checked = rejected_tol = rejected_col = 0
    # exact check only for seeds that got close (within 1 cm / 0.02 rad weighted); best first
    near = np.nonzero(conv | (last_err < 1e-4))[0]
    for i in near[np.argsort(last_err[near], kind="stable")]:
        q = Q[i]
        checked += 1
        if not goal.valid(robot.fk(q)):
            rejected_tol += 1
            continue
        if check_collision and robot.in_collision(q):
            rejected_col += 1
            continue
        if any(np.linalg.norm(q - s) <= distinct_tol for s in sols):
            continue
        sols.append(q.copy())
        if len(sols) >= n_solutions:
            break
    return BatchIKResult(sols, {"seeds": len(Q), "converged": int(conv.sum()), "checked": checked,
                                "rejected_tolerance": rejected_tol, "rejected_collision": rejected_col,
                                "iterations": iterations})
