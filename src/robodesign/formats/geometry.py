"""Geometry specs (box, cylinder, sphere, mesh) and their coal collision objects.

A :class:`GeometrySpec` is plain data. :func:`collision_objects` turns it into coal shapes:
primitives map 1:1; an ``.stl`` (or other trimesh-readable) mesh becomes a BVH model (exact);
a ``.wrl`` VRML file — the convex decompositions IMPROV ships — becomes one coal ``Convex`` per
``Shape`` (fast: convex–convex distance is ~10–100× cheaper than mesh–mesh).
Loaded meshes are cached per process by (file, scale, mode).
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import List, Optional, Sequence, Tuple, cast

import numpy as np

from robodesign.core.errors import InputError, PathPart, describe_value
from robodesign.core.jsonio import check_finite, resolve_inside
from robodesign.core.spatial import parse_pose

GEOMETRY_TYPES = ("box", "cylinder", "sphere", "mesh", "empty")
_PARAM_ALIASES = {"radius": "r", "length": "z"}
# parameter names each type reads (others are ignored by the reference: dropped with a warning)
_PARAMETERS = {"box": ("x", "y", "z"), "cylinder": ("r", "radius", "z", "length"), "sphere": ("r",),
               "mesh": ("file", "scale"), "empty": ()}
LFS_POINTER_PREFIX = b"version https://git-lfs"


@dataclass(frozen=True, eq=False)
class GeometrySpec:
    kind: str  # box | cylinder | sphere | mesh
    pose: np.ndarray  # 4x4, relative to the owning frame (body frame; world for obstacles)
    size: Tuple[float, ...] = ()  # box (x,y,z) full lengths; cylinder (r, z) full length; sphere (r,)
    file: Optional[Path] = None  # mesh: absolute, resolved path
    scale: Tuple[float, float, float] = (1.0, 1.0, 1.0)
    ref: Optional[str] = None  # mesh: the path as written in the file (for writing back)

    def to_json(self) -> dict:
        from robodesign.core.spatial import pose_to_list
        params: dict
        if self.kind == "box":
            params = dict(zip("xyz", self.size))
        elif self.kind == "cylinder":
            params = {"r": self.size[0], "z": self.size[1]}
        elif self.kind == "sphere":
            params = {"r": self.size[0]}
        elif self.kind == "mesh":
            params = {"file": self.ref or str(self.file), "scale": list(self.scale)}
        else:
            params = {}
        return {"type": self.kind, "parameters": params, "pose": pose_to_list(self.pose)}


def canonical_geometry_json(value, file: str, path: Sequence[PathPart], warnings):
    """The canonical form of a geometry object (or list of them) as real files write it.

    The type name is matched case-insensitively (the reference accepts ``BOX`` and ``box``); parameters
    the type does not read are dropped and reported once through ``warnings.ignored_key`` (the reference
    ignores them). Anything malformed is returned as it is, for the schema to name.
    """
    if isinstance(value, list):
        return [canonical_geometry_json(g, file, list(path) + [i], warnings) for i, g in enumerate(value)]
    if not isinstance(value, dict):
        return value
    out = dict(value)
    kind = out.get("type")
    if isinstance(kind, str) and kind.lower() in GEOMETRY_TYPES:
        kind = out["type"] = kind.lower()
    params = out.get("parameters")
    if isinstance(kind, str) and kind in _PARAMETERS and isinstance(params, dict):
        known = _PARAMETERS[kind]
        for k in params:
            if k not in known:
                warnings.ignored_key(file, list(path) + ["parameters"], k, known)
        out["parameters"] = {k: v for k, v in params.items() if k in known}
    return out


def parse_geometries(value, root: Optional[Path], file: str, path: Sequence[PathPart],
                     required_files: bool = True, warnings=None) -> Tuple[GeometrySpec, ...]:
    """Parse one geometry object or a list of them. ``root`` is the folder mesh paths are relative to.

    A collision mesh (``required_files``) that is missing, empty, a Git LFS pointer, unreadable or
    degenerate raises :class:`InputError` naming the file and field. A visual mesh that is missing,
    empty or an LFS pointer is dropped with a message in ``warnings`` (an :class:`InputWarnings`).
    """
    path = list(path)
    if value is None:
        return ()
    items = value if isinstance(value, list) else [value]
    out = []
    for i, g in enumerate(items):
        p = path + [i] if isinstance(value, list) else path
        spec = parse_geometry(g, root, file, p, required_files, warnings)
        if spec is not None:
            out.append(spec)
    return tuple(out)


def parse_geometry(g, root, file, path, required_files=True, warnings=None) -> Optional[GeometrySpec]:
    path = list(path)
    if not isinstance(g, dict):
        raise InputError(f"expected a geometry object, got {describe_value(g)}", file=file, path=path)
    kind = g.get("type")
    if kind not in GEOMETRY_TYPES:
        raise InputError(f"unknown geometry type {describe_value(kind)} (expected one of {', '.join(GEOMETRY_TYPES)})",
                         file=file, path=path + ["type"])
    pose = parse_pose(g["pose"], file, path + ["pose"]) if "pose" in g else np.eye(4)
    params = g.get("parameters", {}) or {}
    if not isinstance(params, dict):
        raise InputError("expected an object", file=file, path=path + ["parameters"])
    params = {_PARAM_ALIASES.get(k, k): v for k, v in params.items()}
    pp = path + ["parameters"]

    def num(key, positive=True):
        if key not in params:
            raise InputError(f"missing parameter {key!r} for a {kind}", file=file, path=pp)
        v = check_finite(params[key], file, pp + [key])
        if positive and v <= 0:
            raise InputError(f"must be positive, got {v}", file=file, path=pp + [key])
        return v

    if kind == "empty":
        return None
    if kind == "box":
        return GeometrySpec("box", pose, (num("x"), num("y"), num("z")))
    if kind == "cylinder":
        return GeometrySpec("cylinder", pose, (num("r"), num("z")))
    if kind == "sphere":
        return GeometrySpec("sphere", pose, (num("r"),))
    # mesh
    if "file" not in params:
        raise InputError("missing parameter 'file' for a mesh", file=file, path=pp)
    ref = params["file"]
    if root is None:
        raise InputError("mesh files need a folder to resolve against", file=file, path=pp + ["file"])
    target = resolve_inside(root, ref, file, pp + ["file"])
    scale = params.get("scale", 1.0)
    if isinstance(scale, list):
        if len(scale) != 3:
            raise InputError(f"scale must be a number or 3 numbers, got {describe_value(scale)}", file=file,
                             path=pp + ["scale"])
        sx, sy, sz = (check_finite(s, file, pp + ["scale", i]) for i, s in enumerate(scale))
        sc = (sx, sy, sz)
    else:
        s = check_finite(scale, file, pp + ["scale"])
        sc = (s, s, s)
    if any(s <= 0 for s in sc):
        raise InputError(f"scale must be positive, got {list(sc)}", file=file, path=pp + ["scale"])
    problem: Optional[str]
    if not target.is_file():
        problem = f"mesh file not found: {ref!r} (looked at {target})"
    else:
        problem = mesh_problem(target, sc, full=required_files)
        problem = problem and f"{'collision' if required_files else 'visual'} mesh file {ref!r} {problem}"
    if problem:
        if required_files:
            raise InputError(problem, file=file, path=pp + ["file"])
        if warnings is not None:
            warnings.add(file, pp + ["file"], f"{problem}; the visual is skipped")
        return None
    return GeometrySpec("mesh", pose, (), target, sc, ref)


def mesh_problem(file: Path, scale: Tuple[float, float, float], full: bool = True) -> Optional[str]:
    """Why a mesh file cannot serve as geometry (None if it can).

    Always checked: empty file, a Git LFS pointer left in place of the mesh. With ``full`` (collision
    geometry) the mesh is read: unreadable, no triangles, non-finite vertices, or zero surface area
    (all triangles degenerate) are problems too — an obstacle that silently disappears would make the
    checker certify collisions.
    """
    try:
        with open(file, "rb") as fh:
            head = fh.read(len(LFS_POINTER_PREFIX))
    except OSError as e:
        return f"cannot be read ({e.strerror or e})"
    if not head:
        return "is empty (0 bytes)"
    if head == LFS_POINTER_PREFIX:
        return "is a Git LFS pointer, not the mesh (fetch it with `git lfs pull`)"
    if not full:
        return None
    try:
        parts = load_mesh_arrays(str(file), tuple(scale))
    except Exception as e:  # any reader error means: not a usable mesh
        return f"cannot be read as a mesh ({type(e).__name__}: {str(e)[:120]})"
    area = 0.0
    for verts, tris in parts:
        if len(verts) and not np.all(np.isfinite(verts)):
            return "has non-finite vertex coordinates"
        if len(tris):
            if tris.min() < 0 or tris.max() >= len(verts):
                return "has triangles that index missing vertices"
            a, b, c = verts[tris[:, 0]], verts[tris[:, 1]], verts[tris[:, 2]]
            area += 0.5 * float(np.linalg.norm(np.cross(b - a, c - a), axis=1).sum())
    if not any(len(t) for _, t in parts):
        return "has no triangles (truncated or not a mesh?)"
    if area <= 1e-12:
        return "is degenerate (all triangles have zero area)"
    return None


# ---------------------------------------------------------------------------------------------
# Mesh loading
# ---------------------------------------------------------------------------------------------

_WRL_SHAPE = re.compile(r"point\s*\[(.*?)\]", re.S)
_WRL_INDEX = re.compile(r"coordIndex\s*\[(.*?)\]", re.S)


def read_wrl_parts(path: Path) -> List[Tuple[np.ndarray, np.ndarray]]:
    """Parse a VRML 2 file of IndexedFaceSet shapes into [(vertices (n,3), triangles (m,3))]."""
    text = path.read_text(errors="replace")
    parts = []
    for chunk in text.split("Shape")[1:]:
        pm = _WRL_SHAPE.search(chunk)
        im = _WRL_INDEX.search(chunk)
        if not pm:
            continue
        nums = np.array([float(x) for x in re.split(r"[\s,]+", pm.group(1).strip()) if x], dtype=float)
        verts = nums.reshape(-1, 3)
        tris = []
        if im:
            idx = [int(x) for x in re.split(r"[\s,]+", im.group(1).strip()) if x]
            face: list = []
            for k in idx:
                if k < 0:
                    for j in range(1, len(face) - 1):  # fan triangulation
                        tris.append((face[0], face[j], face[j + 1]))
                    face = []
                else:
                    face.append(k)
        parts.append((verts, np.array(tris, dtype=np.int64).reshape(-1, 3)))
    return parts


@lru_cache(maxsize=256)
def load_mesh_arrays(file: str, scale: Tuple[float, float, float]) -> List[Tuple[np.ndarray, np.ndarray]]:
    """Vertices and triangles of a mesh file, scaled. ``.wrl`` gives one entry per convex part."""
    p = Path(file)
    if p.suffix.lower() == ".wrl":
        parts = read_wrl_parts(p)
    elif p.suffix.lower() == ".stl" and (stl := read_stl(p)) is not None:
        parts = [stl]
    else:
        import trimesh
        m = cast(trimesh.Trimesh, trimesh.load(str(p), force="mesh", process=False))  # force="mesh": one Trimesh
        parts = [(np.asarray(m.vertices, dtype=float), np.asarray(m.faces, dtype=np.int64))]
    s = np.asarray(scale, dtype=float)
    return [(v * s, f) for v, f in parts]


def _binary_stl_triangles(path: Path) -> Optional[int]:
    """Triangle count of a binary STL whose size matches its header (None: ASCII, truncated or other)."""
    size = path.stat().st_size
    if size < 84:
        return None
    with open(path, "rb") as fh:
        fh.seek(80)
        n = int(np.frombuffer(fh.read(4), dtype="<u4")[0])
    return n if size == 84 + 50 * n else None


_STL_VERTEX = re.compile(rb"vertex\s+(\S+)\s+(\S+)\s+(\S+)")


def read_stl(path: Path) -> Optional[Tuple[np.ndarray, np.ndarray]]:
    """Vertices (one per triangle corner, as trimesh reads them unprocessed) and triangles of a binary or
    ASCII STL, read with numpy (no trimesh import); None if the file is neither (the caller falls back)."""
    if _binary_stl_triangles(path) is not None:
        rec = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
        verts = np.fromfile(path, dtype=rec, offset=84)["v"].reshape(-1, 3).astype(float)
    else:
        text = path.read_bytes()
        if not text.lstrip().startswith(b"solid"):
            return None
        try:
            verts = np.array(_STL_VERTEX.findall(text), dtype=float).reshape(-1, 3)
        except ValueError:
            return None
        if len(verts) % 3 or len(verts) != 3 * text.count(b"endfacet"):
            return None
    return verts, np.arange(len(verts), dtype=np.int64).reshape(-1, 3)


def _vec3s(points: np.ndarray):
    import coal
    v = coal.StdVec_Vec3s()
    for pt in points:
        v.append(np.asarray(pt, dtype=float))
    return v


@lru_cache(maxsize=256)
def _mesh_shapes(file: str, scale: Tuple[float, float, float], convex: bool):
    import coal
    shapes = []
    parts = load_mesh_arrays(file, scale)
    is_decomposition = Path(file).suffix.lower() == ".wrl"
    for verts, tris in parts:
        if len(verts) < 4:
            continue
        if is_decomposition or convex:
            shapes.append(coal.Convex.convexHull(_vec3s(verts), True, "Qt"))
        else:
            bvh = coal.BVHModelOBBRSS()
            bvh.beginModel(len(tris), len(verts))
            bvh.addVertices(np.ascontiguousarray(verts, dtype=float))
            bvh.addTriangles(np.ascontiguousarray(tris, dtype=np.int64))
            bvh.endModel()
            shapes.append(bvh)
    return tuple(shapes)


def coal_shapes(spec: GeometrySpec, convex_meshes: bool = False) -> Tuple[object, ...]:
    """coal collision geometries of one spec (a mesh may give several convex parts).

    Shapes are shared between robots (cached); coal objects are not mutated after creation.
    ``convex_meshes`` replaces a triangle mesh by its convex hull (conservative, much faster).
    """
    import coal
    if spec.kind == "box":
        return (coal.Box(*spec.size),)
    if spec.kind == "cylinder":
        return (coal.Cylinder(spec.size[0], spec.size[1]),)
    if spec.kind == "sphere":
        return (coal.Sphere(spec.size[0]),)
    if spec.kind == "mesh":
        return _mesh_shapes(str(spec.file), tuple(spec.scale), convex_meshes)
    return ()


def contains_point(spec: GeometrySpec, point) -> bool:
    """Whether a world point lies inside (or on) the geometry; meshes by their generalized winding number
    (exact for closed meshes, a sensible inside/outside for small holes)."""
    local = np.linalg.solve(spec.pose, np.append(np.asarray(point, dtype=float), 1.0))[:3]
    if spec.kind == "box":
        return bool(np.all(np.abs(local) <= 0.5 * np.asarray(spec.size) + 1e-12))
    if spec.kind == "cylinder":
        r, half = spec.size[0], 0.5 * spec.size[1]
        return bool(np.hypot(local[0], local[1]) <= r + 1e-12 and abs(local[2]) <= half + 1e-12)
    if spec.kind == "sphere":
        return bool(np.linalg.norm(local) <= spec.size[0] + 1e-12)
    if spec.kind == "mesh":
        return any(abs(_winding_number(v, f, local)) > 0.5
                   for v, f in load_mesh_arrays(str(spec.file), tuple(spec.scale)) if len(f))
    return False


def center_point(spec: GeometrySpec) -> np.ndarray:
    """World position of the geometry's centre (a mesh: the mean of its vertices)."""
    if spec.kind == "mesh":
        vs = [v for v, _ in load_mesh_arrays(str(spec.file), tuple(spec.scale)) if len(v)]
        if vs:
            return (spec.pose @ np.append(np.vstack(vs).mean(axis=0), 1.0))[:3]
    return np.asarray(spec.pose[:3, 3], dtype=float)


def _winding_number(verts: np.ndarray, tris: np.ndarray, p: np.ndarray) -> float:
    """Σ solid angles of the triangles seen from p / 4π (Van Oosterom & Strackee)."""
    a, b, c = (verts[tris[:, i]] - p for i in range(3))
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    num = np.einsum("ij,ij->i", a, np.cross(b, c))
    den = (la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", a, c) * lb
           + np.einsum("ij,ij->i", b, c) * la)
    return float(2.0 * np.arctan2(num, den).sum() / (4.0 * np.pi))
