"""pinocchio's inverse dynamics (``pinocchio.rnea``) at many samples, compiled (numba): the same floating-point
operations in the same order as pinocchio's own RNEA (pinocchio/src/algorithm/rnea.hxx with its joint, motion,
force, inertia and SE3 operations, as compiled with Eigen on SSE2, no FMA), so the same torques **bit for bit**
(tests/test_rnea_kernel.py) without a model pool's copy and pinocchio's cost per sample (issue 25).

Covered: chains of revolute and prismatic joints about a joint frame's x, y or z axis (pinocchio's
``JointModelR{X,Y,Z}`` and ``JointModelP{X,Y,Z}``) with armature; :func:`pack` returns None for any other model,
which keeps pinocchio. The orders that matter (found against pinocchio's data, tests/test_rnea_kernel.py):

- a rotation's transpose times a vector (``actInv``): every entry ((r₀x₀ + r₁x₁) + r₂x₂);
- a rotation times a vector (a force's ``act``): rows 0 and 1 ((r₀x₀ + r₁x₁) + r₂x₂) (Eigen's packet of two
  rows), row 2 r₀x₀ + (r₁x₁ + r₂x₂) (Eigen's unrolled sum of the remaining row);
- the cross product a × b: (a₁b₂ − a₂b₁, a₂b₀ − a₀b₂, a₀b₁ − a₁b₀); a symmetric inertia times a vector: every
  entry ((·) + (·)) + (·).

Readiness as :mod:`robodesign.model.sweep_kernel` (``ROBODESIGN_JIT=0`` switches the kernel off: pinocchio runs).
"""
from __future__ import annotations

import sys
from typing import Optional, Tuple

import numpy as np

from robodesign.core.jit_cache import KernelModule, njit

_KINDS = {"JointModelRX": (0, 0), "JointModelRY": (0, 1), "JointModelRZ": (0, 2),
          "JointModelPX": (1, 0), "JointModelPY": (1, 1), "JointModelPZ": (1, 2)}   # name → (prismatic?, axis)

Packed = Tuple[np.ndarray, ...]
_NEXT = np.array([1, 2, 0, 1])   # axis a → the next two axes (a + 1) % 3, (a + 2) % 3


def pack(model, armature: bool = True) -> Optional[Packed]:
    """The arrays :func:`rnea` reads for ``model`` (``armature`` False: as if the model had none), or None when
    a joint is not one of the covered types: (per joint: parent (−1: the universe), prismatic?, axis, q index,
    v index; placement rotations (n, 3, 3) and translations (n, 3); masses, levers (n, 3), rotational inertias
    (n, 6) as pinocchio's Symmetric3 (xx, xy, yy, xz, yz, zz); armature (nv); gravity (linear, angular))."""
    n = model.njoints - 1
    if n < 1 or model.nq != model.nv:
        return None
    ints, PR, Pt = np.empty((5, n), np.int64), np.empty((n, 3, 3)), np.empty((n, 3))
    mass, lever, sym = np.empty(n), np.empty((n, 3)), np.empty((n, 6))
    joints, parents, placements, inertias = model.joints, model.parents, model.jointPlacements, model.inertias
    for k in range(n):   # (one pass, each of pinocchio's accessors asked once: ~1 µs each)
        jm = joints[k + 1]
        kind = _KINDS.get(jm.shortname())
        if kind is None or jm.nq != 1:
            return None
        ints[:, k] = (parents[k + 1] - 1, kind[0], kind[1], jm.idx_q, jm.idx_v)
        H = placements[k + 1].homogeneous
        PR[k], Pt[k] = H[:3, :3], H[:3, 3]
        Y = inertias[k + 1]
        mass[k], lever[k], d = Y.mass, Y.lever, Y.inertia
        sym[k] = d[0, 0], d[0, 1], d[1, 1], d[0, 2], d[1, 2], d[2, 2]
    arm = np.array(model.armature, dtype=float) if armature else np.zeros(model.nv)
    return (ints[0], ints[1], ints[2], ints[3], ints[4], PR, Pt, mass, lever, sym, arm,
            np.array(model.gravity.vector, dtype=float))


@njit(cache=True, nogil=True, inline="always")
def _cross(a0, a1, a2, b0, b1, b2):  # pragma: no cover - compiled
    """a × b as Eigen's cross."""
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@njit(cache=True, nogil=True, inline="always")
def _rtv(R, k, x0, x1, x2):  # pragma: no cover - compiled
    """R[k]ᵀx, each entry ((R₀ᵢx₀ + R₁ᵢx₁) + R₂ᵢx₂)."""
    return ((R[k, 0, 0] * x0 + R[k, 1, 0] * x1) + R[k, 2, 0] * x2,
            (R[k, 0, 1] * x0 + R[k, 1, 1] * x1) + R[k, 2, 1] * x2,
            (R[k, 0, 2] * x0 + R[k, 1, 2] * x1) + R[k, 2, 2] * x2)


@njit(cache=True, nogil=True, inline="always")
def _rv(R, k, x0, x1, x2):  # pragma: no cover - compiled
    """R[k]x: rows 0 and 1 ((Rᵢ₀x₀ + Rᵢ₁x₁) + Rᵢ₂x₂), row 2 R₂₀x₀ + (R₂₁x₁ + R₂₂x₂) (Eigen's order)."""
    return ((R[k, 0, 0] * x0 + R[k, 0, 1] * x1) + R[k, 0, 2] * x2,
            (R[k, 1, 0] * x0 + R[k, 1, 1] * x1) + R[k, 1, 2] * x2,
            R[k, 2, 0] * x0 + (R[k, 2, 1] * x1 + R[k, 2, 2] * x2))


@njit(cache=True, nogil=True, inline="always")
def _inertia_times(m, c, S, k, x0, x1, x2, x3, x4, x5):  # pragma: no cover - compiled
    """The spatial inertia of joint k (mass m, lever c[k], Symmetric3 S[k]) times the motion x (linear x0..x2,
    angular x3..x5) as pinocchio's Inertia.__mult__: f.lin = m(x.lin − c × x.ang); f.ang = S x.ang + c × f.lin."""
    k0, k1, k2 = _cross(c[k, 0], c[k, 1], c[k, 2], x3, x4, x5)
    l0, l1, l2 = m * (x0 - k0), m * (x1 - k1), m * (x2 - k2)
    a0 = (S[k, 0] * x3 + S[k, 1] * x4) + S[k, 3] * x5
    a1 = (S[k, 1] * x3 + S[k, 2] * x4) + S[k, 4] * x5
    a2 = (S[k, 3] * x3 + S[k, 4] * x4) + S[k, 5] * x5
    e0, e1, e2 = _cross(c[k, 0], c[k, 1], c[k, 2], l0, l1, l2)
    return l0, l1, l2, a0 + e0, a1 + e1, a2 + e2


@njit(cache=True, nogil=True, inline="always")
def _placement(PR, Pt, k, kind, ax, q, R, T):  # pragma: no cover - compiled
    """R[k] (3, 3), T[k] (3,): joint k's placement (PR[k], Pt[k]) times its transform at q (pinocchio's
    TransformRevolute / TransformPrismatic se3Action)."""
    for i in range(3):
        T[k, i] = Pt[k, i]
        for j in range(3):
            R[k, i, j] = PR[k, i, j]
    if kind == 1:
        for i in range(3):
            T[k, i] = Pt[k, i] + PR[k, i, ax] * q
        return
    s, c = np.sin(q), np.cos(q)
    b, d = _NEXT[ax], _NEXT[ax + 1]
    for i in range(3):
        R[k, i, b] = c * PR[k, i, b] + s * PR[k, i, d]
    x0, x1, x2 = _cross(R[k, 0, ax], R[k, 1, ax], R[k, 2, ax], R[k, 0, b], R[k, 1, b], R[k, 2, b])
    R[k, 0, d], R[k, 1, d], R[k, 2, d] = x0, x1, x2


@njit(cache=True, nogil=True, inline="always")
def _add_act_inv(R, T, k, X, p, out):  # pragma: no cover - compiled
    """out[k] (6,) += the motion X[p] seen from joint k's frame (R[k], T[k]) (pinocchio's actInv):
    lin Rᵀ(x.lin − T × x.ang), ang Rᵀx.ang."""
    k0, k1, k2 = _cross(T[k, 0], T[k, 1], T[k, 2], X[p, 3], X[p, 4], X[p, 5])
    l0, l1, l2 = _rtv(R, k, X[p, 0] - k0, X[p, 1] - k1, X[p, 2] - k2)
    a0, a1, a2 = _rtv(R, k, X[p, 3], X[p, 4], X[p, 5])
    out[k, 0], out[k, 1], out[k, 2] = out[k, 0] + l0, out[k, 1] + l1, out[k, 2] + l2
    out[k, 3], out[k, 4], out[k, 5] = out[k, 3] + a0, out[k, 4] + a1, out[k, 5] + a2


@njit(cache=True, nogil=True, inline="always")
def _motion(k, p, kind, ax, w, dw, R, T, vel, acc):  # pragma: no cover - compiled
    """Joint k's velocity vel[k] and acceleration with gravity acc[k] (its parent's at row p; the universe's
    row: no velocity) as RneaForwardStep: v = S w (+ the parent's); a = v × S w + S dw + the parent's."""
    n = len(vel) - 1
    for i in range(6):
        vel[k, i] = 0.0
        acc[k, i] = 0.0
    j = 3 * (1 - kind) + ax        # (the entry of S: angular for a revolute joint, linear for a prismatic one)
    vel[k, j] = w
    if p != n:
        _add_act_inv(R, T, k, vel, p, vel)
    b, d, s = _NEXT[ax], _NEXT[ax + 1], -w   # (v ^ S w: pinocchio's alphaCross(−w, ·) per part)
    if kind == 0:
        acc[k, b], acc[k, d] = -s * vel[k, d], s * vel[k, b]
        acc[k, b + 3], acc[k, d + 3] = -s * vel[k, d + 3], s * vel[k, b + 3]
    else:           # (a prismatic joint's term is linear, of the angular velocity)
        acc[k, b], acc[k, d] = -s * vel[k, d + 3], s * vel[k, b + 3]
    acc[k, j] = acc[k, j] + dw
    _add_act_inv(R, T, k, acc, p, acc)


@njit(cache=True, nogil=True, inline="always")
def _force(k, vel, acc, f, mass, lever, sym):  # pragma: no cover - compiled
    """f[k] = I a + v ×* (I v) (RneaForwardStep's force)."""
    v0, v1, v2, v3, v4, v5 = vel[k, 0], vel[k, 1], vel[k, 2], vel[k, 3], vel[k, 4], vel[k, 5]
    h0, h1, h2, h3, h4, h5 = _inertia_times(mass[k], lever, sym, k, v0, v1, v2, v3, v4, v5)
    f0, f1, f2, f3, f4, f5 = _inertia_times(mass[k], lever, sym, k, acc[k, 0], acc[k, 1], acc[k, 2], acc[k, 3],
                                            acc[k, 4], acc[k, 5])
    l0, l1, l2 = _cross(v3, v4, v5, h0, h1, h2)
    e0, e1, e2 = _cross(v3, v4, v5, h3, h4, h5)
    g0, g1, g2 = _cross(v0, v1, v2, h0, h1, h2)
    f[k, 0], f[k, 1], f[k, 2] = f0 + l0, f1 + l1, f2 + l2
    f[k, 3], f[k, 4], f[k, 5] = f3 + (e0 + g0), f4 + (e1 + g1), f5 + (e2 + g2)


@njit(cache=True, nogil=True, inline="always")
def _add_act(R, T, k, f, p):  # pragma: no cover - compiled
    """f[p] += the force f[k] of joint k's frame (R[k], T[k]) in its parent's (pinocchio's act): lin Rx.lin,
    ang Rx.ang + T × (Rx.lin)."""
    l0, l1, l2 = _rv(R, k, f[k, 0], f[k, 1], f[k, 2])
    a0, a1, a2 = _rv(R, k, f[k, 3], f[k, 4], f[k, 5])
    e0, e1, e2 = _cross(T[k, 0], T[k, 1], T[k, 2], l0, l1, l2)
    f[p, 0], f[p, 1], f[p, 2] = f[p, 0] + l0, f[p, 1] + l1, f[p, 2] + l2
    f[p, 3], f[p, 4], f[p, 5] = f[p, 3] + (a0 + e0), f[p, 4] + (a1 + e1), f[p, 5] + (a2 + e2)


@njit(cache=True, nogil=True)
def rnea(parent, kind, axis, iq, iv, PR, Pt, mass, lever, sym, arm, grav, Q, V, A):  # pragma: no cover - compiled
    """(N, nv) pinocchio's rnea at every row of Q, V, A (N, nv) for the model :func:`pack` packed (its arrays
    in that order): the forward pass over the joints in order, the backward pass from the last joint on
    (τ = Sᵀf, the parent's f += the child's f acted), then τ += armature · a."""
    n, N, nv = len(parent), Q.shape[0], len(arm)
    R, T = np.empty((n, 3, 3)), np.empty((n, 3))
    vel, acc, f = np.empty((n + 1, 6)), np.empty((n + 1, 6)), np.empty((n, 6))
    for i in range(6):
        acc[n, i] = -grav[i]      # (row n: the universe's; pinocchio's a_gf[0] = −gravity)
    out = np.empty((N, nv))
    for r in range(N):
        for k in range(n):
            p = parent[k] if parent[k] >= 0 else n
            _placement(PR, Pt, k, kind[k], axis[k], Q[r, iq[k]], R, T)
            _motion(k, p, kind[k], axis[k], V[r, iv[k]], A[r, iv[k]], R, T, vel, acc)
            _force(k, vel, acc, f, mass, lever, sym)
        for k in range(n - 1, -1, -1):
            out[r, iv[k]] = 0.0 + f[k, 3 * (1 - kind[k]) + axis[k]]
            if parent[k] >= 0:
                _add_act(R, T, k, f, parent[k])
        for j in range(nv):
            out[r, j] = out[r, j] + arm[j] * A[r, j]
    return out


def _warm() -> None:
    """The kernel called once on a one-joint revolute and prismatic chain (compiles or loads it)."""
    z, P = np.zeros((1, 2)), np.stack([np.eye(3)] * 2)
    rnea(np.array([-1, 0]), np.array([0, 1]), np.array([2, 2]), np.array([0, 1]), np.array([0, 1]), P,
         np.zeros((2, 3)), np.ones(2), np.zeros((2, 3)), np.ones((2, 6)), np.zeros(2), np.zeros(6), z, z, z)


KERNELS = KernelModule("robodesign.model.rnea_kernel", __file__, rnea, ("rnea",), _warm)
available, compiled, warm_up, ready = KERNELS.available, KERNELS.compiled, KERNELS.warm_up, KERNELS.ready
compile_into_cache = KERNELS.compile_into_cache

if __name__ == "__main__":
    sys.exit(KERNELS.main())
