"""Parsing of CLI argument values (joint vectors, poses, module orders) with clear errors."""
from __future__ import annotations

import math
from typing import List

import numpy as np

from .errors import InputError
from .spatial import homogeneous, rpy_to_matrix


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
