"""Safe handling of uploaded files: names, mesh references, zip archives, writes into the data folder.

Rules (docs/website.md, "Safety"):

* A stored file name is a relative path whose segments match :data:`SAFE_SEGMENT` (letters, digits,
  ``_ - . + ( )`` and spaces, not starting with ``.``); anything else is never written.
* Mesh references of a task / module set are resolved with
  ``resolve_inside(root, ref, ..., follow_symlinks=True)`` (plus the lexical check), must name a safe path
  with an allowed mesh extension, and only the referenced files are stored.
* A zip entry that is absolute, has a drive letter, contains ``..``, is a symbolic link or is encrypted
  rejects the whole upload; harmless but odd entries (``.DS_Store``, ``__MACOSX/...``) are ignored. The
  declared uncompressed total and the bytes actually inflated are both capped (zip bombs).
* Files are created with ``O_EXCL | O_NOFOLLOW`` below a folder that is checked to resolve inside the data
  folder.
"""
from __future__ import annotations

import io
import os
import re
import stat
import zipfile
from pathlib import Path, PurePosixPath
from typing import Dict, Iterator, List, Optional, Sequence, Tuple

from robodesign.core.errors import InputError, PathPart
from robodesign.core.jsonio import resolve_inside

SAFE_SEGMENT = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.+() \-]{0,199}$")
MESH_EXTENSIONS = (".stl", ".obj", ".ply", ".off", ".glb", ".dae", ".wrl")
NAME_RE = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.\-]{0,99}$")  # module set names


class TooLarge(InputError):
    """A request, file or archive beyond the configured size limits (HTTP 413)."""


def check_name(name: str, what: str = "module set name") -> str:
    if not isinstance(name, str) or not NAME_RE.match(name) or name in (".", ".."):
        raise InputError(f"invalid {what} {name!r}: use letters, digits, '_', '.', '-' (at most 100 characters, "
                         f"not starting with '.' or '-')")
    return name


def dangerous_name(name: str) -> Optional[str]:
    """Why a file name inside an upload is unsafe (NUL, absolute, escaping its folder, ...), None if it is not."""
    if "\x00" in name:
        return "contains a NUL character"
    n = name.replace("\\", "/")
    if n.startswith("/") or re.match(r"^[A-Za-z]:", n):
        return "is an absolute path"
    if any(seg == ".." for seg in n.split("/")):
        return "contains '..' (it would be written outside its folder)"
    return None


def safe_relpath(name: str) -> Optional[str]:
    """``name`` normalized to ``a/b/c.stl`` if every segment is safe, else None (never raises)."""
    if not isinstance(name, str) or dangerous_name(name):
        return None
    segs = [s for s in name.replace("\\", "/").split("/") if s not in ("", ".")]
    if not segs or not all(SAFE_SEGMENT.match(s) for s in segs):
        return None
    return "/".join(segs)


def mesh_refs(obj, path: Tuple[PathPart, ...] = ()) -> Iterator[Tuple[List[PathPart], object]]:
    """Every ``{"type": "mesh", "parameters": {"file": ...}}`` in a JSON document, with its JSON path."""
    if isinstance(obj, dict):
        params = obj.get("parameters")
        if obj.get("type") == "mesh" and isinstance(params, dict) and "file" in params:
            yield list(path) + ["parameters", "file"], params["file"]
        for k, v in obj.items():
            yield from mesh_refs(v, path + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from mesh_refs(v, path + (i,))


def check_mesh_refs(data, root: Path, fname: str) -> Dict[str, List[PathPart]]:
    """Resolve every mesh reference inside ``root`` (lexically and following symlinks) → {relpath: JSON path}."""
    out: Dict[str, List[PathPart]] = {}
    root_abs = Path(os.path.abspath(root))
    for jpath, ref in mesh_refs(data):
        lexical = resolve_inside(root, ref, fname, jpath)
        resolve_inside(root, ref, fname, jpath, follow_symlinks=True)
        rel = lexical.relative_to(root_abs).as_posix()
        safe = safe_relpath(rel)
        if safe is None:
            raise InputError(f"unsafe file name {ref!r}: path segments may only use letters, digits, "
                             f"'_', '-', '.', '+', '(', ')' and spaces, and may not start with '.'",
                             file=fname, path=jpath)
        if not safe.lower().endswith(MESH_EXTENSIONS):
            raise InputError(f"mesh file {ref!r} has an unsupported extension (allowed: "
                             f"{', '.join(MESH_EXTENSIONS)})", file=fname, path=jpath)
        out.setdefault(safe, jpath)
    return out


class FileSource:
    """Where the files of an upload come from: ``get(relpath) -> bytes | None``."""

    def get(self, rel: str) -> Optional[bytes]:
        raise NotImplementedError


class DictSource(FileSource):
    def __init__(self, files: Dict[str, bytes], prefix: str = ""):
        self.files, self.prefix = files, prefix

    def get(self, rel):
        return self.files.get(self.prefix + rel)


class FolderSource(FileSource):
    """Files of a local folder (seeding). Symlinks are followed only while they stay inside ``root``."""

    def __init__(self, root: Path, max_file_bytes: int):
        self.root, self.max = Path(root), max_file_bytes

    def get(self, rel):
        p = resolve_inside(self.root, rel, str(self.root), [], follow_symlinks=True)  # raises if a link leaves
        if not p.is_file():
            return None
        if p.stat().st_size > self.max:
            raise TooLarge(f"file {rel!r} is larger than {self.max} bytes", file=str(self.root))
        return p.read_bytes()


class ZipSource(FileSource):
    """A zip archive read in memory with every entry name checked before anything is extracted."""

    def __init__(self, data: bytes, display: str, max_total: int, max_entries: int = 5000):
        self.display, self.max_total = display, max_total
        try:
            self.zf = zipfile.ZipFile(io.BytesIO(data))
            infos = self.zf.infolist()
        except (zipfile.BadZipFile, zipfile.LargeZipFile, ValueError, EOFError) as e:
            raise InputError(f"not a readable zip archive ({e})", file=display) from None
        if len(infos) > max_entries:
            raise TooLarge(f"the archive has {len(infos)} entries (at most {max_entries})", file=display)
        self.members: Dict[str, zipfile.ZipInfo] = {}
        declared = 0
        for info in infos:
            bad = dangerous_name(info.filename)
            if bad:
                raise InputError(f"zip entry {info.filename!r} {bad}; the archive is rejected", file=display)
            mode = info.external_attr >> 16
            if stat.S_ISLNK(mode):
                raise InputError(f"zip entry {info.filename!r} is a symbolic link; the archive is rejected",
                                 file=display)
            if info.flag_bits & 0x1:
                raise InputError(f"zip entry {info.filename!r} is encrypted", file=display)
            if info.is_dir():
                continue
            declared += info.file_size
            if declared > max_total:
                raise TooLarge(f"the archive inflates to more than {max_total} bytes", file=display)
            rel = safe_relpath(info.filename)
            if rel is None:
                continue  # odd but harmless name (e.g. .DS_Store): never extracted
            if rel in self.members:
                raise InputError(f"zip entry {info.filename!r} appears twice", file=display)
            self.members[rel] = info
        self._inflated = 0

    def names(self) -> List[str]:
        return sorted(self.members)

    def get(self, rel):
        info = self.members.get(rel)
        if info is None:
            return None
        buf = bytearray()
        try:
            with self.zf.open(info) as f:
                while True:
                    chunk = f.read(1 << 16)
                    if not chunk:
                        break
                    buf += chunk
                    self._inflated += len(chunk)
                    if len(buf) > info.file_size or self._inflated > self.max_total:
                        raise TooLarge(f"zip entry {rel!r} inflates beyond its declared size or the archive "
                                       f"limit ({self.max_total} bytes)", file=self.display)
        except (zipfile.BadZipFile, EOFError, OSError, NotImplementedError, RuntimeError) as e:
            raise InputError(f"cannot read zip entry {rel!r} ({e})", file=self.display) from None
        return bytes(buf)


def write_new_file(root: Path, rel: str, data: bytes) -> Path:
    """Create ``root/rel`` (new file, no symlink anywhere below ``root``)."""
    safe = safe_relpath(rel)
    if safe is None:
        raise InputError(f"unsafe file name {rel!r}")
    root_res = Path(root).resolve()
    target = root_res.joinpath(*PurePosixPath(safe).parts)
    target.parent.mkdir(parents=True, exist_ok=True)
    parent = target.parent.resolve()
    if parent != root_res and root_res not in parent.parents:
        raise InputError(f"file name {rel!r} leaves its folder")
    fd = os.open(target, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o644)
    with os.fdopen(fd, "wb") as f:
        f.write(data)
    return target


def assert_no_symlinks(root: Path) -> None:
    for dirpath, dirnames, filenames in os.walk(root):
        for n in dirnames + filenames:
            if os.path.islink(os.path.join(dirpath, n)):
                raise InputError(f"unexpected symbolic link {n!r} in a stored folder")


def task_id_segments(task_id: str, fname: str) -> Sequence[str]:
    """A task ID ``a/b/c`` as safe path segments (CoBRA: segments of letters, digits, '_', '.', '-')."""
    segs = task_id.split("/") if isinstance(task_id, str) else []
    if not segs or any(not s or s in (".", "..") or not re.match(r"^[A-Za-z0-9_.\-]{1,100}$", s) for s in segs) \
            or len(task_id) > 200:
        raise InputError(f"invalid task ID {task_id!r}: segments of letters, digits, '_', '.', '-' separated by '/'",
                         file=fname, path=["header", "ID"])
    return segs
