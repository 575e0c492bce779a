"""First-party robodesign optimizer plugins. Each module uses only ``robodesign.optimize`` and
``robodesign.search_space`` (the public plugin API)."""
