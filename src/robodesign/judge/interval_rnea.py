"""Inverse dynamics over a box: enclosures of the link-side torque and of its rate along a constant-acceleration arc.

Over a piece of one arc of the judged motion (:mod:`robodesign.judge.motion`) every joint moves with a constant
acceleration a, so q(t) ranges over an interval Q, q̇(t) = v₀ + a·t over an interval V, and q̈ = a. The
recursive Newton–Euler algorithm (RNEA, pinocchio's convention: local joint frames, gravity as an upward
acceleration of the base) is evaluated here in **dual interval arithmetic**: every quantity is a pair
(value interval, interval of its time derivative along the arc), with the time derivatives of the inputs
(q̇ for q, a for q̇, 0 for q̈). The result encloses, for every instant of the piece, the link-side torque
RNEA(q(t), q̇(t), a) and its rate d/dt RNEA(q(t), q̇(t), a): no Lipschitz constant is guessed, each bound
follows from the model's masses, inertias and placements and the piece's box. Intervals are kept as
(midpoint, radius) arrays vectorised over pieces; a product of (m₁, r₁) and (m₂, r₂) is (m₁m₂, |m₁|r₂ + r₁|m₂|
+ r₁r₂), cos/sin of (m, r) are cos m ± (|sin m|·r + r²/2) (Taylor with remainder). The enclosures hold up to
floating-point rounding (relative 1e-15 per operation, far inside the checker's LIMIT_RTOL of 1e-9). Their
width shrinks linearly with the piece: :mod:`robodesign.judge.arc_torques` splits pieces until they decide.

Joints: revolute and prismatic about ±z of the joint frame (what :class:`~robodesign.model.robot.Robot`
builds). A world wrench at the TCP (a follow goal's force and torque) enters as pinocchio's external force on
the TCP's joint, expressed in that joint's frame (as :meth:`Robot.tcp_wrench_forces
<robodesign.model.robot.Robot.tcp_wrench_forces>` does).
"""
from __future__ import annotations

import sys
from functools import cached_property
from typing import Any, Callable, Dict, List, Optional, Tuple

import numpy as np


class DI:
    """Dual interval arrays: value (m, r) and time derivative (dm, dr); the last axis of a vector is xyz."""
    __slots__ = ("m", "r", "dm", "dr")

    def __init__(self, m, r, dm, dr):
        self.m, self.r, self.dm, self.dr = m, r, dm, dr

    @classmethod
    def const(cls, x, shape) -> "DI":
        m = np.broadcast_to(np.asarray(x, dtype=float), shape).copy()
        z = np.zeros(shape)
        return cls(m, z, z.copy(), z.copy())

    def __add__(self, o: "DI") -> "DI":
        return DI(self.m + o.m, self.r + o.r, self.dm + o.dm, self.dr + o.dr)

    def __sub__(self, o: "DI") -> "DI":
        return DI(self.m - o.m, self.r + o.r, self.dm - o.dm, self.dr + o.dr)

    def __neg__(self) -> "DI":
        return DI(-self.m, self.r, -self.dm, self.dr)

    def __mul__(self, o: "DI") -> "DI":
        m, r = _imul(self.m, self.r, o.m, o.r)
        m1, r1 = _imul(self.dm, self.dr, o.m, o.r)
        m2, r2 = _imul(self.m, self.r, o.dm, o.dr)
        return DI(m, r, m1 + m2, r1 + r2)

    def scale(self, c) -> "DI":
        """Times a constant (array broadcasting against the value)."""
        c = np.asarray(c, dtype=float)
        return DI(self.m * c, self.r * np.abs(c), self.dm * c, self.dr * np.abs(c))

    def lin(self, M: np.ndarray) -> "DI":
        """A constant 3×3 matrix times every vector (last axis): (x0·M[i,0] + x1·M[i,1]) + x2·M[i,2], written out
        (not a matrix product, whose rounding depends on the BLAS: :mod:`~robodesign.judge.interval_kernel` makes
        the same operations)."""
        A = np.abs(M)
        return DI(*(((x[..., 0:1] * B[:, 0] + x[..., 1:2] * B[:, 1]) + x[..., 2:3] * B[:, 2])
                    for x, B in ((self.m, M), (self.r, A), (self.dm, M), (self.dr, A))))

    def __getitem__(self, i) -> "DI":
        return DI(self.m[..., i], self.r[..., i], self.dm[..., i], self.dr[..., i])


def _imul(m1, r1, m2, r2):
    return m1 * m2, np.abs(m1) * r2 + r1 * np.abs(m2) + r1 * r2


def _stack(parts: List[DI]) -> DI:
    return DI(*(np.stack([getattr(p, f) for p in parts], axis=-1) for f in ("m", "r", "dm", "dr")))


_I, _J = [1, 2, 0], [2, 0, 1]


def _xm(x, y):
    """x × y of point vectors (last axis)."""
    return x[..., _I] * y[..., _J] - x[..., _J] * y[..., _I]


def _xr(x, y):
    """|x_j|·|y_k| + |x_k|·|y_j|: the radius term of a cross product for non-negative x, y."""
    return x[..., _I] * y[..., _J] + x[..., _J] * y[..., _I]


def _icross(am, ar, bm, br):
    """Interval a × b, (mid, radius) of vectors."""
    aa, ab = np.abs(am), np.abs(bm)
    return _xm(am, bm), _xr(aa, br) + _xr(ar, ab) + _xr(ar, br)


_IJ = _I + _J


def _rolled(x):
    """(x[..., _I], x[..., _J]) in one gather."""
    t = x[..., _IJ]
    return t[..., :3], t[..., 3:]


def _cross(a: DI, b: DI) -> DI:
    """a × b with its derivative ȧ × b + a × ḃ: the component products of :func:`_icross`, each operand's
    components gathered once (the same operations in the same order)."""
    (amI, amJ), (arI, arJ), (admI, admJ), (adrI, adrJ) = (_rolled(x) for x in (a.m, a.r, a.dm, a.dr))
    (bmI, bmJ), (brI, brJ), (bdmI, bdmJ), (bdrI, bdrJ) = (_rolled(x) for x in (b.m, b.r, b.dm, b.dr))
    aaI, aaJ, abI, abJ = np.abs(amI), np.abs(amJ), np.abs(bmI), np.abs(bmJ)
    m = amI * bmJ - amJ * bmI
    r = (aaI * brJ + aaJ * brI) + (arI * abJ + arJ * abI) + (arI * brJ + arJ * brI)
    adaI, adaJ = np.abs(admI), np.abs(admJ)
    m1 = admI * bmJ - admJ * bmI
    r1 = (adaI * brJ + adaJ * brI) + (adrI * abJ + adrJ * abI) + (adrI * brJ + adrJ * brI)
    bdaI, bdaJ = np.abs(bdmI), np.abs(bdmJ)
    m2 = amI * bdmJ - amJ * bdmI
    r2 = (aaI * bdrJ + aaJ * bdrI) + (arI * bdaJ + arJ * bdaI) + (arI * bdrJ + arJ * bdrI)
    return DI(m, r, m1 + m2, r1 + r2)


def _skew(p) -> np.ndarray:
    x, y, z = p
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def _cos_sin(th: DI) -> Tuple[DI, DI]:
    """cos and sin of a dual interval angle (value enclosures by Taylor with remainder)."""
    c, s = np.cos(th.m), np.sin(th.m)
    r2 = th.r * th.r / 2
    cv = DI(c, np.abs(s) * th.r + r2, 0.0, 0.0)
    sv = DI(s, np.abs(c) * th.r + r2, 0.0, 0.0)
    # d cos = −sin·θ̇, d sin = cos·θ̇ (intervals)
    dcm, dcr = _imul(-sv.m, sv.r, th.dm, th.dr)
    dsm, dsr = _imul(cv.m, cv.r, th.dm, th.dr)
    return DI(cv.m, cv.r, dcm, dcr), DI(sv.m, sv.r, dsm, dsr)


_SWAP = [1, 0]
_SIGN_T = np.array([1.0, -1.0])  # Rz(θ)ᵀ·y = (c·y0 + s·y1, c·y1 − s·y0, y2)
_SIGN = np.array([-1.0, 1.0])  # Rz(θ)·y = (c·y0 − s·y1, c·y1 + s·y0, y2)


def _cs(c: DI, s: DI) -> DI:
    """cos θ and sin θ stacked, (2, P, 1): the left factor of :func:`_rot_z`."""
    return DI(*(np.stack([a, b])[..., None] for a, b in ((c.m, s.m), (c.r, s.r), (c.dm, s.dm), (c.dr, s.dr))))


def _rot_z(cs: DI, y: DI, transpose: bool) -> DI:
    """Rz(θ)·y (or Rz(θ)ᵀ·y) for vectors y, with ``cs`` = :func:`_cs` of cos θ and sin θ (scalars per row):
    c·(y0, y1) + s·(±y1, ∓y0) as one product of the stacked factors, then the sum of its two halves."""
    sign = _SIGN_T if transpose else _SIGN
    pair = DI(np.stack([y.m[..., :2], y.m[..., _SWAP] * sign]), np.stack([y.r[..., :2], y.r[..., _SWAP]]),
              np.stack([y.dm[..., :2], y.dm[..., _SWAP] * sign]), np.stack([y.dr[..., :2], y.dr[..., _SWAP]]))
    p = cs * pair
    o = DI(p.m[0], p.r[0], p.dm[0], p.dr[0]) + DI(p.m[1], p.r[1], p.dm[1], p.dr[1])
    return DI(*(np.concatenate([a, b[..., 2:]], axis=-1) for a, b in ((o.m, y.m), (o.r, y.r), (o.dm, y.dm),
                                                                     (o.dr, y.dr))))


_PASSES = [0]  # interval passes made by this process
NUMPY_PASSES = 4  # passes on the numpy path before a process that has not imported numba imports it


def _kernel() -> Any:
    """The compiled kernel module (:mod:`~robodesign.judge.interval_kernel`) when it runs in this process, else
    None. Importing numba takes 0.3–1 s, more than the kernel saves a single check: a process that has not
    imported it (no IK kernel) makes its first :data:`NUMPY_PASSES` passes on the numpy path. Both paths give
    the same numbers, so which one runs never changes a result."""
    _PASSES[0] += 1
    if "numba" not in sys.modules and _PASSES[0] <= NUMPY_PASSES:
        return None
    from robodesign.judge import interval_kernel
    return interval_kernel if interval_kernel.ready() else None


_TREES: Dict[tuple, tuple] = {}   # (id(module set), assembly key) → (module set, IntervalDynamics of such a robot)


class IntervalDynamics:
    """The robot's kinematic tree and inertias, read once from its pinocchio model, for :meth:`link_torques`.

    A base pose changes only the placements of the root joints (those on the base) in the model. So what the
    last robot of the same module set and assembly read is kept (:data:`_TREES`): a robot of it reads just its
    root joints' placements, the gravity and the TCP (the same numbers as a full read, tests/test_interval_trees.py).
    """

    def __init__(self, robot):
        m = robot.model
        key = (id(robot.module_set), robot.assembly.key()) if getattr(robot, "assembly", None) is not None else None
        kept = _TREES.get(key) if key is not None else None
        if kept is not None and kept[0] is robot.module_set:
            self._adopt(kept[1], m)
        else:
            self._read(robot, m)
            if key is not None:
                if len(_TREES) >= 64:
                    _TREES.clear()
                _TREES[key] = (robot.module_set, self)
        self.gravity = np.array(m.gravity.linear)
        fr = m.frames[robot.tcp_frame]
        self.tcp_joint = int(fr.parentJoint)
        self.tcp_offset = np.array(fr.placement.translation)

    def _read(self, robot, m) -> None:
        """Every joint's parent, kind, sign, placement (R, p) and body inertia (mass, lever, inertia) from ``m``."""
        self.dof = robot.dof
        self.parents, self.kinds, self.signs, self.R, self.p = [], [], [], [], []
        self.mass, self.lever, self.inertia = [], [], []
        for jid in range(1, m.njoints):
            name = m.joints[jid].shortname()
            info = robot.joint_infos[jid - 1]
            if name in ("JointModelRZ", "JointModelPZ"):
                sign = 1.0
            elif name in ("JointModelRevoluteUnaligned", "JointModelPrismaticUnaligned") and info.reversed:
                sign = -1.0  # the reversed modules' joints: about (0, 0, −1)
            else:
                raise NotImplementedError(f"interval dynamics: joint type {name} of {info.name}")
            if m.joints[jid].idx_v != jid - 1:
                raise NotImplementedError("interval dynamics: joints must be in velocity order")
            self.parents.append(m.parents[jid])
            self.kinds.append(0 if name in ("JointModelRZ", "JointModelRevoluteUnaligned") else 1)
            self.signs.append(sign)
            P = m.jointPlacements[jid]
            self.R.append(np.array(P.rotation))
            self.p.append(np.array(P.translation))
            Y = m.inertias[jid]
            self.mass.append(float(Y.mass))
            self.lever.append(np.array(Y.lever))
            self.inertia.append(np.array(Y.inertia))

    def _adopt(self, kept: "IntervalDynamics", m) -> None:
        """:meth:`_read` of a model of ``kept``'s module set and assembly: ``kept``'s tree (its lists shared, never
        changed) with the root joints' placements read from ``m``, and its kernel arguments with those rows."""
        self.dof, self.parents, self.kinds, self.signs = kept.dof, kept.parents, kept.kinds, kept.signs
        self.mass, self.lever, self.inertia = kept.mass, kept.lever, kept.inertia
        self.R, self.p = list(kept.R), list(kept.p)
        args = kept._kernel_args
        R, Sp = args[3].copy(), args[4].copy()
        for j, parent in enumerate(self.parents):
            if parent == 0:
                P = m.jointPlacements[j + 1]
                self.R[j], self.p[j] = np.array(P.rotation), np.array(P.translation)
                R[j], Sp[j] = self.R[j], _skew(self.p[j])
        self.__dict__["_kernel_args"] = args[:3] + (R, Sp) + args[5:]

    def mass_matrix_bound(self, Q: Tuple[np.ndarray, np.ndarray]) -> np.ndarray:
        """(P, dof, dof) bounds of |M(q)[j, i]| (link side, no armature) over the boxes ``Q``: column i is RNEA
        with q̈ = e_i, no velocity, no gravity, in interval arithmetic."""
        P, n = Q[0].shape
        Qm, Qr = np.repeat(Q[0], n, axis=0), np.repeat(Q[1], n, axis=0)
        zero = np.zeros_like(Qm)
        T = self.link_torques((Qm, Qr), (zero, zero), np.tile(np.eye(n), (P, 1)), gravity=False)
        return (np.abs(T.m) + T.r).reshape(P, n, n).transpose(0, 2, 1)

    def rates_and_mass_bound(self, Q: Tuple[np.ndarray, np.ndarray], V: Tuple[np.ndarray, np.ndarray],
                             a: Tuple[np.ndarray, np.ndarray], rows: np.ndarray) -> Tuple[DI, np.ndarray]:
        """``link_torques(Q, V, a)`` (no wrench) and ``mass_matrix_bound`` of the boxes ``Q[rows]`` in one pass:
        the rows of both stacked, gravity on the first P only (each row's arithmetic is its own)."""
        P, n = Q[0].shape
        G = len(rows)
        z = np.zeros((G * n, n))
        stack = lambda x, y: np.concatenate([np.asarray(x, dtype=float), y])  # noqa: E731
        Qm, Qr = np.repeat(Q[0][rows], n, axis=0), np.repeat(Q[1][rows], n, axis=0)
        T = self.link_torques((stack(Q[0], Qm), stack(Q[1], Qr)), (stack(V[0], z), stack(V[1], z)),
                              (stack(a[0], np.tile(np.eye(n), (G, 1))), stack(a[1], z)),
                              gravity=np.r_[np.ones(P, dtype=bool), np.zeros(G * n, dtype=bool)])
        head = DI(T.m[:P], T.r[:P], T.dm[:P], T.dr[:P])
        return head, (np.abs(T.m[P:]) + T.r[P:]).reshape(G, n, n).transpose(0, 2, 1)

    def link_torques(self, Q: Tuple[np.ndarray, np.ndarray], V: Tuple[np.ndarray, np.ndarray], a,
                     wrench: Optional[np.ndarray] = None, gravity=True) -> DI:
        """Enclosure (P, dof) of RNEA(q, q̇, a) and of its rate along the arc, for P pieces with q in the
        intervals ``Q`` = (mid, radius), q̇ in ``V`` = (mid, radius) (all (P, dof)), q̈ = ``a`` (P, dof), constant
        along each arc (an array, or (mid, radius): any constant acceleration in that interval), and ``wrench``
        (P, 6) world wrenches [f; τ] at the TCP (None: none). ``gravity``: a bool, or one per row."""
        a_m, a_r = (np.asarray(a[0], float), np.asarray(a[1], float)) if isinstance(a, tuple) else \
            (np.asarray(a, float), np.zeros(np.shape(a)))
        P = a_m.shape[0]
        kernel = _kernel() if wrench is None or self.tcp_joint <= 0 else None
        if kernel is not None:
            return self._compiled(kernel, Q, V, (a_m, a_r), gravity)
        z = np.zeros((P,))
        q = DI(Q[0], Q[1], V[0], V[1])
        qd = DI(V[0], V[1], a_m, a_r)
        qdd = DI(a_m, a_r, np.zeros_like(a_m), np.zeros_like(a_m))
        zero3 = DI.const(0.0, (P, 3))
        n = self.dof
        vel: List[DI] = [zero3] * (n + 1)  # index 0: the universe
        ang: List[DI] = [zero3] * (n + 1)
        acc: List[DI] = [zero3] * (n + 1)
        alpha: List[DI] = [zero3] * (n + 1)
        g = np.asarray(gravity)
        acc[0] = DI.const(np.where(g[:, None], -self.gravity, 0.0) if g.ndim else -self.gravity if gravity else
                          np.zeros(3), (P, 3))
        trig: Dict[int, DI] = {}  # revolute joint → (cos, sin) of its angle, stacked (_cs)
        f_lin: List[DI] = [zero3] * (n + 1)
        f_ang: List[DI] = [zero3] * (n + 1)
        # world wrench carried down the chain to the TCP's joint (Rᵀ applied joint after joint)
        w_f: Optional[List[DI]] = None  # None: no wrench to carry
        w_t: List[DI] = []
        if wrench is not None and self.tcp_joint > 0:
            w_f, w_t = [zero3] * (n + 1), [zero3] * (n + 1)  # each joint's entry is set before its children read it
            w_f[0], w_t[0] = DI.const(wrench[:, :3], (P, 3)), DI.const(wrench[:, 3:], (P, 3))

        def unit_z(k: DI) -> DI:  # k·e_z for a scalar dual interval k (P,)
            zz = DI(z, z, z, z)
            return _stack([zz, zz, k])

        for i in range(1, n + 1):
            j = i - 1
            lam = self.parents[j]
            Rp, pp, sg = self.R[j], self.p[j], self.signs[j]
            qi, qdi, qddi = q[j], qd[j], qdd[j]
            # parent motion at the joint's placement, in the placement's axes: Rpᵀ(lin − p × ang)
            w_par = ang[lam].lin(Rp.T)
            v_par = (vel[lam] - ang[lam].lin(_skew(pp))).lin(Rp.T)
            al_par = alpha[lam].lin(Rp.T)
            a_par = (acc[lam] - alpha[lam].lin(_skew(pp))).lin(Rp.T)
            s_qd, s_qdd = unit_z(qdi.scale(sg)), unit_z(qddi.scale(sg))
            if self.kinds[j] == 0:  # revolute: then rotate by θ = sign·q about z
                c, s = _cos_sin(qi.scale(sg))
                cs = trig[i] = _cs(c, s)
                w_i = _rot_z(cs, w_par, True) + s_qd
                v_i = _rot_z(cs, v_par, True)
                al_i = _rot_z(cs, al_par, True) + s_qdd + _cross(w_i, s_qd)
                a_i = _rot_z(cs, a_par, True) + _cross(v_i, s_qd)
            else:  # prismatic: translated by sign·q along z
                d = unit_z(qi.scale(sg))
                w_i = w_par
                v_i = v_par - _cross(d, w_par) + s_qd
                al_i = al_par
                a_i = a_par - _cross(d, al_par) + s_qdd + _cross(w_i, s_qd)
            vel[i], ang[i], acc[i], alpha[i] = v_i, w_i, a_i, al_i
            fl, fa = self._body_wrench(j, v_i, w_i, a_i, al_i)
            if w_f is not None:
                wf, wt = w_f[lam].lin(Rp.T), w_t[lam].lin(Rp.T)
                if self.kinds[j] == 0:
                    wf, wt = _rot_z(cs, wf, True), _rot_z(cs, wt, True)
                w_f[i], w_t[i] = wf, wt
                if i == self.tcp_joint:  # pinocchio: f_i −= fext_i (force, moment about the joint origin)
                    fl = fl - wf
                    fa = fa - (wt + wf.lin(_skew(self.tcp_offset)))
            f_lin[i], f_ang[i] = fl, fa
        return self._backward(q, f_lin, f_ang, trig, unit_z)

    def _compiled(self, kernel, Q, V, a, gravity) -> DI:
        """:meth:`link_torques` without a wrench by the compiled kernel (the same operations, bit for bit)."""
        f = lambda x: np.ascontiguousarray(x, dtype=float)  # noqa: E731
        Q0, Q1, V0, V1, am, ar = (f(x) for x in (Q[0], Q[1], V[0], V[1], a[0], a[1]))
        P, n = am.shape
        g = np.asarray(gravity)
        acc0 = np.broadcast_to(np.where(g[:, None], -self.gravity, 0.0) if g.ndim else -self.gravity if gravity
                               else np.zeros(3), (P, 3))
        C, S = np.zeros((P, n)), np.zeros((P, n))
        for j in range(n):
            if self.kinds[j] == 0:  # cos and sin as _cos_sin takes them (numpy's, of the same numbers)
                th = Q0[..., j] * np.asarray(self.signs[j], dtype=float)
                C[:, j], S[:, j] = np.cos(th), np.sin(th)
        k = self._kernel_args
        out = kernel.link_torques(Q0, Q1, V0, V1, am, ar, f(acc0), C, S, *k)
        return DI(out[0], out[1], out[2], out[3])

    @cached_property
    def _kernel_args(self) -> tuple:
        return (np.array(self.parents, dtype=np.int64), np.array(self.kinds, dtype=np.int64),
                np.array(self.signs, dtype=float), np.array(self.R, dtype=float),
                np.array([_skew(p) for p in self.p]), np.array(self.mass, dtype=float),
                np.array([_skew(c) for c in self.lever]), np.array(self.inertia, dtype=float))

    def _body_wrench(self, j: int, v_i: DI, w_i: DI, a_i: DI, al_i: DI) -> Tuple[DI, DI]:
        """Body wrench of joint ``j``'s body: I·a + v ×* I·v, with I (mass m, lever c, rotational inertia Ic about
        the com). → (force, moment)."""
        mass, cvec, Ic = self.mass[j], self.lever[j], self.inertia[j]
        Sc = _skew(cvec)
        h_lin = (v_i - w_i.lin(Sc)).scale(mass)
        h_ang = w_i.lin(Ic) + h_lin.lin(Sc)
        g_lin = (a_i - al_i.lin(Sc)).scale(mass)
        g_ang = al_i.lin(Ic) + g_lin.lin(Sc)
        fl = g_lin + _cross(w_i, h_lin)
        fa = g_ang + _cross(w_i, h_ang) + _cross(v_i, h_lin)
        return fl, fa

    def _backward(self, q: DI, f_lin: List[DI], f_ang: List[DI], trig: Dict[int, DI],
                  unit_z: Callable[[DI], DI]) -> DI:
        """The backward pass of RNEA: each body's wrench carried to its parent, the joint torques read off from
        the TCP back to the base. → (P, dof) torques."""
        n = self.dof
        taus: Dict[int, DI] = {}  # joint index → its torque, set from the TCP back to the base
        f_lin, f_ang = list(f_lin), list(f_ang)
        for i in range(n, 0, -1):
            j = i - 1
            sg = self.signs[j]
            taus[j] = (f_ang[i][2] if self.kinds[j] == 0 else f_lin[i][2]).scale(sg)
            lam = self.parents[j]
            if lam == 0:
                continue
            Rp, pp = self.R[j], self.p[j]
            fl, fa = f_lin[i], f_ang[i]
            if self.kinds[j] == 0:
                fl, fa = _rot_z(trig[i], fl, False), _rot_z(trig[i], fa, False)
            else:
                fa = fa + _cross(unit_z(q[j].scale(sg)), fl)
            fl_p, fa_p = fl.lin(Rp), fa.lin(Rp)
            f_lin[lam] = f_lin[lam] + fl_p
            f_ang[lam] = f_ang[lam] + fa_p + fl_p.lin(_skew(pp))
        return _stack([taus[j] for j in range(n)])
