"""robodesign: find the best modular robot for a task (CoBRA-compatible).

Public API (stable):
    load_module_set, ModuleSet, Assembly, Robot, InputError

The package is laid out by layer (docs/architecture.md): core → formats → model → judge → solvers → design →
collab, generate → experiment → viewer, web → cli. Optimizer plugins import :mod:`robodesign.plugin`.
"""
from robodesign import _compat
from robodesign.core.errors import AssemblyError, InputError, RobodesignError
from robodesign.formats.assembly import Assembly
from robodesign.formats.module_io import load_module_set
from robodesign.formats.module_spec import ModuleSet
from robodesign.model.robot import Robot

_compat.install()

__version__ = "0.1.0"
__all__ = ["Assembly", "AssemblyError", "InputError", "RobodesignError", "load_module_set", "ModuleSet", "Robot",
           "__version__"]
