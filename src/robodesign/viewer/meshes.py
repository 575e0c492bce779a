"""Mesh data for the viewer: welded, decimated triangle meshes encoded as base64 arrays.

A mesh file (STL, OBJ, … or an IMPROV ``.wrl`` convex decomposition) is loaded once per
``(file, scale)`` with :func:`robodesign.formats.geometry.load_mesh_arrays`, its duplicate vertices are
welded (STL stores three per triangle), degenerate triangles are dropped and, if it still has more
than ``max_triangles`` triangles, it is decimated by vertex clustering (numpy only): vertices are
snapped to a cubic grid, each occupied cell becomes one vertex (the mean of its vertices) and
triangles that collapse are removed. The grid is the finest (found by bisection) that gives at most
``max_triangles`` triangles.

Encoding: vertices as little-endian float32 ``x, y, z`` triples, indices as little-endian uint16
(fewer than 65 536 vertices) or uint32, both base64 (see :func:`encode_mesh`).
"""
from __future__ import annotations

import base64
from functools import lru_cache
from pathlib import Path
from typing import Dict, Tuple

import numpy as np

from robodesign.formats.geometry import load_mesh_arrays

MAX_TRIANGLES = 20_000


def weld(vertices: np.ndarray, triangles: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Merge exactly equal vertices; drop degenerate and unused data."""
    v = np.asarray(vertices, dtype=float).reshape(-1, 3)
    f = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if len(v) == 0 or len(f) == 0:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    uniq, inverse = np.unique(v, axis=0, return_inverse=True)
    f = inverse.reshape(-1)[f]
    return _compact(uniq, _drop_degenerate(f))


def _drop_degenerate(f: np.ndarray) -> np.ndarray:
    keep = (f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])
    return f[keep]


def _compact(v: np.ndarray, f: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    used = np.unique(f)
    remap = np.full(len(v), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return v[used], remap[f]


def cluster_vertices(vertices: np.ndarray, triangles: np.ndarray, cell: float) -> Tuple[np.ndarray, np.ndarray]:
    """Vertex-clustering decimation on a cubic grid of edge ``cell`` (one vertex per occupied cell)."""
    v = np.asarray(vertices, dtype=float)
    f = np.asarray(triangles, dtype=np.int64)
    keys = np.floor((v - v.min(axis=0)) / cell).astype(np.int64)
    _, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.reshape(-1)
    sums = np.zeros((len(counts), 3))
    np.add.at(sums, inverse, v)
    centers = sums / counts[:, None]
    f = _drop_degenerate(inverse[f])
    if len(f):
        # one copy of each triangle (ignoring orientation of equal vertex sets is not done on purpose:
        # two faces with opposite winding are kept, they show both sides)
        f = np.unique(f, axis=0)
    return _compact(centers, f)


def decimate(vertices: np.ndarray, triangles: np.ndarray, max_triangles: int = MAX_TRIANGLES,
             iterations: int = 18) -> Tuple[np.ndarray, np.ndarray]:
    """At most ``max_triangles`` triangles by vertex clustering on the finest sufficient grid."""
    v, f = np.asarray(vertices, dtype=float), np.asarray(triangles, dtype=np.int64)
    if len(f) <= max_triangles:
        return v, f
    diag = float(np.linalg.norm(v.max(axis=0) - v.min(axis=0))) or 1.0
    lo, hi = diag * 1e-6, diag  # lo: (assumed) too fine, hi: coarse enough
    best = cluster_vertices(v, f, hi)
    for _ in range(iterations):
        mid = np.sqrt(lo * hi)
        cand = cluster_vertices(v, f, mid)
        if len(cand[1]) <= max_triangles:
            hi, best = mid, cand
        else:
            lo = mid
        if hi / lo < 1.02:
            break
    return best


def b64(array: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(array).tobytes()).decode("ascii")


def decode_b64(text: str, dtype) -> np.ndarray:
    return np.frombuffer(base64.b64decode(text), dtype=np.dtype(dtype).newbyteorder("<"))


def encode_mesh(vertices: np.ndarray, triangles: np.ndarray) -> Dict[str, object]:
    v = np.asarray(vertices, dtype="<f4").reshape(-1, 3)
    idx_type = "uint16" if len(v) < 65536 else "uint32"
    idx = np.asarray(triangles).reshape(-1).astype("<u2" if idx_type == "uint16" else "<u4")
    return {"vertices": b64(v), "indices": b64(idx), "index_type": idx_type,
            "n_vertices": int(len(v)), "n_triangles": int(len(idx) // 3)}


@lru_cache(maxsize=128)
def mesh_entry(file: str, scale: Tuple[float, float, float], max_triangles: int = MAX_TRIANGLES) -> Dict[str, object]:
    """The viewer's record of one mesh file: encoded arrays plus provenance (cached per process)."""
    parts = load_mesh_arrays(str(file), tuple(float(s) for s in scale))
    vs, fs, off = [], [], 0
    for v, f in parts:
        vs.append(np.asarray(v, float).reshape(-1, 3))
        fs.append(np.asarray(f, np.int64).reshape(-1, 3) + off)
        off += len(vs[-1])
    v = np.concatenate(vs) if vs else np.zeros((0, 3))
    f = np.concatenate(fs) if fs else np.zeros((0, 3), dtype=np.int64)
    n_orig = int(len(f))
    v, f = weld(v, f)
    v2, f2 = decimate(v, f, max_triangles)
    entry = encode_mesh(v2, f2)
    entry.update({"name": Path(file).name, "source_triangles": n_orig, "decimated": bool(len(f2) < len(f)),
                  "bbox": [v2.min(axis=0).tolist(), v2.max(axis=0).tolist()] if len(v2) else [[0, 0, 0], [0, 0, 0]]})
    return entry
