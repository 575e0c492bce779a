"""First-party robodesign optimizer plugins. Each module uses only ``robodesign.plugin`` and
``robodesign.design.search_space`` (the public plugin API)."""
