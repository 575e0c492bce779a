"""robodesign: find the best modular robot for a task (CoBRA-compatible).

Public API (stable):
    load_module_set, ModuleSet, Assembly, Robot, InputError
"""
from .assembly import Assembly
from .errors import AssemblyError, InputError, RobodesignError
from .module_io import load_module_set
from .module_spec import ModuleSet
from .robot import Robot

__version__ = "0.1.0"
__all__ = ["Assembly", "AssemblyError", "InputError", "RobodesignError", "load_module_set", "ModuleSet", "Robot",
           "__version__"]
