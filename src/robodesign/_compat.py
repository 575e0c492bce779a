"""Old module names keep importing: ``robodesign.checker`` is ``robodesign.judge.checker`` and so on.

robodesign ≤ 0.1 kept its modules side by side in one package; they now live in packages by layer
(docs/architecture.md). User code, pickles and stored results that name an old module get the new one (the
same module object) with a ``DeprecationWarning``.
"""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

MOVED = {
    "errors": "core.errors", "paths": "core.paths", "defaults": "core.defaults", "jsonio": "core.jsonio",
    "schema": "core.schema", "input_warnings": "core.input_warnings", "spatial": "core.spatial",
    "geometry": "formats.geometry", "tolerance": "formats.tolerance", "module_spec": "formats.module_spec",
    "task_spec": "formats.task_spec", "solution": "formats.solution", "costs": "formats.costs",
    "benchmark_id": "formats.benchmark_id", "module_io": "formats.module_io", "task_io": "formats.task_io",
    "urdf": "formats.urdf", "assembly": "formats.assembly",
    "robot": "model.robot", "sweep": "model.sweep", "pair_sweep": "model.pair_sweep", "cell": "model.cell",
    "quantities": "judge.quantities", "checker": "judge.checker",
    "problem": "design.problem", "search_space": "design.search_space", "evaluator": "design.evaluator",
    "solve": "design.solve", "optimize": "design.optimize",
    "collab_optimize": "collab.optimize", "cli_args": "cli.args", "commands": "cli.commands",
    "collab_commands": "cli.collab", "experiment.cli": "cli.run", "generate.cli": "cli.generate",
    "viewer.cli": "cli.view",
}


class _Alias(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds ``robodesign.<old>`` and loads it as the module ``robodesign.<new>``."""

    def find_spec(self, fullname, path=None, target=None):
        if not fullname.startswith("robodesign."):
            return None
        new = MOVED.get(fullname[len("robodesign."):])
        if new is None:
            return None
        return importlib.util.spec_from_loader(fullname, self)

    def create_module(self, spec):
        new = "robodesign." + MOVED[spec.name[len("robodesign."):]]
        warnings.warn(f"{spec.name} is now {new}", DeprecationWarning, stacklevel=3)
        return importlib.import_module(new)

    def exec_module(self, module):  # the real module is already executed
        pass


def install() -> None:
    if not any(isinstance(f, _Alias) for f in sys.meta_path):
        sys.meta_path.append(_Alias())
