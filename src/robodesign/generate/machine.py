"""Machine meshes for the machine-tending family: where a mesh's work area is, and the default machine (a
box-built CNC housing written as a binary STL by the generator itself).

The work area is the free space inside the machine that a robot standing in front can reach straight in:
on a grid (``STEP``) of the mesh's bounding box at working height (``WORK_Z`` above its lowest point), a point
belongs to it when

* a horizontal probe ray from the front face of the box (the side towards the robot) reaches it without
  crossing a triangle (line of sight from the front), and
* the mesh is both above it (within ``COVER_UP``: roof, spindle, housing) and below it (within
  ``COVER_DOWN``: table, bed) — this is what tells the inside of a machine from the open air in front of it.

The side of the box with the most work-area points faces the robot (the mesh is turned by a multiple of
90°). The test is a pure function of the mesh's vertices (own vectorised ray-triangle tests), so it is
deterministic.
"""
from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from functools import lru_cache
from typing import List, Optional, Tuple

import numpy as np

from robodesign.formats.geometry import load_mesh_arrays

STEP = 0.1  # m, grid of the probes
WORK_Z = (0.6, 1.6)  # m above the machine's floor
COVER_UP = 1.5  # m: mesh above a work-area point within this height
COVER_DOWN = 1.0  # m: mesh below it within this depth
MARGIN = 0.05  # m: a work-area point stays this far in front of the first triangle along its probe ray


@dataclass(frozen=True)
class MachineFrame:
    """How the mesh is placed: turned by ``yaw`` (a multiple of π/2) so that its work area faces -x, then
    shifted so that its lowest point is on the floor and its bounding box's front face at x = 0. ``points``
    are the work-area points in that frame (x behind the front face, y, z above the floor)."""
    yaw: float
    shift: Tuple[float, float, float]
    size: Tuple[float, float, float]  # bounding-box extents after the yaw
    points: Tuple[Tuple[float, float, float], ...]

    def matrix(self) -> np.ndarray:
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        T = np.eye(4)
        T[:3, :3] = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
        T[:3, 3] = self.shift
        return T


def _ray_depths(V: np.ndarray, F: np.ndarray, origins: np.ndarray) -> np.ndarray:
    """Distance along +x from each origin to the first triangle (inf if none): Möller–Trumbore, vectorised."""
    A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    e1, e2 = B - A, C - A
    d = np.array([1.0, 0.0, 0.0])
    pvec = np.cross(d, e2)  # (m, 3)
    det = np.einsum("ij,ij->i", e1, pvec)
    ok = np.abs(det) > 1e-12
    A, e1, e2, pvec, det = A[ok], e1[ok], e2[ok], pvec[ok], det[ok]
    inv = 1.0 / det
    out = np.full(len(origins), np.inf)
    for k0 in range(0, len(origins), 256):
        O = origins[k0:k0 + 256]
        tvec = O[:, None, :] - A[None, :, :]
        u = np.einsum("rij,ij->ri", tvec, pvec) * inv
        qvec = np.cross(tvec, e1[None, :, :])
        v = qvec[..., 0] * inv  # q · d with d = +x
        t = np.einsum("rij,ij->ri", qvec, e2) * inv
        hit = (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-9)
        t = np.where(hit, t, np.inf)
        out[k0:k0 + 256] = t.min(axis=1)
    return out


def _covered(V: np.ndarray, F: np.ndarray, xy: np.ndarray, zs: np.ndarray) -> np.ndarray:
    """(len(xy), len(zs)) booleans: the vertical line through xy[i] meets the mesh within COVER_UP above zs[j]
    and within COVER_DOWN below it (2-D barycentric test of the triangles' footprints)."""
    A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    e1, e2 = (B - A)[:, :2], (C - A)[:, :2]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    ok = np.abs(det) > 1e-12
    A, B, C, e1, e2, det = A[ok], B[ok], C[ok], e1[ok], e2[ok], det[ok]
    out = np.zeros((len(xy), len(zs)), dtype=bool)
    for k0 in range(0, len(xy), 256):
        P = xy[k0:k0 + 256, None, :] - A[None, :, :2]
        u = (P[..., 0] * e2[:, 1] - P[..., 1] * e2[:, 0]) / det
        v = (e1[:, 0] * P[..., 1] - e1[:, 1] * P[..., 0]) / det
        inside = (u >= 0) & (v >= 0) & (u + v <= 1)
        z = A[:, 2] + u * (B[:, 2] - A[:, 2]) + v * (C[:, 2] - A[:, 2])
        z = np.where(inside, z, np.nan)[:, :, None]  # (c, m, 1)
        dz = z - zs[None, None, :]
        with np.errstate(invalid="ignore"):
            up = np.any((dz > 0) & (dz <= COVER_UP), axis=1)
            down = np.any((dz < 0) & (dz >= -COVER_DOWN), axis=1)
        out[k0:k0 + 256] = up & down
    return out


def _rotz(V: np.ndarray, yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return V @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T


@lru_cache(maxsize=16)
def analyse(file: str, scale: float) -> MachineFrame:
    """Place the machine mesh (file, uniform scale) with its work area towards the robot (-x side)."""
    parts = load_mesh_arrays(file, (scale, scale, scale))
    V0 = np.concatenate([v for v, _ in parts])
    offs = np.cumsum([0] + [len(v) for v, _ in parts[:-1]])
    F = np.concatenate([f + o for (_, f), o in zip(parts, offs)])
    best: Optional[MachineFrame] = None
    for quarter in range(4):
        yaw = quarter * math.pi / 2
        V = _rotz(V0, yaw)
        lo, hi = V.min(axis=0), V.max(axis=0)
        ys = np.arange(lo[1] + STEP / 2, hi[1], STEP)
        zs = lo[2] + np.arange(WORK_Z[0], min(WORK_Z[1], hi[2] - lo[2]) + 1e-9, STEP)
        xs = lo[0] + np.arange(STEP / 2, hi[0] - lo[0], STEP)
        Y, Z = np.meshgrid(ys, zs, indexing="ij")
        O = np.stack([np.full(Y.size, lo[0] - 0.01), Y.ravel(), Z.ravel()], axis=1)
        depth = (_ray_depths(V, F, O) - 0.01).reshape(Y.shape)  # (ny, nz), from the front face
        X2, Y2 = np.meshgrid(xs, ys, indexing="ij")
        cov = _covered(V, F, np.stack([X2.ravel(), Y2.ravel()], axis=1), zs).reshape(len(xs), len(ys), len(zs))
        sight = (xs - lo[0])[:, None, None] <= depth[None, :, :] - MARGIN
        ix, iy, iz = np.nonzero(cov & sight)
        pts = tuple((float(xs[a] - lo[0]), float(ys[b]), float(zs[c] - lo[2])) for a, b, c in zip(ix, iy, iz))
        if best is None or len(pts) > len(best.points):
            size = hi - lo
            best = MachineFrame(yaw, (float(-lo[0]), 0.0, float(-lo[2])),
                                (float(size[0]), float(size[1]), float(size[2])), pts)
    assert best is not None  # the first orientation always sets it
    return best


# ---------------------------------------------------------------------------------------------------------
# the default machine: a CNC housing with a front door opening, built from boxes
DEFAULT_NAME = "robodesign_cnc_box.stl"
_BOXES = (  # (lo, hi) in metres; front face at x = 0, door opening y ∈ [-0.45, 0.45], z ∈ [0.85, 1.55]
    ((0.00, -0.90, 0.00), (1.60, 0.90, 0.85)),  # base and machine bed (work table at z = 0.85)
    ((1.50, -0.90, 0.85), (1.60, 0.90, 2.10)),  # back wall
    ((0.00, -0.90, 0.85), (1.60, -0.80, 2.10)),  # side walls
    ((0.00, 0.80, 0.85), (1.60, 0.90, 2.10)),
    ((0.00, -0.90, 2.00), (1.60, 0.90, 2.10)),  # roof
    ((0.00, -0.80, 0.85), (0.05, -0.45, 2.00)),  # front: jambs and lintel around the door
    ((0.00, 0.45, 0.85), (0.05, 0.80, 2.00)),
    ((0.00, -0.45, 1.55), (0.05, 0.45, 2.00)),
    ((1.05, -0.30, 1.40), (1.35, 0.30, 2.00)),  # spindle head
    ((0.55, -0.12, 0.85), (0.75, 0.12, 0.95)),  # vise on the table
)


def _box_triangles(lo, hi) -> List[np.ndarray]:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    c = np.array([[lo[0] if i & 1 == 0 else hi[0], lo[1] if i & 2 == 0 else hi[1], lo[2] if i & 4 == 0 else hi[2]]
                  for i in range(8)])
    quads = ((0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5))  # outward
    tris = []
    for a, b, cc, d in quads:
        tris.append(c[[a, b, cc]])
        tris.append(c[[a, cc, d]])
    return tris


def default_machine_stl() -> bytes:
    """The default machine as a binary STL (fixed header, so the bytes never change)."""
    tris = [t for lo, hi in _BOXES for t in _box_triangles(lo, hi)]
    out = [b"robodesign default CNC machine (boxes), metres".ljust(80, b" "), struct.pack("<I", len(tris))]
    for t in tris:
        n = np.cross(t[1] - t[0], t[2] - t[0])
        n = n / np.linalg.norm(n)
        out.append(struct.pack("<12fH", *n, *t.ravel(), 0))
    return b"".join(out)
