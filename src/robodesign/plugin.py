"""The public API of optimizer plugins: everything a plugin imports (docs/plugins.md).

A plugin subclasses :class:`Optimizer`, declares its options with :func:`option`, proposes
:class:`Candidate` objects and reads :class:`Evaluation` results; it sees the :class:`Problem` and its
:class:`SearchSpace`. Plugins import from here only, so the library's inner layout may change under them.
"""
from robodesign.core.errors import AssemblyError
from robodesign.design.optimize import (
    BASE_PARAMS,
    STAGES,
    Budget,
    Candidate,
    Evaluation,
    Optimizer,
    OptionError,
    Problem,
    SearchSpace,
    SerialExecutor,
    Study,
    StudyResult,
    available_optimizers,
    create_optimizer,
    load_optimizer,
    optimize,
    option,
    option_specs,
    parse_options,
)

__all__ = ["Optimizer", "option", "OptionError", "Problem", "SearchSpace", "Candidate", "Evaluation", "STAGES",
           "BASE_PARAMS", "create_optimizer", "load_optimizer", "available_optimizers", "option_specs",
           "parse_options", "optimize", "Budget", "Study", "StudyResult", "SerialExecutor", "AssemblyError"]
