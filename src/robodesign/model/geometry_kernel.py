"""Compiled (numba) kernels of a robot's geometry: its joint poses at a configuration, forward kinematics batched
over samples, and the broad phase of a configuration's collision query.

:func:`frame_poses` and :func:`joint_poses` are :class:`robodesign.model.batch_fk._BatchKinematics`'s passes over
the samples, one sample at a time in compiled loops (the same products of the same placements; equal to the numpy
path and to pinocchio to rounding, tests/test_fk_batch.py).

:meth:`robodesign.model.collision_cull.CollisionCuller.in_collision` asks coal only about the pairs
:func:`survivors` returns, with the bounds of :mod:`.collision_cull` (a bounding sphere per robot geometry, its
centre from the joint poses of this configuration):

* a self pair survives when its spheres lie within the pair's limit (radii + security margin + slack);
* a robot–obstacle pair survives when the sphere's centre lies within the limit of the obstacle's bounding box
  (the coal shape's local AABB, in the obstacle's frame: it contains the shape, so its distance is a lower
  bound) and, for an obstacle with a distance grid (:class:`~.collision_cull.DistanceField`), within the limit
  of the grid's lower bound: the exact distance from the centre of the point's cell minus the point's distance
  to that centre. A cell not computed yet lets the pair survive (coal decides) and is reported, so that the
  caller can fill it for the next queries;
* a surviving self pair whose inner spheres (:mod:`.inner_spheres`) overlap by more than the slack beyond its
  margin is reported as proven colliding: coal would find it so, and the culler then asks coal nothing. So is
  the pair coal found colliding last when one of its convex hulls holds a point of an edge of the other deeper than
  |margin − slack| (only that pair: the test costs ~1 µs a pair, and ~11 pairs survive a query).

Every bound is conservative (slack on top of the margin far above coal's tolerances), so the verdict is the
one ``pin.computeCollisions`` gives (tests/test_geometry_kernel.py compares them state by state). Without numba
(or before its background compilation has filled the cache) the numpy paths run and the robot asks coal about
every pair, as before.
"""
from __future__ import annotations

import sys

import numpy as np

from robodesign.core.jit_cache import KernelModule, njit


@njit(cache=True, nogil=True)
def _joint_poses(q, parents, Rl, tl, kind, axis, iq, R, p):  # pragma: no cover
    """The world rotation ``R[j]`` and position ``p[j]`` of every joint frame at ``q`` (index 0: the world)."""
    J = len(parents)
    for i in range(3):
        for j in range(3):
            R[0, i, j] = 1.0 if i == j else 0.0
        p[0, i] = 0.0
    for j in range(1, J + 1):
        k = j - 1
        par = parents[k]
        for r in range(3):           # R_j = R_par · Rl, p_j = p_par + R_par · tl
            acc = p[par, r]
            for m in range(3):
                acc += R[par, r, m] * tl[k, m]
            p[j, r] = acc
            for c in range(3):
                acc = 0.0
                for m in range(3):
                    acc += R[par, r, m] * Rl[k, m, c]
                R[j, r, c] = acc
        x = q[iq[k]]
        a0, a1, a2 = axis[k, 0], axis[k, 1], axis[k, 2]
        if kind[k] == 1:             # prismatic: p += R·a·x
            for r in range(3):
                p[j, r] += (R[j, r, 0] * a0 + R[j, r, 1] * a1 + R[j, r, 2] * a2) * x
        else:                        # revolute: R ← R·(I + s K + (1 − c) K²), K = [a]×
            cs, sn = np.cos(x), np.sin(x)
            v = 1.0 - cs
            m00, m01, m02 = cs + v * a0 * a0, v * a0 * a1 - sn * a2, v * a0 * a2 + sn * a1
            m10, m11, m12 = v * a0 * a1 + sn * a2, cs + v * a1 * a1, v * a1 * a2 - sn * a0
            m20, m21, m22 = v * a0 * a2 - sn * a1, v * a1 * a2 + sn * a0, cs + v * a2 * a2
            for r in range(3):
                b0, b1, b2 = R[j, r, 0], R[j, r, 1], R[j, r, 2]
                R[j, r, 0] = b0 * m00 + b1 * m10 + b2 * m20
                R[j, r, 1] = b0 * m01 + b1 * m11 + b2 * m21
                R[j, r, 2] = b0 * m02 + b1 * m12 + b2 * m22


@njit(cache=True, nogil=True)
def frame_poses(Q, parents, Rl, tl, kind, axis, iq, jid, Rf, tf, R, p, out):  # pragma: no cover
    """``out[n]`` (4×4): the world pose of the frame on joint ``jid`` at placement (Rf, tf) at every row of ``Q``."""
    for n in range(len(Q)):
        _joint_poses(Q[n], parents, Rl, tl, kind, axis, iq, R, p)
        for i in range(3):
            for j in range(3):
                out[n, i, j] = R[jid, i, 0] * Rf[0, j] + R[jid, i, 1] * Rf[1, j] + R[jid, i, 2] * Rf[2, j]
            out[n, i, 3] = p[jid, i] + (R[jid, i, 0] * tf[0] + R[jid, i, 1] * tf[1] + R[jid, i, 2] * tf[2])
            out[n, 3, i] = 0.0
        out[n, 3, 3] = 1.0


@njit(cache=True, nogil=True)
def joint_poses(Q, parents, Rl, tl, kind, axis, iq, R, p, out):  # pragma: no cover
    """``out[n, j]`` (4×4): the world pose of every joint frame ``j`` (0: the world) at every row of ``Q``."""
    for n in range(len(Q)):
        _joint_poses(Q[n], parents, Rl, tl, kind, axis, iq, R, p)
        for j in range(len(parents) + 1):
            for i in range(3):
                for c in range(3):
                    out[n, j, i, c] = R[j, i, c]
                out[n, j, i, 3] = p[j, i]
                out[n, j, 3, i] = 0.0
            out[n, j, 3, 3] = 1.0


@njit(cache=True, nogil=True)
def _inner_overlap(a, b, lim, gpar, istart, ilocal, irad, R, p):  # pragma: no cover
    """Whether an inner sphere of geometry ``a`` and one of ``b`` (centres ``ilocal`` in their joints' frames,
    ``istart``: each geometry's first) lie closer than their radii + ``lim`` (the pair's margin − slack)."""
    ja, jb = gpar[a], gpar[b]
    for u in range(istart[a], istart[a + 1]):
        x0 = p[ja, 0] + R[ja, 0, 0] * ilocal[u, 0] + R[ja, 0, 1] * ilocal[u, 1] + R[ja, 0, 2] * ilocal[u, 2]
        x1 = p[ja, 1] + R[ja, 1, 0] * ilocal[u, 0] + R[ja, 1, 1] * ilocal[u, 1] + R[ja, 1, 2] * ilocal[u, 2]
        x2 = p[ja, 2] + R[ja, 2, 0] * ilocal[u, 0] + R[ja, 2, 1] * ilocal[u, 1] + R[ja, 2, 2] * ilocal[u, 2]
        for v in range(istart[b], istart[b + 1]):
            reach = irad[u] + irad[v] + lim
            if reach <= 0.0:
                continue
            d0 = x0 - (p[jb, 0] + R[jb, 0, 0] * ilocal[v, 0] + R[jb, 0, 1] * ilocal[v, 1] + R[jb, 0, 2] * ilocal[v, 2])
            d1 = x1 - (p[jb, 1] + R[jb, 1, 0] * ilocal[v, 0] + R[jb, 1, 1] * ilocal[v, 1] + R[jb, 1, 2] * ilocal[v, 2])
            d2 = x2 - (p[jb, 2] + R[jb, 2, 0] * ilocal[v, 0] + R[jb, 2, 1] * ilocal[v, 1] + R[jb, 2, 2] * ilocal[v, 2])
            if d0 * d0 + d1 * d1 + d2 * d2 < reach * reach:
                return True
    return False


@njit(cache=True, nogil=True)
def _moved(ja, jb, R, p, x0, x1, x2):  # pragma: no cover
    """The point (x0, x1, x2) of joint ``ja``'s frame in joint ``jb``'s frame."""
    e0 = p[ja, 0] + R[ja, 0, 0] * x0 + R[ja, 0, 1] * x1 + R[ja, 0, 2] * x2 - p[jb, 0]
    e1 = p[ja, 1] + R[ja, 1, 0] * x0 + R[ja, 1, 1] * x1 + R[ja, 1, 2] * x2 - p[jb, 1]
    e2 = p[ja, 2] + R[ja, 2, 0] * x0 + R[ja, 2, 1] * x1 + R[ja, 2, 2] * x2 - p[jb, 2]
    return (R[jb, 0, 0] * e0 + R[jb, 1, 0] * e1 + R[jb, 2, 0] * e2, R[jb, 0, 1] * e0 + R[jb, 1, 1] * e1
            + R[jb, 2, 1] * e2, R[jb, 0, 2] * e0 + R[jb, 1, 2] * e1 + R[jb, 2, 2] * e2)


@njit(cache=True, nogil=True)
def _edge_inside(a, b, lim, gpar, istart, ilocal, irad, R, p):  # pragma: no cover
    """Whether a point of a hull edge of geometry ``a`` lies inside the hull of ``b`` with every face plane's
    ``n·x + d`` below −|``lim``| (``lim``: the pair's margin − slack; the edges' ends in pairs of rows and the planes:
    :func:`~.inner_spheres.placed_inner_spheres`' second and third blocks, in their joints' frames): each edge is
    clipped by the planes (Cyrus–Beck). Such a point is one of ``a`` (the edge lies in its convex hull) whose depth
    in ``b`` (> |lim|, its distance to b's boundary) bounds the penetration from below, so the pair's distance is at
    most −depth < lim: coal finds it colliding."""
    top = -abs(lim)
    G1 = len(gpar) + 1
    f0, f1 = istart[2 * G1 + b], istart[2 * G1 + b + 1]
    if f0 == f1:
        return False
    ja, jb = gpar[a], gpar[b]
    for u in range(istart[G1 + a], istart[G1 + a + 1], 2):
        y0, y1, y2 = _moved(ja, jb, R, p, ilocal[u, 0], ilocal[u, 1], ilocal[u, 2])
        z0, z1, z2 = _moved(ja, jb, R, p, ilocal[u + 1, 0], ilocal[u + 1, 1], ilocal[u + 1, 2])
        lo, hi = 0.0, 1.0   # the part of the edge (y + t (z − y)) below every plane so far
        for f in range(f0, f1):
            s0 = ilocal[f, 0] * y0 + ilocal[f, 1] * y1 + ilocal[f, 2] * y2 + irad[f] - top
            s1 = ilocal[f, 0] * z0 + ilocal[f, 1] * z1 + ilocal[f, 2] * z2 + irad[f] - top
            if s0 >= 0.0 and s1 >= 0.0:
                hi = -1.0
            elif s0 >= 0.0:
                lo = max(lo, s0 / (s0 - s1))
            elif s1 >= 0.0:
                hi = min(hi, s0 / (s0 - s1))
            if not lo < hi:
                break
        if lo < hi:
            return True
    return False


@njit(cache=True, nogil=True)
def survivors(q, parents, Rl, tl, kind, axis, iq, gpar, glocal, sa, sb, slim, sk, istart, ilocal, irad, sproof,
              oa, ob, olim, ok, oR, ot, olo, ohi, grid_lo, grid_dim, grid_off, h, grid, active, R, p, C, out,
              unknown):  # pragma: no cover
    """:func:`_bounds` at ``q``, with the proof of collision of its surviving self pairs: returns (surviving pairs,
    unknown cells, the first surviving self pair whose inner spheres overlap (:mod:`.inner_spheres`), or -1)."""
    return _bounds(q, parents, Rl, tl, kind, axis, iq, gpar, glocal, sa, sb, slim, sk, istart, ilocal, irad, sproof,
                   oa, ob, olim, ok, oR, ot, olo, ohi, grid_lo, grid_dim, grid_off, h, grid, active, R, p, C, out,
                   unknown, -1)


@njit(cache=True, nogil=True)
def _bounds(q, parents, Rl, tl, kind, axis, iq, gpar, glocal, sa, sb, slim, sk, istart, ilocal, irad, sproof,
            oa, ob, olim, ok, oR, ot, olo, ohi, grid_lo, grid_dim, grid_off, h, grid, active, R, p, C, out, unknown,
            prove):  # pragma: no cover
    """The pairs (indices: the self pairs' in their order, then the robot–obstacle pairs') that the bounds do not
    clear at ``q``, written to ``out``; the grid cells (flat indices into ``grid``) asked but not known, written to
    ``unknown``; ``R``, ``p`` (the joints' world poses) and ``C`` (the spheres' centres) are scratch space. With
    ``prove`` ≥ −1, the first surviving self pair ``sk[i]`` whose inner spheres lie closer than their radii +
    ``sproof[i]`` or, when it is pair ``prove``, one of whose hull edges has a point inside the other's hull with every
    plane below −|``sproof[i]``| (it collides; −1: no hull tested, −2: no proof). Returns (surviving pairs, unknown
    cells, that pair or -1)."""
    _joint_poses(q, parents, Rl, tl, kind, axis, iq, R, p)
    for g in range(len(gpar)):
        jg = gpar[g]
        for r in range(3):
            C[g, r] = p[jg, r] + R[jg, r, 0] * glocal[g, 0] + R[jg, r, 1] * glocal[g, 1] + R[jg, r, 2] * glocal[g, 2]
    n = 0
    hit = -1
    for i in range(len(sa)):
        if not active[sk[i]]:
            continue
        d0 = C[sa[i], 0] - C[sb[i], 0]
        d1 = C[sa[i], 1] - C[sb[i], 1]
        d2 = C[sa[i], 2] - C[sb[i], 2]
        if d0 * d0 + d1 * d1 + d2 * d2 <= slim[i] * slim[i]:
            out[n] = sk[i]
            n += 1
            if prove >= -1 and hit < 0 and (
                    _inner_overlap(sa[i], sb[i], sproof[i], gpar, istart, ilocal, irad, R, p)
                    or (sk[i] == prove and (_edge_inside(sa[i], sb[i], sproof[i], gpar, istart, ilocal, irad, R, p)
                                            or _edge_inside(sb[i], sa[i], sproof[i], gpar, istart, ilocal, irad, R, p)))):
                hit = sk[i]
    nu = 0
    for i in range(len(oa)):
        if not active[ok[i]]:
            continue
        o = ob[i]
        lim = olim[i]
        g = oa[i]
        dd = 0.0
        for a in range(3):           # the centre in the obstacle's frame, and its distance to the shape's box
            xa = (oR[o, a, 0] * (C[g, 0] - ot[o, 0]) + oR[o, a, 1] * (C[g, 1] - ot[o, 1])
                  + oR[o, a, 2] * (C[g, 2] - ot[o, 2]))
            e = max(olo[o, a] - xa, xa - ohi[o, a], 0.0)
            dd += e * e
        if dd > lim * lim:
            continue                 # farther from the shape's box than the limit
        if grid_dim[o, 0] > 0:
            inside = True
            flat = 0
            dc = 0.0
            for a in range(3):
                ia = int(np.floor(C[g, a] / h))
                la = ia - grid_lo[o, a]
                if la < 0 or la >= grid_dim[o, a]:
                    inside = False
                    break
                flat = flat * grid_dim[o, a] + la
                e = C[g, a] - (ia + 0.5) * h
                dc += e * e
            if inside:
                v = grid[grid_off[o] + flat]
                if np.isnan(v):
                    unknown[nu] = grid_off[o] + flat
                    nu += 1
                elif v - np.sqrt(dc) > lim:
                    continue         # the cell's exact distance clears it
        out[n] = ok[i]
        n += 1
    return n, nu, hit



#: the positions, among :func:`survivors`' arguments after ``q``, of the integer arrays and of the float arrays (with
#: ``h``) that :func:`pack` lays end to end for :func:`survivors_packed`; ``grid`` and ``active`` stay apart (the
#: fields and the culler write to them in place)
_INTS = (0, 3, 5, 6, 8, 9, 11, 12, 16, 17, 19, 24, 25, 26, 33, 34)
_FLOATS = (1, 2, 4, 7, 10, 13, 14, 15, 18, 20, 21, 22, 23, 27, 30, 31, 32)
_GRID, _ACTIVE = 28, 29


def pack(args: tuple) -> tuple:
    """(packed, views): :func:`survivors`' arguments after ``q`` as :func:`survivors_packed` takes them (an int64
    array: the sizes J, G, S, U, P, O and len(out), then the integer arrays; a float array; ``grid``; ``active``),
    and the same arguments as views into those arrays (``grid`` and ``active`` themselves): a kernel writing to the
    scratch space or the outputs of one writes to the other's. Fewer arguments: numba's dispatcher types and
    unboxes each one at every call."""
    ints = [np.asarray(args[k], np.int64) for k in _INTS]
    floats = [np.asarray(args[k], np.float64) for k in _FLOATS]
    head = np.array([len(args[0]), len(args[6]), len(args[8]), len(args[14]), len(args[16]), len(args[20]),
                     len(args[33])], np.int64)
    packed = (np.concatenate([head] + [a.ravel() for a in ints]), np.concatenate([a.ravel() for a in floats]),
              args[_GRID], args[_ACTIVE])
    views = list(args)
    for whole, ks, parts, off in ((packed[0], _INTS, ints, len(head)), (packed[1], _FLOATS, floats, 0)):
        for k, a in zip(ks, parts):
            views[k] = whole[off:off + a.size].reshape(a.shape) if a.ndim else float(whole[off])
            off += a.size
    return packed, tuple(views)


@njit(cache=True, nogil=True)
def _int_views(I):  # pragma: no cover
    """The integer arrays of :func:`pack`'s first array, in :data:`_INTS`' order (views)."""
    J, G, S, P, O, n_out = I[0], I[1], I[2], I[4], I[5], I[6]
    i = 7
    parents, kind, iq = I[i:i + J], I[i + J:i + 2 * J], I[i + 2 * J:i + 3 * J]
    i += 3 * J
    gpar = I[i:i + G]
    i += G
    sa, sb, sk = I[i:i + S], I[i + S:i + 2 * S], I[i + 2 * S:i + 3 * S]
    i += 3 * S
    istart = I[i:i + 3 * (G + 1)]
    i += 3 * (G + 1)
    oa, ob, ok = I[i:i + P], I[i + P:i + 2 * P], I[i + 2 * P:i + 3 * P]
    i += 3 * P
    grid_lo, grid_dim = I[i:i + 3 * O].reshape((O, 3)), I[i + 3 * O:i + 6 * O].reshape((O, 3))
    i += 6 * O
    grid_off = I[i:i + O]
    i += O
    return parents, kind, iq, gpar, sa, sb, sk, istart, oa, ob, ok, grid_lo, grid_dim, grid_off, I[i:i + n_out], \
        I[i + n_out:i + n_out + P + 1]


@njit(cache=True, nogil=True)
def _float_views(F, I):  # pragma: no cover
    """The float arrays of :func:`pack`'s second array (and ``h``), in :data:`_FLOATS`' order (views)."""
    J, G, S, U, P, O = I[0], I[1], I[2], I[3], I[4], I[5]
    Rl, tl, axis = F[:9 * J].reshape((J, 3, 3)), F[9 * J:12 * J].reshape((J, 3)), F[12 * J:15 * J].reshape((J, 3))
    i = 15 * J
    glocal = F[i:i + 3 * G].reshape((G, 3))
    i += 3 * G
    slim = F[i:i + S]
    i += S
    ilocal, irad = F[i:i + 3 * U].reshape((U, 3)), F[i + 3 * U:i + 4 * U]
    i += 4 * U
    sproof, olim = F[i:i + S], F[i + S:i + S + P]
    i += S + P
    oR = F[i:i + 9 * O].reshape((O, 3, 3))
    i += 9 * O
    ot, olo, ohi = F[i:i + 3 * O].reshape((O, 3)), F[i + 3 * O:i + 6 * O].reshape((O, 3)), \
        F[i + 6 * O:i + 9 * O].reshape((O, 3))
    i += 9 * O
    h = F[i]
    i += 1
    R, p = F[i:i + 9 * (J + 1)].reshape((J + 1, 3, 3)), F[i + 9 * (J + 1):i + 12 * (J + 1)].reshape((J + 1, 3))
    i += 12 * (J + 1)
    return Rl, tl, axis, glocal, slim, ilocal, irad, sproof, olim, oR, ot, olo, ohi, h, R, p, \
        F[i:i + 3 * G].reshape((G, 3))


@njit(cache=True, nogil=True)
def survivors_packed(q, I, F, grid, active, left, due, last):  # pragma: no cover
    """:func:`survivors` at ``q`` on its arguments as :func:`pack` lays them out (the same bounds, the same
    outputs: the views of ``out`` and ``unknown`` in ``I``), then the asks of coal counted down: ``left[k]`` (the
    asks left before pair ``k``'s proof; none when ``left`` is empty) lowered by one for each surviving pair above 0,
    the pairs it takes to 0 written to ``due`` in their order; the hull proof is tried on pair ``last`` (the one coal
    found colliding last: the converged IK solutions that collide mostly share it; −1: none). Returns (surviving
    pairs, unknown cells, the proven
    colliding pair or -1, pairs due)."""
    parents, kind, iq, gpar, sa, sb, sk, istart, oa, ob, ok, grid_lo, grid_dim, grid_off, out, unknown = _int_views(I)
    Rl, tl, axis, glocal, slim, ilocal, irad, sproof, olim, oR, ot, olo, ohi, h, R, p, C = _float_views(F, I)
    n, nu, hit = _bounds(q, parents, Rl, tl, kind, axis, iq, gpar, glocal, sa, sb, slim, sk, istart, ilocal, irad,
                         sproof, oa, ob, olim, ok, oR, ot, olo, ohi, grid_lo, grid_dim, grid_off, h, grid, active, R, p,
                         C, out, unknown, last)
    m = 0
    if len(left):
        for i in range(n):
            k = out[i]
            if left[k] > 0:
                left[k] -= 1
                if left[k] == 0:
                    due[m] = k
                    m += 1
    return n, nu, hit, m


@njit(cache=True, nogil=True)
def survivors_rows(Q, parents, Rl, tl, kind, axis, iq, gpar, glocal, sa, sb, slim, sk, istart, ilocal, irad, sproof,
                   oa, ob, olim, ok, oR, ot, olo, ohi, grid_lo, grid_dim, grid_off, h, grid, active, R, p, C, out,
                   unknown, S, unknown_all):  # pragma: no cover
    """:func:`_bounds` of every row of ``Q`` (no proofs): ``S[i, k]`` set for the pairs ``k`` that survive at row
    ``i`` (``S`` all False on entry); the unknown cells of all rows in ``unknown_all`` (room for ``len(ok)`` per
    row). Returns the number of unknown cells."""
    nu_all = 0
    for i in range(len(Q)):
        n, nu, _ = _bounds(Q[i], parents, Rl, tl, kind, axis, iq, gpar, glocal, sa, sb, slim, sk, istart, ilocal,
                           irad, sproof, oa, ob, olim, ok, oR, ot, olo, ohi, grid_lo, grid_dim, grid_off, h, grid,
                           active, R, p, C, out, unknown, -2)
        for k in range(n):
            S[i, out[k]] = True
        for k in range(nu):
            unknown_all[nu_all + k] = unknown[k]
        nu_all += nu
    return nu_all


# ---------------------------------------------------------------------------------------------------------
# readiness: compile in the background, never stall a caller on the compilation (core.jit_cache.KernelModule)
# ---------------------------------------------------------------------------------------------------------
def _warm() -> None:
    """Every kernel called once on tiny arguments (compiles or loads them). The stamp is looked for at most once a
    second while the cache is cold: the culler and batched FK ask often."""
    i1, f1 = np.zeros(1, np.int64), np.zeros(1)
    args = (i1, np.zeros((1, 3, 3)), np.zeros((1, 3)), i1, np.zeros((1, 3)), i1, i1, np.zeros((1, 3)), i1, i1, f1, i1,
            np.zeros(6, np.int64), np.zeros((1, 3)), f1, f1, i1, i1, f1, i1, np.zeros((1, 3, 3)), np.zeros((1, 3)),
            np.zeros((1, 3)), np.zeros((1, 3)),
            np.zeros((1, 3), np.int64), np.zeros((1, 3), np.int64), i1, 1.0, f1, np.ones(1, np.bool_),
            np.zeros((2, 3, 3)), np.zeros((2, 3)), np.zeros((1, 3)), np.zeros(2, np.int64), np.zeros(2, np.int64))
    survivors(np.zeros(1), *args)
    packed = (*pack(args)[0], np.zeros(1, np.int64), np.zeros(2, np.int64), -1)   # (+ asks left, pairs due, last)
    survivors_packed(np.zeros(1), *packed)
    survivors_rows(np.zeros((1, 1)), *args, np.zeros((1, 1), np.bool_), np.zeros(2, np.int64))
    tree = args[:6]
    for Rf in (np.eye(3), np.eye(3).T):   # the frame's rotation C- or F-ordered (a pinocchio matrix is the latter)
        frame_poses(np.zeros((1, 1)), *tree, 1, Rf, np.zeros(3), np.zeros((2, 3, 3)), np.zeros((2, 3)),
                    np.zeros((1, 4, 4)))
    joint_poses(np.zeros((1, 1)), *tree, np.zeros((2, 3, 3)), np.zeros((2, 3)), np.zeros((1, 2, 4, 4)))


KERNELS = KernelModule("robodesign.model.geometry_kernel", __file__, survivors,
                       ("survivors", "survivors_packed", "survivors_rows", "frame_poses", "joint_poses"), _warm,
                       every=1.0)
available, compiled, warm_up, ready = KERNELS.available, KERNELS.compiled, KERNELS.warm_up, KERNELS.ready
compile_into_cache = KERNELS.compile_into_cache

if __name__ == "__main__":
    sys.exit(KERNELS.main())
