"""Small helpers for homogeneous transforms (4x4 numpy arrays)."""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np
import numpy.typing as npt

from robodesign.core.errors import InputError, PathPart, describe_value

# Mating two connectors: A→B is a rotation of π about x (x-axes aligned, z-axes anti-parallel).
RX_PI = np.array([[1.0, 0, 0, 0], [0, -1.0, 0, 0], [0, 0, -1.0, 0], [0, 0, 0, 1.0]])


def rot_x(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]], dtype=float)


def rot_y(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]], dtype=float)


def rot_z(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], dtype=float)


def homogeneous(R: np.ndarray | None = None, p: npt.ArrayLike | None = None) -> np.ndarray:
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    if p is not None:
        T[:3, 3] = p
    return T


def translation(x: float, y: float, z: float) -> np.ndarray:
    return homogeneous(None, (x, y, z))


def inv(T: np.ndarray) -> np.ndarray:
    R = T[:3, :3]
    out = np.eye(4)
    out[:3, :3] = R.T
    out[:3, 3] = -R.T @ T[:3, 3]
    return out


def parse_pose(value, file: str | None, path: Sequence[PathPart], rot_tol: float = 1e-5) -> np.ndarray:
    """A CoBRA pose: row-major 4x4 list, or a list of 4x4 matrices multiplied left to right.

    The rotation block must be orthonormal with det +1 (to ``rot_tol``) and the last row
    ``[0,0,0,1]``; it is re-orthonormalised so that downstream code sees an exact rotation.
    """
    path = list(path)
    arr = _as_matrix_stack(value, file, path)
    T = np.eye(4)
    for M in arr:
        T = T @ M
    R = T[:3, :3]
    if not np.all(np.isfinite(T)):
        raise InputError("pose contains a non-finite number", file=file, path=path)
    if np.abs(T[3] - np.array([0, 0, 0, 1.0])).max() > 1e-9:
        raise InputError(f"last row of a pose must be [0, 0, 0, 1], got {T[3].tolist()}", file=file, path=path)
    err = np.abs(R @ R.T - np.eye(3)).max()
    if err > rot_tol or np.linalg.det(R) < 0:
        raise InputError(f"rotation part is not a proper rotation matrix (orthonormality error {err:.2g})",
                         file=file, path=path)
    U, _, Vt = np.linalg.svd(R)
    T[:3, :3] = U @ Vt
    return T


def _as_matrix_stack(value, file, path):
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"expected a 4x4 matrix (list of 4 rows of 4 numbers), got {describe_value(value)}",
                         file=file, path=path) from None
    if a.shape == (4, 4):
        return [a]
    if a.ndim == 3 and a.shape[1:] == (4, 4) and a.shape[0] >= 1:
        return list(a)
    raise InputError(f"expected a 4x4 matrix (list of 4 rows of 4 numbers), got shape {a.shape}",
                     file=file, path=path)


def pose_to_list(T: np.ndarray, decimals: int = 12) -> list:
    return [[float(round(x, decimals)) + 0.0 for x in row] for row in np.asarray(T)]


def log3(R: np.ndarray) -> np.ndarray:
    """Rotation vector n·θ with θ in [0, π]."""
    import pinocchio as pin
    return np.asarray(pin.log3(np.asarray(R, dtype=float)))


def rpy_to_matrix(r: float, p: float, y: float) -> np.ndarray:
    """R = Rz(y)·Ry(p)·Rx(r): the roll-pitch-yaw convention of URDF and CoBRA, the only one in robodesign."""
    return rot_z(y) @ rot_y(p) @ rot_x(r)


def matrix_to_rpy(R: np.ndarray) -> tuple[float, float, float]:
    """(roll, pitch, yaw) with R = Rz(yaw)·Ry(pitch)·Rx(roll) (the inverse of :func:`rpy_to_matrix`); pitch in
    [−π/2, π/2]. At gimbal lock (pitch = ±π/2, only roll ∓ yaw is defined) roll = 0 and yaw carries the angle."""
    R = np.asarray(R, dtype=float)
    c = math.hypot(R[0, 0], R[1, 0])
    pitch = math.atan2(-R[2, 0], c)
    if c < 1e-10:
        return 0.0, pitch, math.atan2(-R[0, 1], R[1, 1])
    return math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0])
