"""Experiments: a YAML config → runs (task × optimizer × seed) → a results folder you can trust.

* :mod:`.config`   – the config schema (pydantic), loading with errors that name file and field, and
  resolution of tasks, module sets, costs and optimizers.
* :mod:`.storage`  – the SQLite results database (one commit per evaluation, WAL) and the per-run
  storage the :class:`robodesign.design.optimize.Study` replays to resume exactly.
* :mod:`.executors` – serial, local processes and Ray (fault tolerant) evaluation of candidates.
* :mod:`.runner`   – runs an experiment (new or resumed), writes config snapshot, meta, best solutions.
* :mod:`.report`   – anytime curves (CSV + PNG), summary tables and ``index.html``.

See docs/experiments.md and docs/ray.md.
"""
_LAZY = {"ExperimentConfig": "config", "ResolvedExperiment": "config", "load_config": "config",
         "resolve_config": "config", "load_experiment": "config", "run_experiment": "runner",
         "ExperimentOutcome": "runner", "write_report": "report"}
__all__ = list(_LAZY)


def __getattr__(name):  # imported lazily: `robodesign --help` must not pay for pydantic, sqlite, matplotlib
    if name in _LAZY:
        import importlib
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(name)
