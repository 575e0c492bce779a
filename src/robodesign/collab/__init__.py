"""Collaborative tasks: several robots in one cell (docs/collaborative.md)."""


def __getattr__(name: str):  # ``from robodesign.collab import check_collab`` (the names of collab.core)
    import robodesign.collab.core as core
    try:
        return getattr(core, name)
    except AttributeError:
        raise AttributeError(f"module 'robodesign.collab' has no attribute {name!r}") from None
