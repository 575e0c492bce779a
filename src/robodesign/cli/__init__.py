"""The command line: ``robodesign COMMAND`` (one module per command group; ``main`` parses and dispatches)."""
from robodesign.cli.entry import main

__all__ = ["main"]


def __getattr__(name: str):  # the names of robodesign ≤ 0.1's cli module (build_parser, cmd_check, ...)
    import robodesign.cli.entry as entry
    try:
        return getattr(entry, name)
    except AttributeError:
        raise AttributeError(f"module 'robodesign.cli' has no attribute {name!r}") from None
