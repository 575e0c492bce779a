"""The task-generator families and their options (a small registry, one module per family).

A family is a :class:`Family` (generate.family): a name, a version (bumped whenever the same arguments would write
different bytes), its options, and ``build(prov, folder) -> GeneratedTask``. ``generate()`` writes a
folder of tasks; ``regenerate()`` rebuilds one task from the provenance tags in its header.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Tuple

from robodesign.core.errors import InputError
from robodesign.core.jsonio import load_json
from robodesign.generate.bpo2024 import FAMILY as BPO2024
from robodesign.generate.common import Provenance
from robodesign.generate.family import VARIANT, VERIFY, Family, GeneratedTask, Option, copy_file
from robodesign.generate.liu2020 import FAMILY as LIU2020
from robodesign.generate.whitman2020 import FAMILY as WHITMAN2020

FAMILIES: Tuple[Family, ...] = (WHITMAN2020, LIU2020, BPO2024)  # the order of ``robodesign generate --list``


def families() -> Dict[str, Family]:
    """name → Family, in the order of ``robodesign generate --list``."""
    return {f.name: f for f in FAMILIES}


def get_family(name: str) -> Family:
    fams = families()
    if name not in fams:
        raise InputError(f"unknown generator family {name!r} (one of {', '.join(fams)}; "
                         f"see robodesign generate --list)")
    return fams[name]


def option_tags(family: Family, values: Dict[str, Any]) -> Tuple[Tuple[str, str], ...]:
    """Options as written into the header tags; a user-given file is recorded by its name in the folder."""
    out = []
    for o in family.options:
        v = values[o.name]
        if v is None:
            continue
        out.append((o.name, Path(str(v)).name if o.path else (repr(v) if isinstance(v, float) else str(v))))
    return tuple(sorted(out))


def build_one(family: Family, values: Dict[str, Any], seed: int, index: int, folder: Path) -> GeneratedTask:
    prov = Provenance(family.name, family.version, seed, index, option_tags(family, values))
    return family.build(prov, values, folder)


def write_task(gen: GeneratedTask, folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    out = folder / gen.filename
    out.write_text(gen.text, encoding="utf-8")
    return out


def generate(family_name: str, out: Path, count: int, seed: int, options: Optional[Dict[str, Any]] = None,
             progress: Optional[Callable[[Path], None]] = None) -> List[Path]:
    """Write ``count`` tasks of a family into folder ``out`` (task index 0..count-1); returns the files."""
    family = get_family(family_name)
    if count < 1:
        raise InputError(f"--count must be at least 1, got {count}")
    if seed < 0:
        raise InputError(f"--seed must be non-negative, got {seed}")
    values = family.resolve(dict(options or {}))
    out = Path(out)
    files = []
    for index in range(count):
        p = write_task(build_one(family, values, seed, index, out), out)
        files.append(p)
        if progress:
            progress(p)
    return files


def regenerate(task_file: Path, out: Path) -> Path:
    """Rebuild one generated task from its header's provenance tags into folder ``out``.

    A family that reads a user file (liu2020 ``--machine``) takes the copy the generator made in ``assets/``
    beside the task."""
    task_file = Path(task_file)
    data = load_json(task_file, display_name=task_file.name)
    head = data.get("header") if isinstance(data, dict) else None
    tags = head.get("tags") if isinstance(head, dict) else None
    prov = Provenance.from_tags(tags if isinstance(tags, list) else [], task_file.name)
    family = get_family(prov.family)
    if prov.version != family.version:
        raise InputError(f"written by {prov.family} generator version {prov.version}, this is version "
                         f"{family.version}: it cannot be reproduced bit for bit", file=task_file.name,
                         path=["header", "tags"])
    given: Dict[str, Any] = dict(prov.options)
    for o in family.options:
        if o.path and o.name in given:
            given[o.name] = str(_find_asset(task_file, str(given[o.name])))
    try:
        values = family.resolve(given)
    except InputError as e:
        raise InputError(str(e), file=task_file.name, path=["header", "tags"]) from None
    return write_task(build_one(family, values, prov.seed, prov.index, Path(out)), Path(out))


def _find_asset(task_file: Path, name: str) -> Path:
    if not name or name != Path(name).name or name in (".", ".."):
        raise InputError(f"the file named in the provenance tags, {name!r}, must be a plain file name",
                         file=task_file.name, path=["header", "tags"])
    for cand in (task_file.parent / "assets" / name, task_file.parent / name):
        if cand.is_file():
            return cand
    raise InputError(f"the task was generated from the file {name!r}, which is not in assets/ beside it",
                     file=task_file.name, path=["header", "tags"])


__all__ = ["Family", "GeneratedTask", "Option", "VARIANT", "VERIFY", "families", "get_family", "generate", "regenerate",
           "copy_file", "build_one", "write_task"]
