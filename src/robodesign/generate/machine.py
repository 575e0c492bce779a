"""Machine meshes for the machine-tending family: where a mesh's door opening is, and the default
machine (a box-built CNC housing written as a binary STL by the generator itself).

The opening is found by casting horizontal rays at working height (0.6–1.6 m above the machine's
lowest point) into each of the four sides of the machine's bounding box: the side whose rays go deepest
before they hit a triangle faces the robot. Rays that leave the box without a hit (a hole in an open
mesh) are ignored. Everything is a pure function of the mesh's vertices, so it is deterministic.
"""
from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from functools import lru_cache
from typing import List, Tuple

import numpy as np

RAY_STEP = 0.05  # m, grid of the ray probes
RAY_Z = (0.6, 1.6)  # m above the machine's floor
DEEP = 0.35  # m: a ray that goes this far inside counts for the opening


@dataclass(frozen=True)
class MachineFrame:
    """How the mesh is placed: yaw (multiple of π/2) turning its open side to -x, then a shift putting its
    lowest point on the floor and its front face at x = 0; ``rays`` are the probes into the opening in
    that frame: (y, z, depth) with depth the free distance behind the front face."""
    yaw: float
    shift: Tuple[float, float, float]
    size: Tuple[float, float, float]  # bounding-box extents after the yaw
    rays: Tuple[Tuple[float, float, float], ...]

    def matrix(self) -> np.ndarray:
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        T = np.eye(4)
        T[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
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


def _rotz(V: np.ndarray, yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return V @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T


@lru_cache(maxsize=16)
def analyse(file: str, scale: float) -> MachineFrame:
    """Place the machine mesh (file, uniform scale) with its deepest opening towards the robot (-x side)."""
    from ..geometry import load_mesh_arrays
    parts = load_mesh_arrays(file, (scale, scale, scale))
    V0 = np.concatenate([v for v, _ in parts])
    offs = np.cumsum([0] + [len(v) for v, _ in parts[:-1]])
    F = np.concatenate([f + o for (_, f), o in zip(parts, offs)])
    best = None
    for quarter in range(4):
        yaw = quarter * math.pi / 2
        V = _rotz(V0, yaw)
        lo, hi = V.min(axis=0), V.max(axis=0)
        ys = np.arange(lo[1] + RAY_STEP, hi[1] - RAY_STEP / 2, RAY_STEP)
        zs = lo[2] + np.arange(RAY_Z[0], min(RAY_Z[1], hi[2] - lo[2]) + 1e-9, RAY_STEP)
        Y, Z = np.meshgrid(ys, zs, indexing="ij")
        O = np.stack([np.full(Y.size, lo[0] - 0.01), Y.ravel(), Z.ravel()], axis=1)
        depth = _ray_depths(V, F, O) - 0.01
        keep = np.isfinite(depth)
        score = int(np.sum(depth[keep] >= DEEP))
        if best is None or score > best[0]:
            shift = (-lo[0], 0.0, -lo[2])
            rays = tuple((float(y), float(z - lo[2]), float(d)) for y, z, d in zip(O[keep, 1], O[keep, 2], depth[keep]))
            best = (score, MachineFrame(yaw, shift, tuple(float(x) for x in hi - lo), rays))
    return best[1]


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
