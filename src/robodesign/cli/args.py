"""Parsing of CLI argument values (joint vectors, poses, module orders) with clear errors."""
from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Dict, List

import numpy as np

from robodesign.core.errors import InputError
from robodesign.core.spatial import homogeneous, rpy_to_matrix


def parse_floats(text: str, what: str) -> List[float]:
    out = []
    for k, tok in enumerate(t for t in text.replace(";", ",").split(",") if t.strip() != ""):
        try:
            v = float(tok)
        except ValueError:
            raise InputError(f"{what}: entry {k} is not a number: {tok.strip()!r}") from None
        if not math.isfinite(v):
            raise InputError(f"{what}: entry {k} is not finite: {tok.strip()!r}")
        out.append(v)
    return out


def parse_order(text: str) -> List[str]:
    order = [t.strip() for t in text.split(",") if t.strip()]
    if not order:
        raise InputError("--order: give module IDs separated by commas, e.g. 1,21,4,22,5,23,12")
    return order


def parse_base_pose(text: str) -> np.ndarray:
    """``x,y,z``, ``x,y,z,roll,pitch,yaw`` (rad, XYZ-fixed) or 16 numbers (row-major 4x4)."""
    v = parse_floats(text, "--base-pose")
    if len(v) == 3:
        return homogeneous(None, v)
    if len(v) == 6:
        return homogeneous(rpy_to_matrix(*v[3:]), v[:3])
    if len(v) == 16:
        T = np.array(v).reshape(4, 4)
        R = T[:3, :3]
        if np.abs(R @ R.T - np.eye(3)).max() > 1e-6 or np.abs(T[3] - [0, 0, 0, 1]).max() > 1e-9:
            raise InputError("--base-pose: the 4x4 matrix is not a rigid transform")
        return T
    raise InputError(f"--base-pose: expected 3 (x,y,z), 6 (x,y,z,roll,pitch,yaw) or 16 numbers, got {len(v)}")


def module_set_for_solution(solution, modules=None):
    """The module set for checking or showing ``solution``: ``--modules`` if given, else the solution's
    ``moduleSet`` when it is found locally (a folder or a built-in name); otherwise an error that says to
    pass --modules."""
    from robodesign.core.paths import builtin_module_sets
    from robodesign.formats.module_io import load_module_set, resolve_module_set_path
    name = modules or solution.module_set
    where = solution.source or "solution"
    if not name:
        raise InputError("the solution names no moduleSet; pass --modules DIR (a folder with modules.json or "
                         "a built-in name)", file=where, path="moduleSet")
    if not modules:
        try:
            if not str(name).lower().endswith(".urdf"):
                resolve_module_set_path(name)
            elif not Path(name).is_file():
                raise InputError("no such URDF file")
        except InputError:
            known = ", ".join(builtin_module_sets()) or "none"
            raise InputError(f"module set {name!r} is not found locally (built-in: {known}); pass --modules DIR "
                             "(the folder holding its modules.json)", file=where, path="moduleSet") from None
    return load_module_set(name)


def print_input_warnings(*loaded) -> None:
    """Show once, on stderr, what was tolerated while reading tasks / module sets (their ``warnings``)."""
    import sys
    for obj in loaded:
        for w in getattr(obj, "warnings", ()) or ():
            print(f"robodesign: warning: {w}", file=sys.stderr)


def parse_options(items: List[str]) -> Dict[str, object]:
    """``key=value`` pairs; values parsed as JSON when possible (numbers, booleans, lists)."""
    out: Dict[str, object] = {}
    for it in items or []:
        k, sep, v = it.partition("=")
        if not sep or not k:
            raise InputError(f"--opt {it!r}: expected key=value")
        try:
            out[k] = json.loads(v)
        except json.JSONDecodeError:
            out[k] = v
    return out
