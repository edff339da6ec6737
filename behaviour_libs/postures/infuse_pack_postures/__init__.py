"""The postures behaviour pack: data and a manifest (see pack/manifest.toml); no code but its registration."""
