"""Seeded generators of CoBRA task families (``robodesign generate``; docs/generators.md).

    from robodesign.generate import generate, families
    files = generate("whitman2020", "tasks/w33", count=50, seed=0, options={"goals": 3, "obstacles": 3})
"""
from robodesign.generate.registry import Family, GeneratedTask, Option, families, generate, get_family, regenerate

__all__ = ["Family", "GeneratedTask", "Option", "families", "generate", "get_family", "regenerate"]
