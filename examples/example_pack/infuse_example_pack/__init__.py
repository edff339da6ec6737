"""Example behaviour pack for infuse: data and a manifest (``pack/``), and the plugin that registers it."""
