"""Symbolic (CasADi SX) kinematics and inverse dynamics built from a robot's pinocchio model.

The ``pin`` wheel has no ``pinocchio.casadi``, so robodesign builds the expressions itself from the
model data: joint placements ``model.jointPlacements``, parents ``model.parents``, (merged) link
inertias ``model.inertias``, joint types (``model.joints[i].shortname()``) and ``model.gravity``.
Everything is SX, so the functions can be inlined and ``expand``-ed inside an NLP (5× faster ipopt
iterations than MX, see the dependency notes).

Supported joints: revolute and prismatic about/along x, y, z (``RX, RY, RZ, PX, PY, PZ``) and about
any axis (``RevoluteUnaligned``, ``PrismaticUnaligned``), on any kinematic tree; 1-DoF joints only
(what :class:`robodesign.model.robot.Robot` builds).

Conventions follow pinocchio: spatial motions (v, ω) and forces (f, n) are expressed in the local
joint frame; the base acceleration is −gravity (so the result includes gravity).

* :func:`casadi_rnea` — link-side RNEA, equal to ``Robot.rnea`` (pinocchio's ``rnea`` minus the
  armature term, which pinocchio ≥ 3 includes); ``include_armature=True`` gives ``pin.rnea`` itself.
* :func:`casadi_drivetrain_torque` — ``Robot.drivetrain_torques``: RNEA + k²·I_m·q̈ + f_v·q̇ +
  f_c·sin(atan(100·q̇)).
* :func:`casadi_fk` — world position (3,) and rotation (3×3) of a frame (default: the TCP).
"""
from __future__ import annotations

from typing import Any, List, Optional, Tuple

import casadi as ca
import numpy as np
import pinocchio as pin

from robodesign.model.robot import COULOMB_SMOOTHING


def _model(robot) -> pin.Model:
    return robot if isinstance(robot, pin.Model) else robot.model


def _axis(jm) -> Tuple[str, np.ndarray]:
    """('R' or 'P', unit axis) of a 1-DoF joint model."""
    name = jm.shortname()
    fixed = {"JointModelRX": ("R", [1, 0, 0]), "JointModelRY": ("R", [0, 1, 0]), "JointModelRZ": ("R", [0, 0, 1]),
             "JointModelPX": ("P", [1, 0, 0]), "JointModelPY": ("P", [0, 1, 0]), "JointModelPZ": ("P", [0, 0, 1])}
    if name in fixed:
        kind, ax = fixed[name]
        return kind, np.array(ax, dtype=float)
    if name in ("JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned"):
        ext = jm.extract() if hasattr(jm, "extract") else jm
        axis = np.asarray(ext.axis, dtype=float).reshape(3)
        return ("R" if "Revolute" in name else "P"), axis / np.linalg.norm(axis)
    raise NotImplementedError(f"joint type {name} is not supported by casadi_dynamics (1-DoF R*/P* joints only)")


def _rot(axis: np.ndarray, q):
    """Rotation matrix about a constant unit axis (Rodrigues), SX."""
    c, s = ca.cos(q), ca.sin(q)
    x, y, z = (float(a) for a in axis)
    if (x, y, z) == (0.0, 0.0, 1.0):
        return ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1))
    if (x, y, z) == (1.0, 0.0, 0.0):
        return ca.vertcat(ca.horzcat(1, 0, 0), ca.horzcat(0, c, -s), ca.horzcat(0, s, c))
    if (x, y, z) == (0.0, 1.0, 0.0):
        return ca.vertcat(ca.horzcat(c, 0, s), ca.horzcat(0, 1, 0), ca.horzcat(-s, 0, c))
    K = ca.DM(np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]]))
    return ca.DM.eye(3) + s * K + (1 - c) * (K @ K)


class _Joint:
    __slots__ = ("kind", "axis", "idx", "parent", "R0", "p0")

    def __init__(self, model: pin.Model, i: int):
        jm = model.joints[i]
        if jm.nq != 1 or jm.nv != 1:
            raise NotImplementedError(f"joint {model.names[i]} has nq={jm.nq}, nv={jm.nv}; only 1-DoF joints")
        self.kind, self.axis = _axis(jm)
        self.idx = jm.idx_v
        self.parent = model.parents[i]
        M = model.jointPlacements[i]
        self.R0, self.p0 = np.array(M.rotation), np.array(M.translation)

    def placement(self, q):
        """(R, p) of the joint frame (after the motion q) in its parent joint's frame."""
        if self.kind == "R":
            return ca.DM(self.R0) @ _rot(self.axis, q), ca.DM(self.p0)
        return ca.DM(self.R0), ca.DM(self.p0) + ca.DM(self.R0) @ ca.DM(self.axis) * q


def _joints(model: pin.Model) -> List[_Joint]:
    return [_Joint(model, i) for i in range(1, model.njoints)]


def rnea_expr(model: pin.Model, q, dq, ddq, include_armature: bool = False):
    """SX expression of RNEA τ(q, q̇, q̈) for symbolic column vectors q, dq, ddq (length nv)."""
    joints = _joints(model)
    n = model.njoints
    g = np.array(model.gravity.linear, dtype=float)
    v: List = [None] * n
    w: List = [None] * n
    a: List = [None] * n
    al: List = [None] * n
    Rl: List = [None] * n
    pl: List = [None] * n
    f: List = [None] * n
    nt: List = [None] * n
    zero = ca.SX.zeros(3, 1)
    v[0], w[0], a[0], al[0] = zero, zero, ca.SX(ca.DM(-g)), zero
    for i, J in enumerate(joints, start=1):
        R, p = J.placement(q[J.idx])
        Rl[i], pl[i] = R, p
        lam = J.parent
        # parent motion expressed in frame i: ω_i = Rᵀω, v_i = Rᵀ(v + ω × p)
        wi = R.T @ w[lam]
        vi = R.T @ (v[lam] + ca.cross(w[lam], p))
        ali = R.T @ al[lam]
        ai = R.T @ (a[lam] + ca.cross(al[lam], p))
        S = ca.DM(J.axis)
        qd, qdd = dq[J.idx], ddq[J.idx]
        if J.kind == "R":
            wJ, vJ = S * qd, zero
            aJw, aJv = S * qdd, zero
        else:
            wJ, vJ = zero, S * qd
            aJw, aJv = zero, S * qdd
        # a_i = X a_λ + S q̈ + v_i × S q̇   (spatial cross product with v_i before adding S q̇)
        ai = ai + aJv + ca.cross(wi, vJ) + ca.cross(vi, wJ)
        ali = ali + aJw + ca.cross(wi, wJ)
        wi = wi + wJ
        vi = vi + vJ
        v[i], w[i], a[i], al[i] = vi, wi, ai, ali
        Y = model.inertias[i]
        m, c, Ic = float(Y.mass), ca.DM(np.array(Y.lever)), ca.DM(np.array(Y.inertia))
        # h = I·(v, ω): linear m(v − c×ω), angular Ic ω + c × linear   (Ic about the CoM)
        def inertia_mul(lin, ang):
            hl = m * (lin - ca.cross(c, ang))
            return hl, Ic @ ang + ca.cross(c, hl)
        fa_l, fa_n = inertia_mul(ai, ali)
        hv_l, hv_n = inertia_mul(vi, wi)
        # f = I a + v ×* (I v): (ω × h_l, ω × h_n + v × h_l)
        f[i] = fa_l + ca.cross(wi, hv_l)
        nt[i] = fa_n + ca.cross(wi, hv_n) + ca.cross(vi, hv_l)
    tau: List[Any] = [None] * model.nv  # one SX per dof, each set in the loop below
    for i in range(n - 1, 0, -1):
        J = joints[i - 1]
        S = ca.DM(J.axis)
        tau[J.idx] = (S.T @ nt[i]) if J.kind == "R" else (S.T @ f[i])
        lam = J.parent
        if lam > 0:
            R, p = Rl[i], pl[i]
            fl = R @ f[i]
            f[lam] = f[lam] + fl
            nt[lam] = nt[lam] + R @ nt[i] + ca.cross(p, fl)
    out = ca.vertcat(*tau)
    if include_armature:
        out = out + ca.DM(np.asarray(model.armature, float)) * ddq
    return out


def casadi_rnea(robot, include_armature: bool = False) -> ca.Function:
    """``Function('rnea', [q, dq, ddq], [tau])`` (SX). Link-side by default (= ``Robot.rnea``);
    ``include_armature=True`` adds k²·I_m·q̈ (= ``pinocchio.rnea``)."""
    model = _model(robot)
    nv = model.nv
    q, dq, ddq = ca.SX.sym("q", nv), ca.SX.sym("dq", nv), ca.SX.sym("ddq", nv)
    tau = rnea_expr(model, q, dq, ddq, include_armature)
    return ca.Function("rnea", [q, dq, ddq], [tau], ["q", "dq", "ddq"], ["tau"])


def casadi_drivetrain_torque(robot) -> ca.Function:
    """``Function('drivetrain_torque', [q, dq, ddq], [tau])`` (SX) equal to ``Robot.drivetrain_torques``:
    τ = RNEA + armature·q̈ + f_v·q̇ + f_c·sin(atan(100·q̇))."""
    model = _model(robot)
    nv = model.nv
    fv = np.asarray(getattr(robot, "friction_viscous", np.zeros(nv)), float)
    fc = np.asarray(getattr(robot, "friction_coulomb", np.zeros(nv)), float)
    q, dq, ddq = ca.SX.sym("q", nv), ca.SX.sym("dq", nv), ca.SX.sym("ddq", nv)
    tau = rnea_expr(model, q, dq, ddq, include_armature=True)
    tau = tau + ca.DM(fv) * dq + ca.DM(fc) * ca.sin(ca.atan(COULOMB_SMOOTHING * dq))
    return ca.Function("drivetrain_torque", [q, dq, ddq], [tau], ["q", "dq", "ddq"], ["tau"])


def fk_expr(model: pin.Model, q, frame_id: int):
    """SX (p (3,1), R (3,3)) of a frame's world pose."""
    joints = _joints(model)
    fr = model.frames[frame_id]
    # chain from the frame's joint back to the universe
    chain = []
    j = fr.parentJoint
    while j > 0:
        chain.append(j)
        j = model.parents[j]
    R, p = ca.SX.eye(3), ca.SX.zeros(3, 1)
    for j in reversed(chain):
        Rj, pj = joints[j - 1].placement(q[joints[j - 1].idx])
        p = p + R @ pj
        R = R @ Rj
    Mf = fr.placement
    p = p + R @ ca.DM(np.array(Mf.translation))
    R = R @ ca.DM(np.array(Mf.rotation))
    return p, R


def casadi_fk(robot, frame_id: Optional[int] = None) -> ca.Function:
    """``Function('fk', [q], [p, R])`` (SX): world position (3×1) and rotation (3×3) of a frame
    (default: the robot's TCP), equal to ``Robot.fk(q, frame_id)``."""
    model = _model(robot)
    if frame_id is None:
        frame_id = robot.tcp_frame
    q = ca.SX.sym("q", model.nq)
    p, R = fk_expr(model, q, int(frame_id))
    return ca.Function("fk", [q], [p, R], ["q"], ["p", "R"])
