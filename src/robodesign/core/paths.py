"""Where robodesign finds its own data: JSON schemas and built-in assets (module sets, tasks)."""
from __future__ import annotations

import os
from pathlib import Path

_PKG = Path(__file__).resolve().parent.parent  # the robodesign package (this file is in core/)


def project_root() -> Path:
    """The checkout (or the folder named by ROBODESIGN_HOME) that holds schemas/ and assets/."""
    env = os.environ.get("ROBODESIGN_HOME")
    if env:
        return Path(env).resolve()
    for cand in (_PKG.parent.parent, _PKG / "_data"):
        if (cand / "schemas").is_dir():
            return cand
    return _PKG.parent.parent


def schemas_dir() -> Path:
    return project_root() / "schemas"


def assets_dir() -> Path:
    return project_root() / "assets"


def builtin_module_sets() -> dict:
    """name → folder of every built-in module set (``assets/modules/<name>/modules.json``)."""
    d = assets_dir() / "modules"
    if not d.is_dir():
        return {}
    return {p.name: p for p in sorted(d.iterdir()) if (p / "modules.json").is_file()}


def builtin_tasks_dir() -> Path:
    return assets_dir() / "tasks"


DEFAULT_MODULE_SET = "robodesign_arm"
