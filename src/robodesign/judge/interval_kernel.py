"""The interval RNEA of :mod:`robodesign.judge.interval_rnea`, compiled (numba): one loop over the rows instead of
a few thousand small numpy operations per pass; and the judge's TCP twists
(:attr:`TrajectoryQuantities.tcp_twists <robodesign.judge.quantities.TrajectoryQuantities.tcp_twists>`: one loop
over the samples instead of ~25 numpy passes per joint), the arcs of the judged motion, its positions inside a step
(what the collision sweep asks, hundreds of times per check) and the extremes of its positions and velocities per
step (:class:`~robodesign.judge.motion.StepMotion`: one loop instead of ~40 numpy passes), and the whole-step
torque bounds of :mod:`robodesign.judge.arc_torques` (its prefilter's last ~40 numpy passes).

The kernel makes **the same floating-point operations in the same order** as the numpy path
(:meth:`IntervalDynamics.link_torques <robodesign.judge.interval_rnea.IntervalDynamics.link_torques>`: the
dual-interval products, cross products, rotations about z, the constant 3×3 products as explicit sums; cos and
sin of the angles are computed by numpy and passed in), so both give the same enclosures **bit for bit**
(tests/test_interval_kernel.py) and a verdict never depends on which one ran. Covered: no TCP wrench (a wrench
keeps the numpy path), revolute and prismatic joints about ±z (what the numpy path covers).

No cold-start stall: compiling takes several seconds and is cached on disk (numba's cache, ``__pycache__`` beside
this file or ``NUMBA_CACHE_DIR``). A process that finds no stamp of a finished compilation (the stamp beside the
cache records numba, Python, CPU and this file) starts one background process (``python -m
robodesign.judge.interval_kernel``, niced, its own process group) that compiles into the cache, and runs the numpy
path meanwhile. ``ROBODESIGN_JIT=0`` switches the kernel off, ``ROBODESIGN_JIT=wait`` compiles at first use.
"""
from __future__ import annotations

import sys

import numpy as np

from robodesign.core.jit_cache import KernelModule, njit


@njit(cache=True, nogil=True)
def _lin(x, M, out):  # pragma: no cover - compiled
    """out = x·Mᵀ per field (m, dm with M; r, dr with |M|), each component (x0·M[i,0] + x1·M[i,1]) + x2·M[i,2]."""
    for f in range(4):
        for i in range(3):
            if f == 0 or f == 2:
                a, b, c = M[i, 0], M[i, 1], M[i, 2]
            else:
                a, b, c = abs(M[i, 0]), abs(M[i, 1]), abs(M[i, 2])
            out[f, i] = (x[f, 0] * a + x[f, 1] * b) + x[f, 2] * c


@njit(cache=True, nogil=True)
def _add(x, y, out):  # pragma: no cover - compiled
    for f in range(4):
        for i in range(3):
            out[f, i] = x[f, i] + y[f, i]


@njit(cache=True, nogil=True)
def _sub(x, y, out):  # pragma: no cover - compiled
    for i in range(3):
        out[0, i] = x[0, i] - y[0, i]
        out[1, i] = x[1, i] + y[1, i]
        out[2, i] = x[2, i] - y[2, i]
        out[3, i] = x[3, i] + y[3, i]


@njit(cache=True, nogil=True)
def _scale(x, c, out):  # pragma: no cover - compiled
    ac = abs(c)
    for i in range(3):
        out[0, i] = x[0, i] * c
        out[1, i] = x[1, i] * ac
        out[2, i] = x[2, i] * c
        out[3, i] = x[3, i] * ac


@njit(cache=True, nogil=True)
def _cross(a, b, out):  # pragma: no cover - compiled
    """a × b with its derivative, as interval_rnea._cross (the same terms, the same order)."""
    for k in range(3):
        i, j = (k + 1) % 3, (k + 2) % 3
        amI, amJ, arI, arJ = a[0, i], a[0, j], a[1, i], a[1, j]
        admI, admJ, adrI, adrJ = a[2, i], a[2, j], a[3, i], a[3, j]
        bmI, bmJ, brI, brJ = b[0, i], b[0, j], b[1, i], b[1, j]
        bdmI, bdmJ, bdrI, bdrJ = b[2, i], b[2, j], b[3, i], b[3, j]
        aaI, aaJ, abI, abJ = abs(amI), abs(amJ), abs(bmI), abs(bmJ)
        m = amI * bmJ - amJ * bmI
        r = (aaI * brJ + aaJ * brI) + (arI * abJ + arJ * abI) + (arI * brJ + arJ * brI)
        adaI, adaJ = abs(admI), abs(admJ)
        m1 = admI * bmJ - admJ * bmI
        r1 = (adaI * brJ + adaJ * brI) + (adrI * abJ + adrJ * abI) + (adrI * brJ + adrJ * brI)
        bdaI, bdaJ = abs(bdmI), abs(bdmJ)
        m2 = amI * bdmJ - amJ * bdmI
        r2 = (aaI * bdrJ + aaJ * bdrI) + (arI * bdaJ + arJ * bdaI) + (arI * bdrJ + arJ * bdrI)
        out[0, k], out[1, k], out[2, k], out[3, k] = m, r, m1 + m2, r1 + r2


@njit(cache=True, nogil=True)
def _dmul(am, ar, adm, adr, bm, br, bdm, bdr):  # pragma: no cover - compiled
    """DI product of two scalars (interval_rnea.DI.__mul__ with _imul)."""
    m, r = am * bm, abs(am) * br + ar * abs(bm) + ar * br
    m1, r1 = adm * bm, abs(adm) * br + adr * abs(bm) + adr * br
    m2, r2 = am * bdm, abs(am) * bdr + ar * abs(bdm) + ar * bdr
    return m, r, m1 + m2, r1 + r2


@njit(cache=True, nogil=True)
def _rot_z(cs, y, transpose, out):  # pragma: no cover - compiled
    """Rz(θ)·y or Rz(θ)ᵀ·y as interval_rnea._rot_z: c·(y0, y1) + s·(±y1, ∓y0); cs = (4, 2) fields of cos, sin."""
    s0, s1 = (1.0, -1.0) if transpose else (-1.0, 1.0)
    for k in range(2):
        o = 1 - k
        sg = s0 if k == 0 else s1
        p0 = _dmul(cs[0, 0], cs[1, 0], cs[2, 0], cs[3, 0], y[0, k], y[1, k], y[2, k], y[3, k])
        p1 = _dmul(cs[0, 1], cs[1, 1], cs[2, 1], cs[3, 1], y[0, o] * sg, y[1, o], y[2, o] * sg, y[3, o])
        for f in range(4):
            out[f, k] = p0[f] + p1[f]
    for f in range(4):
        out[f, 2] = y[f, 2]


@njit(cache=True, nogil=True)
def _body(v, w, a, al, mass, SC, IC, fl, fa, t1, t2, t3, t4):  # pragma: no cover - compiled
    """interval_rnea.IntervalDynamics._body_wrench: (force fl, moment fa) of one body."""
    _lin(w, SC, t1)
    _sub(v, t1, t2)
    _scale(t2, mass, t1)  # h_lin
    _lin(w, IC, t2)
    _lin(t1, SC, t3)
    _add(t2, t3, t4)  # h_ang
    _lin(al, SC, t2)
    _sub(a, t2, t3)
    _scale(t3, mass, t2)  # g_lin
    _lin(al, IC, t3)
    _lin(t2, SC, fa)
    _add(t3, fa, t3)  # g_ang
    _cross(w, t1, fa)
    _add(t2, fa, fl)  # g_lin + w × h_lin
    _cross(w, t4, t2)
    _add(t3, t2, t3)
    _cross(v, t1, t2)
    _add(t3, t2, fa)


@njit(cache=True, nogil=True)
def _backward(p, Q0, Q1, V0, V1, parents, kinds, signs, R, SP, fl, fa, cs, out, t1, t2, t3, t4, dz):  # pragma: no cover
    """The backward pass of row p: each body's wrench carried to its parent, the torques read off into out."""
    for i in range(len(signs), 0, -1):
        j = i - 1
        sg = signs[j]
        asg = abs(sg)
        src = fa[i] if kinds[j] == 0 else fl[i]
        out[0, p, j], out[1, p, j] = src[0, 2] * sg, src[1, 2] * asg
        out[2, p, j], out[3, p, j] = src[2, 2] * sg, src[3, 2] * asg
        lam = parents[j]
        if lam == 0:
            continue
        if kinds[j] == 0:
            _rot_z(cs[i], fl[i], False, t1)
            _rot_z(cs[i], fa[i], False, t2)
        else:
            t1[:] = fl[i]
            dz[0, 2], dz[1, 2], dz[2, 2], dz[3, 2] = Q0[p, j] * sg, Q1[p, j] * asg, V0[p, j] * sg, V1[p, j] * asg
            _cross(dz, t1, t3)
            _add(fa[i], t3, t2)
        _lin(t1, R[j], t3)  # fl_p
        _lin(t2, R[j], t4)  # fa_p
        _add(fl[lam], t3, fl[lam])
        _add(fa[lam], t4, t2)
        _lin(t3, SP[j], t1)
        _add(t2, t1, fa[lam])


@njit(cache=True, nogil=True)
def link_torques(Q0, Q1, V0, V1, am, ar, acc0, C, S, parents, kinds, signs, R, SP, mass, SC, IC):  # pragma: no cover
    """(4, P, n) fields (m, r, dm, dr) of IntervalDynamics.link_torques without a wrench. C, S (P, n): cos and sin
    of sign·q (the revolute columns); R, SP, SC, IC (n, 3, 3): joint placement rotations, skew(placement
    translation), skew(com lever), rotational inertias."""
    P, n = Q0.shape
    out = np.empty((4, P, n))
    vel, ang = np.zeros((n + 1, 4, 3)), np.zeros((n + 1, 4, 3))
    acc, alp = np.zeros((n + 1, 4, 3)), np.zeros((n + 1, 4, 3))
    fl, fa = np.zeros((n + 1, 4, 3)), np.zeros((n + 1, 4, 3))
    cs = np.zeros((n + 1, 4, 2))
    RT = np.empty((n, 3, 3))
    for j in range(n):
        RT[j] = R[j].T
    t1, t2, t3, t4 = np.zeros((4, 3)), np.zeros((4, 3)), np.zeros((4, 3)), np.zeros((4, 3))
    wp, vp, ap, lp = np.zeros((4, 3)), np.zeros((4, 3)), np.zeros((4, 3)), np.zeros((4, 3))
    sqd, sqdd, dz = np.zeros((4, 3)), np.zeros((4, 3)), np.zeros((4, 3))
    for p in range(P):
        for f in range(4):
            for i in range(3):
                acc[0, f, i] = acc0[p, i] if f == 0 else 0.0
        for i in range(1, n + 1):
            j = i - 1
            lam = parents[j]
            sg = signs[j]
            asg = abs(sg)
            _lin(ang[lam], RT[j], wp)
            _lin(ang[lam], SP[j], t1)
            _sub(vel[lam], t1, t2)
            _lin(t2, RT[j], vp)
            _lin(alp[lam], RT[j], lp)
            _lin(alp[lam], SP[j], t1)
            _sub(acc[lam], t1, t2)
            _lin(t2, RT[j], ap)
            sqd[0, 2], sqd[1, 2], sqd[2, 2], sqd[3, 2] = V0[p, j] * sg, V1[p, j] * asg, am[p, j] * sg, ar[p, j] * asg
            sqdd[0, 2], sqdd[1, 2], sqdd[2, 2], sqdd[3, 2] = am[p, j] * sg, ar[p, j] * asg, 0.0 * sg, 0.0 * asg
            if kinds[j] == 0:
                thr, thdm, thdr = Q1[p, j] * asg, V0[p, j] * sg, V1[p, j] * asg
                c, s = C[p, j], S[p, j]
                r2 = thr * thr / 2
                cr, sr = abs(s) * thr + r2, abs(c) * thr + r2
                ms = -s
                cs[i, 0, 0], cs[i, 1, 0] = c, cr
                cs[i, 2, 0], cs[i, 3, 0] = ms * thdm, abs(ms) * thdr + sr * abs(thdm) + sr * thdr
                cs[i, 0, 1], cs[i, 1, 1] = s, sr
                cs[i, 2, 1], cs[i, 3, 1] = c * thdm, abs(c) * thdr + cr * abs(thdm) + cr * thdr
                _rot_z(cs[i], wp, True, t1)
                _add(t1, sqd, ang[i])
                _rot_z(cs[i], vp, True, vel[i])
                _rot_z(cs[i], lp, True, t1)
                _add(t1, sqdd, t2)
                _cross(ang[i], sqd, t1)
                _add(t2, t1, alp[i])
                _rot_z(cs[i], ap, True, t1)
                _cross(vel[i], sqd, t2)
                _add(t1, t2, acc[i])
            else:
                dz[0, 2], dz[1, 2], dz[2, 2], dz[3, 2] = Q0[p, j] * sg, Q1[p, j] * asg, V0[p, j] * sg, V1[p, j] * asg
                ang[i, :, :] = wp
                _cross(dz, wp, t1)
                _sub(vp, t1, t2)
                _add(t2, sqd, vel[i])
                alp[i, :, :] = lp
                _cross(dz, lp, t1)
                _sub(ap, t1, t2)
                _add(t2, sqdd, t1)
                _cross(ang[i], sqd, t2)
                _add(t1, t2, acc[i])
            _body(vel[i], ang[i], acc[i], alp[i], mass[j], SC[j], IC[j], fl[i], fa[i], t1, t2, t3, t4)
        _backward(p, Q0, Q1, V0, V1, parents, kinds, signs, R, SP, fl, fa, cs, out, t1, t2, t3, t4, dz)
    return out


@njit(cache=True, nogil=True)
def tcp_twists(J, T, dq, jid, prismatic, col, sign):  # pragma: no cover - compiled
    """(n, 6) TCP twists [v; ω] as TrajectoryQuantities.tcp_twists' numpy path, sample by sample: the chain's joints
    (pinocchio ids jid, velocities dq (n, len(jid)) in the chain's order) along ±(coordinate axis col) of their frame
    (sign ±1.0), so world axis z = column col of the joint's rotation in J (n, njoints, 4, 4) times sign; each
    component summed from +0 over the joints in order, v += z·q̇ (prismatic) or ω += z·q̇ and v += (z × (p − o))·q̇
    (revolute; p the TCP position of T (n, 4, 4), o the joint's origin). (0, 6) when a rotation entry of a chain
    joint is no finite number (the numpy path's product then differs from the column)."""
    n, m = J.shape[0], len(jid)
    for t in range(m):
        for k in range(n):
            for a in range(3):
                for b in range(3):
                    if not np.isfinite(J[k, jid[t], a, b]):
                        return np.empty((0, 6))
    out = np.empty((n, 6))
    for k in range(n):
        v0, v1, v2, w0, w1, w2 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        for t in range(m):
            j, c, s, qd = jid[t], col[t], sign[t], dq[k, t]
            z0, z1, z2 = J[k, j, 0, c] * s, J[k, j, 1, c] * s, J[k, j, 2, c] * s
            if prismatic[t]:
                v0, v1, v2 = v0 + z0 * qd, v1 + z1 * qd, v2 + z2 * qd
                continue
            w0, w1, w2 = w0 + z0 * qd, w1 + z1 * qd, w2 + z2 * qd
            b0, b1, b2 = T[k, 0, 3] - J[k, j, 0, 3], T[k, 1, 3] - J[k, j, 1, 3], T[k, 2, 3] - J[k, j, 2, 3]
            v0 = v0 + (z1 * b2 - z2 * b1) * qd
            v1 = v1 + (z2 * b0 - z0 * b2) * qd
            v2 = v2 + (z0 * b1 - z1 * b0) * qd
        out[k, 0], out[k, 1], out[k, 2], out[k, 3], out[k, 4], out[k, 5] = v0, v1, v2, w0, w1, w2
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def step_arcs(q, v, h):  # pragma: no cover - compiled
    """(3, N − 1, dof): the arcs a1, a2 and the switch instant tau per step and joint of the least-acceleration
    motion through q, v (N, dof) with steps h (N − 1,), as StepMotion.through's numpy path: the same operations,
    numpy.clip's and numpy.where's choices (a division by 0 IEEE's, as numpy's)."""
    m, dof = len(h), q.shape[1]
    out = np.empty((3, m, dof))
    for k in range(m):
        H = h[k]
        for j in range(dof):
            v0, v1 = v[k, j], v[k + 1, j]
            D = q[k + 1, j] - q[k, j]
            dv = v1 - v0
            r2 = 2 * D - (v0 + v1) * H
            w = H * (v1 - v0)
            a = (abs(r2) + np.sqrt(r2 * r2 + w * w)) / (H * H)
            sigma = 1.0 if r2 >= 0 else -1.0
            tau = (H + sigma * dv / a) / 2 if a > 0 else H / 2
            if tau == tau:  # numpy.clip(tau, 0.0, H): a NaN stays
                tau = tau if tau > 0.0 else 0.0
                tau = tau if tau < H else H
            tau = 0.0 if tau < 1e-9 * H else (H if tau > (1 - 1e-9) * H else tau)
            out[0, k, j], out[1, k, j], out[2, k, j] = sigma * a, -sigma * a, tau
    return out


@njit(cache=True, nogil=True)
def step_at(rows, k, s):  # pragma: no cover - compiled
    """q at fraction s of step k of the two-arc motion whose per-step rows (N − 1, 6, dof) are q, v at the step's
    start, a1, a2, tau and h (StepMotion's arc rows), as StepMotion.at's numpy path: the same operations in the same
    order, numpy.minimum's and numpy.maximum's choices (a NaN kept)."""
    x = s * rows[k, 5, 0]
    dof = rows.shape[2]
    out = np.empty(dof)
    for j in range(dof):
        T = rows[k, 4, j]
        u = x if (x != x or x <= T) else T
        d = x - T
        w = d if (d != d or d >= 0.0) else 0.0
        V, A1 = rows[k, 1, j], rows[k, 2, j]
        out[j] = (((rows[k, 0, j] + V * u) + A1 * (u * u) / 2) + (V + A1 * u) * w) + rows[k, 3, j] * (w * w) / 2
    return out


@njit(cache=True, nogil=True)
def _first_extreme(c, largest):  # pragma: no cover - compiled
    """numpy.argmin (argmax with ``largest``) of the 1-D array c: the first NaN, else the first smallest (largest)."""
    best, idx = c[0], 0
    if best != best:
        return 0
    for i in range(1, len(c)):
        x = c[i]
        if x != x:
            return i
        if (x > best) if largest else (x < best):
            best, idx = x, i
    return idx


@njit(cache=True, nogil=True)
def position_extremes(q, v, a1, a2, tau, h, qs, vs):  # pragma: no cover - compiled
    """(4, N − 1, dof): min q, its time, max q, its time per step and joint of the two-arc motion (q, v at the
    samples, arcs a1, a2 switching at tau, steps h (N − 1, 1), q and q̇ at the switch qs, vs), as
    StepMotion._position_extremes' numpy path: the candidates (q at both ends, at the switch, at each arc's vertex
    inside it) and their times, the first of the smallest and largest (a NaN first)."""
    m, dof = tau.shape
    out = np.empty((4, m, dof))
    cand, times = np.empty(5), np.empty(5)
    for k in range(m):
        H = h[k, 0]
        for j in range(dof):
            q0, v0, A1, A2, T, QS, VS = q[k, j], v[k, j], a1[k, j], a2[k, j], tau[k, j], qs[k, j], vs[k, j]
            s1 = -v0 / A1 if A1 != 0 else -1.0
            u2 = -VS / A2 if A2 != 0 else -1.0
            in1 = (s1 > 0) and (s1 < T)
            in2 = (u2 > 0) and (u2 < H - T)
            cand[0], cand[1], cand[2] = q0, q[k + 1, j], QS
            cand[3] = (q0 + v0 * s1) + A1 * (s1 * s1) / 2 if in1 else q0
            cand[4] = (QS + VS * u2) + A2 * (u2 * u2) / 2 if in2 else q0
            times[0], times[1], times[2] = 0.0, H, T
            times[3] = s1 if in1 else 0.0
            times[4] = T + u2 if in2 else 0.0
            lo, hi = _first_extreme(cand, False), _first_extreme(cand, True)
            out[0, k, j], out[1, k, j], out[2, k, j], out[3, k, j] = cand[lo], times[lo], cand[hi], times[hi]
    return out


@njit(cache=True, nogil=True)
def velocity_extremes(v, vs, tau, h):  # pragma: no cover - compiled
    """(2, N − 1, dof): the largest |q̇| per step and joint and its time (at the start, the switch tau or the end h),
    as StepMotion._velocity_extremes' numpy path (the first largest; a NaN first)."""
    m, dof = tau.shape
    out = np.empty((2, m, dof))
    c = np.empty(3)
    for k in range(m):
        for j in range(dof):
            c[0], c[1], c[2] = abs(v[k, j]), abs(vs[k, j]), abs(v[k + 1, j])
            i = _first_extreme(c, True)
            out[0, k, j] = c[i]
            out[1, k, j] = 0.0 if i == 0 else tau[k, j] if i == 1 else h[k, 0]
    return out


@njit(cache=True, nogil=True)
def _nmin(a, b):  # pragma: no cover - compiled
    """numpy.minimum of two floats: a NaN (the first) if either is one."""
    if a != a:
        return a
    if b != b:
        return b
    return a if a <= b else b


@njit(cache=True, nogil=True)
def _nmax(a, b):  # pragma: no cover - compiled
    """numpy.maximum of two floats: a NaN (the first) if either is one."""
    if a != a:
        return a
    if b != b:
        return b
    return a if a >= b else b


@njit(cache=True, nogil=True)
def _dsig(x, k):  # pragma: no cover - compiled
    """σ'(x) of the Coulomb smoothing k, as arc_torques._with_friction writes it: k / (1 + (kx)²)^1.5."""
    y = k * x
    return k / (1.0 + y * y) ** 1.5


@njit(cache=True, nogil=True)
def _friction_rates(dm, dr, V0, V1, a_lo, a_hi, fv, fc, k, d_lo, d_hi):  # pragma: no cover - compiled
    """[d_lo, d_hi] of arc_torques._with_friction per group and joint (finite inputs), the same operations."""
    for g in range(dm.shape[0]):
        for j in range(dm.shape[1]):
            vlo, vhi = V0[g, j] - V1[g, j], V0[g, j] + V1[g, j]
            m = 0.0 if 0.0 > vlo else vlo  # numpy.clip(0.0, vlo, vhi) (finite)
            near = m if m < vhi else vhi
            far = vlo if abs(vlo) > abs(vhi) else vhi
            sn, sf = fc[j] * _dsig(near, k), fc[j] * _dsig(far, k)
            f_lo, f_hi = fv[j] + _nmin(sn, sf), fv[j] + _nmax(sn, sf)
            p0, p1, p2, p3 = f_lo * a_lo[g, j], f_lo * a_hi[g, j], f_hi * a_lo[g, j], f_hi * a_hi[g, j]
            d_lo[g, j] = (dm[g, j] - dr[g, j]) + _nmin(_nmin(_nmin(p0, p1), p2), p3)
            d_hi[g, j] = (dm[g, j] + dr[g, j]) + _nmax(_nmax(_nmax(p0, p1), p2), p3)


_FLOAT_MAX = 1.7976931348623157e308  # what numpy.nan_to_num puts for +inf


@njit(cache=True, nogil=True, error_model="numpy")
def _crossing(num, den, delta):  # pragma: no cover - compiled
    """numpy.clip(numpy.nan_to_num(num / den), 0, delta) (delta finite; a division by 0 is IEEE's, as numpy's)."""
    x = num / den
    if x != x:
        x = 0.0
    elif x == np.inf:
        x = _FLOAT_MAX
    elif x == -np.inf:
        x = -_FLOAT_MAX
    x = x if x > 0.0 else 0.0
    return x if x < delta else delta


@njit(cache=True, nogil=True)
def steps_certified(dm, dr, V0, V1, a_lo, a_hi, fv, fc, k, group, ta, tb, J, h, lim):  # pragma: no cover
    """(S, dof) bool: step s (of group group[s], length h[s]) certified for joint j by arc_torques._step_prefilter's
    bounds: the groups' rate enclosures with friction (:func:`_friction_rates` of the link-side rates dm ± dr, q̇ in
    V0 ± V1, accelerations in [a_lo, a_hi]), then _upper of (ta + J, tb + J) ≤ lim and _lower of (ta − J, tb − J)
    ≥ −lim, the same operations as the numpy path. (0, dof) when an input is not finite or not below 1e100 in
    size: the numpy path decides those (no intermediate here overflows otherwise)."""
    for x in (dm, dr, V0, V1, a_lo, a_hi, ta, tb, J):
        for v in x.flat:
            if not abs(v) < 1e100:
                return np.empty((0, dm.shape[1]), np.bool_)
    for v in h:
        if not abs(v) < 1e100:
            return np.empty((0, dm.shape[1]), np.bool_)
    d_lo, d_hi = np.empty(dm.shape), np.empty(dm.shape)
    _friction_rates(dm, dr, V0, V1, a_lo, a_hi, fv, fc, k, d_lo, d_hi)
    S, dof = ta.shape
    out = np.empty((S, dof), np.bool_)
    for s in range(S):
        delta = h[s]
        for j in range(dof):
            lo, hi = d_lo[group[s], j], d_hi[group[s], j]
            a, b = ta[s, j] + J[s, j], tb[s, j] + J[s, j]
            ts = _crossing(b - a - lo * delta, hi - lo, delta)
            ub = _nmin(a + hi * 0.0, b - lo * (delta - 0.0))
            ub = _nmax(ub, _nmin(a + hi * (delta + 0.0), b - lo * (delta - (delta + 0.0))))
            ub = _nmax(ub, _nmin(a + hi * ts, b - lo * (delta - ts)))
            a, b = ta[s, j] - J[s, j], tb[s, j] - J[s, j]
            tl = _crossing(b - a - hi * delta, lo - hi, delta)
            lb = _nmax(a + lo * 0.0, b - hi * (delta - 0.0))
            lb = _nmin(lb, _nmax(a + lo * (delta + 0.0), b - hi * (delta - (delta + 0.0))))
            lb = _nmin(lb, _nmax(a + lo * tl, b - hi * (delta - tl)))
            out[s, j] = (ub <= lim[j]) and (lb >= -lim[j])
    return out


@njit(cache=True, nogil=True)
def prefilter_boxes(steps, chunk, mn, mx, v, vs, a1, a2, h, tau, rtol):  # pragma: no cover - compiled
    """arc_torques._boxes: the sorted ``steps`` grouped by ``chunk`` from the first, and per group its box, the numpy
    path's operations in its order (numpy.minimum/maximum's NaN rule, reduceat's row order): q (mid, radius) of the
    position extremes mn/mx, q̇ (mid, radius) of v at both samples and vs (the switch), q̈ [lo, hi] of a1 and a2;
    radii widened by ``rtol`` (arc_torques._interval). Per step its group, h (S, 1) and |a2 − a1| where the
    acceleration switches inside it (0 elsewhere); per group whether one of its steps switches. h: (N−1,)."""
    S, dof = len(steps), mn.shape[1]
    group = np.empty(S, np.int64)
    G = 0
    for s in range(S):
        if s == 0 or (steps[s] - steps[0]) // chunk != (steps[s - 1] - steps[0]) // chunk:
            G += 1
        group[s] = G - 1
    lo, hi = np.empty((3, G, dof)), np.empty((3, G, dof))  # q, q̇, q̈
    hs, dA, need = np.empty((S, 1)), np.empty((S, dof)), np.zeros(G, np.bool_)
    for s in range(S):
        k, g = steps[s], group[s]
        first = s == 0 or group[s - 1] != g
        hs[s, 0] = h[k]
        for j in range(dof):
            x_lo = (mn[k, j], _nmin(_nmin(v[k, j], vs[k, j]), v[k + 1, j]), _nmin(a1[k, j], a2[k, j]))
            x_hi = (mx[k, j], _nmax(_nmax(v[k, j], vs[k, j]), v[k + 1, j]), _nmax(a1[k, j], a2[k, j]))
            for i in range(3):
                lo[i, g, j] = x_lo[i] if first else _nmin(lo[i, g, j], x_lo[i])
                hi[i, g, j] = x_hi[i] if first else _nmax(hi[i, g, j], x_hi[i])
            t = tau[k, j]
            dA[s, j] = abs(a2[k, j] - a1[k, j]) if t > 0.0 and t < h[k] and a1[k, j] != a2[k, j] else 0.0
            if dA[s, j] != 0.0:
                need[g] = True
    mid, rad = np.empty((2, G, dof)), np.empty((2, G, dof))
    for i in range(2):
        for g in range(G):
            for j in range(dof):
                m, w = (lo[i, g, j] + hi[i, g, j]) / 2, hi[i, g, j] - lo[i, g, j]
                mid[i, g, j], rad[i, g, j] = m, w / 2 + rtol * (abs(m) + abs(w) + 1.0)
    return group, mid[0], rad[0], mid[1], rad[1], lo[2], hi[2], hs, dA, need


# ---------------------------------------------------------------------------------------------------------
# readiness: compile in the background, never stall a caller on the compilation (core.jit_cache.KernelModule)
# ---------------------------------------------------------------------------------------------------------
def _warm() -> None:
    """The kernel called once on tiny arguments (compiles or loads it)."""
    n = 2
    z = np.zeros((1, n))
    m3 = np.zeros((n, 3, 3))
    for writeable in (True, False):   # the gravity's acceleration: a read-only array of the robot's
        acc0 = np.zeros((1, 3))
        acc0.flags.writeable = writeable
        link_torques(z, z, z, z, z, z, acc0, z, z, np.zeros(n, np.int64), np.array([0, 1], np.int64),
                     np.ones(n), m3, m3, np.ones(n), m3, m3)
    i = np.zeros(1, np.int64)
    tcp_twists(np.zeros((1, 1, 4, 4)), np.zeros((1, 4, 4)), np.zeros((1, 1)), i, np.zeros(1, np.bool_), i, np.ones(1))
    a, b = np.zeros((2, 1)), np.zeros((1, 1))
    position_extremes(a, a, b, b, b, b, b, b)
    step_arcs(a, a, np.ones(1))
    step_at(np.zeros((1, 6, 1)), 0, 0.5)
    velocity_extremes(a, b, b, b)
    f = np.zeros(1)
    steps_certified(b, b, b, b, b, b, f, f, 1.0, i, b, b, b, f, f)
    prefilter_boxes(i, 16, b, b, a, b, b, b, f, b, 1e-12)


KERNELS = KernelModule("robodesign.judge.interval_kernel", __file__, link_torques,
                       ("link_torques", "tcp_twists", "step_arcs", "step_at", "position_extremes",
                        "velocity_extremes", "steps_certified", "prefilter_boxes"), _warm)
available, compiled, warm_up, ready = KERNELS.available, KERNELS.compiled, KERNELS.warm_up, KERNELS.ready
compile_into_cache = KERNELS.compile_into_cache

if __name__ == "__main__":
    sys.exit(KERNELS.main())
